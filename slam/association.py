"""Data association: individual Mahalanobis gating with nearest neighbour, and joint compatibility
branch and bound (JCBB, Neira & Tardos 2001) as an option. Vectorised over landmarks.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from .models import chi2_quantile

from .models import wrap


def predict_lines(pose: np.ndarray, lm: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vectorised :func:`slam.models.observe_line` and its Jacobians for (L, 2) world lines:
    (zhat (L,2), H_pose (L,2,3), H_landmark (L,2,2))."""
    X, Y, Phi = pose[:3]
    R, th = lm[:, 0], lm[:, 1]
    c, s = np.cos(th), np.sin(th)
    rho = R - (X * c + Y * s)
    sign = np.where(rho >= 0, 1.0, -1.0)
    alpha = wrap(th - Phi + np.where(rho >= 0, 0.0, np.pi))
    L = lm.shape[0]
    Hp = np.zeros((L, 2, 3))
    Hp[:, 0, 0], Hp[:, 0, 1], Hp[:, 1, 2] = -sign * c, -sign * s, -1.0
    Hl = np.zeros((L, 2, 2))
    Hl[:, 0, 0], Hl[:, 0, 1], Hl[:, 1, 1] = sign, sign * (X * s - Y * c), 1.0
    return np.column_stack((np.abs(rho), alpha)), Hp, Hl


def predict_corners(pose: np.ndarray, lm: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vectorised :func:`slam.models.observe_corner` and its Jacobians for (L, 2) world points."""
    X, Y, Phi = pose[:3]
    c, s = np.cos(Phi), np.sin(Phi)
    dx, dy = lm[:, 0] - X, lm[:, 1] - Y
    L = lm.shape[0]
    Hl = np.zeros((L, 2, 2))
    Hl[:] = np.array([[c, s], [-s, c]])
    Hp = np.zeros((L, 2, 3))
    Hp[:, 0, 0], Hp[:, 0, 1], Hp[:, 0, 2] = -c, -s, -s * dx + c * dy
    Hp[:, 1, 0], Hp[:, 1, 1], Hp[:, 1, 2] = s, -c, -c * dx - s * dy
    return np.column_stack((c * dx + s * dy, -s * dx + c * dy)), Hp, Hl


def innovation_covariances(P: np.ndarray, idx: np.ndarray, Hp: np.ndarray, Hl: np.ndarray) -> np.ndarray:
    """H P H^T (L, 2, 2) for landmarks at state indices ``idx`` (without the observation noise)."""
    Prr = P[:3, :3]
    cols = idx[:, None] + np.arange(2)[None, :]  # (L, 2)
    Prl = P[:3][:, cols].transpose(1, 0, 2)  # (L, 3, 2)
    Pll = P[cols[:, :, None], cols[:, None, :]]  # (L, 2, 2)
    A = Hp @ Prr @ Hp.transpose(0, 2, 1)
    B = Hp @ Prl @ Hl.transpose(0, 2, 1)
    C = Hl @ Pll @ Hl.transpose(0, 2, 1)
    return A + B + B.transpose(0, 2, 1) + C


def mahalanobis2(nu: np.ndarray, S: np.ndarray) -> np.ndarray:
    """nu^T S^-1 nu for stacks of 2-vectors (..., 2) and 2x2 matrices (..., 2, 2)."""
    a, b, c, d = S[..., 0, 0], S[..., 0, 1], S[..., 1, 0], S[..., 1, 1]
    det = a * d - b * c
    x, y = nu[..., 0], nu[..., 1]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # a det of 1e-300: inf, as a 0 one
        m = (d * x * x - (b + c) * x * y + a * y * y) / det
    return np.where(det > 0, m, np.inf)


@dataclass
class Candidates:
    """Individual compatibility of m observations with L landmarks of one kind."""

    nu: np.ndarray  # (m, L, 2) innovations
    S: np.ndarray  # (m, L, 2, 2) innovation covariances
    d2: np.ndarray  # (m, L) squared Mahalanobis distances


def candidates(z: np.ndarray, Rz: np.ndarray, zhat: np.ndarray, HPH: np.ndarray, angle_col: int | None) -> Candidates:
    """Innovations of observations z (m,2) with covariances Rz (m,2,2) against predictions zhat (L,2)."""
    nu = z[:, None, :] - zhat[None, :, :]
    if angle_col is not None:
        nu[..., angle_col] = wrap(nu[..., angle_col])
    S = HPH[None, :, :, :] + Rz[:, None, :, :]
    return Candidates(nu, S, mahalanobis2(nu, S))


def nearest_neighbour(d2: np.ndarray, gate: float, reject_ambiguous: bool = False,
                      ambiguity_d2: np.ndarray | None = None) -> list[tuple[int, int]]:
    """Greedy one-to-one pairs (observation, landmark) by increasing distance, within the gate.
    With ``reject_ambiguous``, an observation that falls in the gate of two or more landmarks
    (counted in ``ambiguity_d2`` when given, e.g. before other masks) is left unpaired (a door
    jamb next to another along an unobservable corridor)."""
    d2 = np.array(d2, dtype=float)
    if reject_ambiguous and d2.size:
        ref = d2 if ambiguity_d2 is None else ambiguity_d2
        d2[np.sum(ref < gate, axis=1) > 1] = np.inf
    obs, lms = np.nonzero(d2 < gate)
    order = np.argsort(d2[obs, lms], kind="stable")
    used_o, used_l, pairs = set(), set(), []
    for k in order:
        o, l = int(obs[k]), int(lms[k])
        if o not in used_o and l not in used_l:
            used_o.add(o)
            used_l.add(l)
            pairs.append((o, l))
    return sorted(pairs)


def joint_nis(pairs: list[tuple[int, int]], nu_fn, S_fn) -> float:
    """Joint squared Mahalanobis distance of a set of pairings (stacked innovation)."""
    if not pairs:
        return 0.0
    nu = np.concatenate([nu_fn(o, l) for o, l in pairs])
    S = S_fn(pairs)
    try:
        return float(nu @ np.linalg.solve(S, nu))
    except np.linalg.LinAlgError:
        return np.inf


def jcbb(d2: np.ndarray, gate: float, nu_fn, S_fn, confidence: float = 0.99, max_nodes: int = 5000) -> list[tuple[int, int]]:
    """Joint compatibility branch and bound: the largest set of jointly compatible pairings
    (ties broken by the smaller joint NIS). ``nu_fn(o, l)`` gives the (2,) innovation,
    ``S_fn(pairs)`` the (2k, 2k) joint innovation covariance. Falls back to the best found
    after ``max_nodes`` nodes."""
    m = d2.shape[0]
    options = [list(np.nonzero(d2[o] < gate)[0][np.argsort(d2[o][d2[o] < gate])]) for o in range(m)]
    thresholds = [0.0] + [chi2_quantile(confidence, 2 * k) for k in range(1, m + 1)]
    best: list = [[], np.inf]
    nodes = [0]

    def recurse(o: int, pairs: list[tuple[int, int]], used: set, nis: float) -> None:
        nodes[0] += 1
        if o == m or nodes[0] > max_nodes:
            if len(pairs) > len(best[0]) or (len(pairs) == len(best[0]) and nis < best[1]):
                best[0], best[1] = list(pairs), nis
            return
        for l in options[o]:
            if l in used:
                continue
            trial = pairs + [(o, int(l))]
            nis_t = joint_nis(trial, nu_fn, S_fn)
            if nis_t < thresholds[len(trial)]:
                used.add(int(l))
                recurse(o + 1, trial, used, nis_t)
                used.discard(int(l))
        # the branch without a pairing for o, only if it can still beat the best
        remaining = sum(1 for k in range(o + 1, m) if options[k])
        if len(pairs) + remaining >= len(best[0]):
            recurse(o + 1, pairs, used, nis)

    recurse(0, [], set(), 0.0)
    return sorted(best[0])
