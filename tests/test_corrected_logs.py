"""Radish ``*-corrected`` CARMEN logs (Intel Research Lab, ACES): the laser lines' pose fields are a
SLAM solution, and an ODOM line at exactly that pose after each laser line restarts the raw
odometry there. Before, the corrected poses were read as the odometry (`info`: odometry yes; the
SLAM table's "raw odometry" row was the reference itself, and the run had nothing to be scored
against); now ``Record.odom`` is the raw odometry the ODOM lines give, chained from scan to scan,
and ``Record.corrected`` the pose fields (lms200.carmen_odom.CorrectedChain)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from lms200 import read_log

ROOM = (-5.0, 5.0, -4.0, 4.0)  # x min, x max, y min, y max of a rectangular room, m
BEAMS = 181


def _matrix(pose) -> np.ndarray:
    x, y, th = pose
    return np.array([[math.cos(th), -math.sin(th), x], [math.sin(th), math.cos(th), y], [0.0, 0.0, 1.0]])


def _pose(m: np.ndarray) -> tuple[float, float, float]:
    return float(m[0, 2]), float(m[1, 2]), math.atan2(m[1, 0], m[0, 0])


def _ranges(pose) -> np.ndarray:
    """Exact ranges (m) from ``pose`` to the room's walls, 181 beams over -90..90 deg."""
    x, y, th = pose
    a = th + np.deg2rad(np.arange(BEAMS) - 90.0)
    c, s = np.cos(a), np.sin(a)
    with np.errstate(divide="ignore"):
        tx = np.where(c > 0, (ROOM[1] - x) / c, np.where(c < 0, (ROOM[0] - x) / c, np.inf))
        ty = np.where(s > 0, (ROOM[3] - y) / s, np.where(s < 0, (ROOM[2] - y) / s, np.inf))
    return np.minimum(tx, ty)


def _trajectories(n: int, seed: int = 3):
    """(corrected poses, raw odometry poses, odometry between them): a loop in the room; the raw
    odometry is dead reckoning of the true steps with a seeded per-step error."""
    rng = np.random.default_rng(seed)
    corrected = [(2.0 * math.cos(2 * math.pi * k / n), 1.5 * math.sin(2 * math.pi * k / n),
                  2 * math.pi * k / n + math.pi / 2) for k in range(n)]
    raw = [np.eye(3)]
    for k in range(1, n):
        step = np.linalg.inv(_matrix(corrected[k - 1])) @ _matrix(corrected[k])
        err = _matrix((rng.normal(0, 0.03), rng.normal(0, 0.01), rng.normal(0, 0.03)))
        raw.append(raw[-1] @ step @ err)
    return corrected, raw


def _write_corrected_log(path: Path, n: int, drop_anchor: int | None = None, anchors: bool = True,
                         anchor_stamped: bool = False) -> tuple:
    """A corrected log as Radish writes them: FLASER at the corrected pose, its ODOM anchor (a junk
    stamp), then three ODOM lines of raw odometry from that anchor, the last at the next scan."""
    corrected, raw = _trajectories(n)
    lines = ["# a Radish-style corrected log", "PARAM robot_frontlaser_offset 0.0 host 0"]
    for k in range(n):
        t = 10.0 + 2.5 * k
        x, y, th = corrected[k]
        ranges = " ".join(f"{r:.3f}" for r in _ranges(corrected[k]))
        lines.append(f"FLASER {BEAMS} {ranges} {x:.6f} {y:.6f} {th:.6f} {x:.6f} {y:.6f} {th:.6f} {t:.4f} host {t:.4f}")
        if anchors and k != drop_anchor:
            stamp = f"{t:.4f}" if anchor_stamped else "1.08499e-42"  # stamped with the scan: a real ODOM line
            lines.append(f"ODOM {x:.6f} {y:.6f} {th:.6f} 0 0 0 {stamp} host 0")
        if k + 1 < n:
            start = np.linalg.inv(raw[k])
            for j, f in enumerate((0.3, 0.7, 1.0)):  # raw odometry samples towards the next scan
                step = start @ raw[k + 1]
                part = _matrix((f * step[0, 2], f * step[1, 2], f * math.atan2(step[1, 0], step[0, 0])))
                ox, oy, oth = _pose(_matrix(corrected[k]) @ part)
                ts = t + 2.5 * f
                lines.append(f"ODOM {ox:.9f} {oy:.9f} {oth:.9f} 0.4 0 0 {ts:.4f} host {ts:.4f}")
    path.write_text("\n".join(lines) + "\n")
    return corrected, raw


def test_a_corrected_log_gives_its_raw_odometry_and_its_corrected_poses(tmp_path):
    corrected, raw = _trajectories(24)
    _write_corrected_log(tmp_path / "lab-corrected.log", 24)
    recs = list(read_log(tmp_path / "lab-corrected.log"))
    assert len(recs) == 24
    np.testing.assert_allclose([r.corrected for r in recs], np.round(corrected, 6), atol=1e-12)
    # the raw odometry, independently: dead reckoning in the frame where it starts at the first scan
    expected = [_pose(_matrix(corrected[0]) @ np.linalg.inv(raw[0]) @ raw[k]) for k in range(24)]
    got = np.array([r.odom for r in recs])
    np.testing.assert_allclose(got[:, :2], np.array(expected)[:, :2], atol=2e-5)  # the log's 6-9 digits
    np.testing.assert_allclose(np.angle(np.exp(1j * (got[:, 2] - np.array(expected)[:, 2]))), 0, atol=2e-5)
    drift = np.hypot(*(got[-1, :2] - np.array(corrected[-1][:2])))
    assert drift > 0.05  # the odometry is not the corrected pose (before: identical)


def test_an_anchor_missing_restarts_the_chain_and_a_plain_log_is_read_as_before(tmp_path):
    corrected, _ = _trajectories(12)
    _write_corrected_log(tmp_path / "one-missing.log", 12, drop_anchor=5)
    recs = list(read_log(tmp_path / "one-missing.log"))
    assert [r.corrected is not None for r in recs] == [k != 5 for k in range(12)]
    assert recs[5].odom == pytest.approx(np.round(corrected[5], 6))  # as read: its pose fields
    assert recs[6].odom == pytest.approx(np.round(corrected[6], 6))  # a new chain starts at its own pose
    for name, options in (("plain.log", {"anchors": False}), ("standing.log", {"anchor_stamped": True})):
        # CARMEN's usual log: ODOM lines are odometry, and one at a scan's pose, stamped with it, is a
        # robot standing still (0.5 s after the scan or less), not an anchor
        _write_corrected_log(tmp_path / name, 12, **options)
        recs = list(read_log(tmp_path / name))
        assert all(r.corrected is None for r in recs), name
        np.testing.assert_allclose([r.odom for r in recs], np.round(corrected, 6), atol=1e-12)


def test_slam_on_a_corrected_log_is_scored_against_its_corrected_poses(tmp_path, capsys):
    """`lmsbench slam` on a corrected log printed no score at all (no ground truth) and its "raw
    odometry" row was the corrected poses; now ATE / RPE against the corrected poses, so named,
    and the raw odometry's row is the ODOM lines' dead reckoning."""
    from experiments.cli import main
    from slam.metrics import ate

    corrected, raw = _trajectories(40)
    log = tmp_path / "lab-corrected.log"
    _write_corrected_log(log, 40)
    out = tmp_path / "run"
    assert main(["slam", str(log), "--out", str(out), "--quiet", "--no-paper-baseline", "--no-odometry-baseline"]) == 0
    printed = capsys.readouterr().out
    assert "ATE RMS against the log's corrected poses (m): this run" in printed
    m = json.loads((out / "metrics.json").read_text())
    assert m["reference"] == "corrected poses" and "not ground truth" in m["input"]["truth"]
    rows = {row["source"]: row for row in m["table"]}
    stamps = 10.0 + 2.5 * np.arange(40)
    odometry = np.array([_pose(_matrix(corrected[0]) @ np.linalg.inv(raw[0]) @ raw[k]) for k in range(40)])
    reference = np.column_stack((stamps, np.round(corrected, 6)))
    expected = ate(np.column_stack((stamps, odometry)), reference).rmse
    assert rows["raw odometry"]["ate_rmse"] == pytest.approx(expected, abs=1e-4)
    assert rows["raw odometry"]["ate_rmse"] > 0.02  # before: 0 (the reference itself)


@pytest.mark.shared_data
@pytest.mark.parametrize(("name", "count", "step_median"), [("intel-corrected.log.gz", 910, (0.03, 0.08)),
                                                             ("aces-corrected.log.gz", 440, (0.03, 0.08))])
def test_the_real_corrected_logs_give_raw_odometry(shared_data, name, count, step_median):
    """Every laser line of Intel and ACES has its anchor; one step of the odometry differs from the
    corrected step by a median 5 cm (the odometry's drift over a 0.7-1 m step), and the path
    lengths agree within 1 %."""
    recs = list(read_log(shared_data / name))
    assert len(recs) == count and all(r.corrected is not None for r in recs)
    odom, corr = np.array([r.odom for r in recs]), np.array([r.corrected for r in recs])
    assert tuple(odom[0]) == tuple(corr[0])
    errors = []
    for k in range(1, count):
        step_o = np.linalg.inv(_matrix(odom[k - 1])) @ _matrix(odom[k])
        step_c = np.linalg.inv(_matrix(corr[k - 1])) @ _matrix(corr[k])
        errors.append(np.hypot(step_o[0, 2] - step_c[0, 2], step_o[1, 2] - step_c[1, 2]))
    assert step_median[0] < np.median(errors) < step_median[1]
    length_o = np.hypot(*np.diff(odom[:, :2], axis=0).T).sum()
    length_c = np.hypot(*np.diff(corr[:, :2], axis=0).T).sum()
    assert abs(length_o / length_c - 1) < 0.01
