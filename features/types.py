"""Feature types shared by every extractor: a FeatureSet holds a scan's lines and corners as arrays
(``Lines``, ``Corners``); ``fs.lines[i]`` and ``fs.corners[i]`` are ``Line`` / ``Corner`` records
built from them on access.

All geometry is in the sensor frame of the scan (x ahead, y left, metres, radians CCW).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import math

import numpy as np

from lms200.codes import unmasked
from lms200.errors import InputError
from lms200.finite import is_number, shown, whole_number

LINE_COLUMNS = ("rho", "alpha", "x0", "y0", "x1", "y1", "cov_rr", "cov_ra", "cov_ar", "cov_aa")
CORNER_COLUMNS = ("x", "y", "angle")


@dataclass(frozen=True, eq=False)
class Line:
    """A line segment ``x cos(alpha) + y sin(alpha) = rho``.

    Attributes:
        rho: distance of the infinite line from the sensor origin (m, >= 0).
        alpha: normal angle of the line (rad, in (-pi, pi]).
        start: (x, y) endpoint at the first beam (m), the projection of that beam's point on the line.
        end: (x, y) endpoint at the last beam (m).
        first: index of the first beam assigned to the line (inclusive).
        last: index of the last beam assigned to the line (inclusive).
        cov: 2x2 covariance of (rho, alpha) in (m^2, m rad, rad^2); of a ``FeatureSet``'s line
            (``fs.lines[i]``), a read-only view of its arrays (writing through it changed the
            FeatureSet, silently): ``cov.copy()`` to change it.
        n_points: number of valid beams that support the line (at most ``last - first + 1``; 0:
            not known).

    Raises:
        InputError: built with a field outside these meanings (:func:`check_line`).
    """

    rho: float
    alpha: float
    start: tuple[float, float]
    end: tuple[float, float]
    first: int
    last: int
    cov: np.ndarray = field(default_factory=lambda: np.full((2, 2), np.nan))
    n_points: int = 0

    def __post_init__(self) -> None:
        check_line(self)

    @property
    def length(self) -> float:
        """Length of the segment between its endpoints (m)."""
        return float(np.hypot(self.end[0] - self.start[0], self.end[1] - self.start[1]))


@dataclass(frozen=True)
class Corner:
    """A corner where two extracted lines meet.

    Attributes:
        x, y: position in the sensor frame (m).
        angle: angle between the two lines (rad, in (0, pi)); pi/2 for a right-angle corner.
        index: beam index of the corner.
        lines: indices of the two lines in ``FeatureSet.lines`` (beam order).

    Raises:
        InputError: built with a field outside these meanings (:func:`check_corner`).
    """

    x: float
    y: float
    angle: float
    index: int
    lines: tuple[int, int]

    def __post_init__(self) -> None:
        check_corner(self)


ALPHA_SLACK = 1e-6  # rad: an alpha rounded past +-pi (atan2's -pi for y = -0.0; float32's pi, 8.7e-8 above) is the same normal
RHO_SLACK = 1e-9  # m: a line through the origin may carry rho -1e-12 after rounding
COV_SLACK = 1e-9  # relative: asymmetry and negative diagonal (of the largest entry), b b' beyond a d, left by rounding
COV_TINY = 1e-300  # absolute: b b' of an exactly singular covariance may round past a d where both underflow


def not_covariance(c: np.ndarray) -> np.ndarray:
    """(m,) mask of the (m, 2, 2) finite matrices ``[[a, b], [b', d]]`` that are no covariance:
    asymmetric (|b - b'| beyond ``COV_SLACK`` of the largest entry), a diagonal below ``-COV_SLACK``
    of it, or a correlation beyond 1 (b b' > a d (1 + COV_SLACK) + COV_TINY): positive semi-definite
    in closed form. The one check of ``Line.cov``, ``slam.Observations`` and ``slam.from_features``
    (there were three, with tolerances relative to the largest entry that took [[1, 3e-5], [3e-5,
    1e-12]], a correlation of 30)."""
    a, b, b2, d = c[:, 0, 0], c[:, 0, 1], c[:, 1, 0], c[:, 1, 1]
    tol = COV_SLACK * np.abs(c).reshape(-1, 4).max(axis=1, initial=0.0)
    return ((np.abs(b - b2) > tol) | (a < -tol) | (d < -tol)
            | (b * b2 > np.maximum(a, 0.0) * np.maximum(d, 0.0) * (1.0 + COV_SLACK) + COV_TINY))


def _real(v: object) -> float | None:
    """``v`` as a finite float (any real number, :func:`lms200.finite.is_number`: an int, float,
    numpy number or ``fractions.Fraction``, and a numeric 0-d array; no bool, no text), else None.
    A review found Fraction and 0-d arrays refused, which worked before the checks."""
    if isinstance(v, np.ndarray) and v.ndim == 0 and v.dtype.kind in "iuf":
        v = v[()]
    if not is_number(v):
        return None
    try:
        f = float(v)  # type: ignore[arg-type]
    except (OverflowError, TypeError, ValueError):  # 10**400, Fraction(10**400)
        return None
    return f if math.isfinite(f) else None


def _point(v: object) -> tuple[float, float] | None:
    """``v`` as two finite numbers (a tuple, list or array of two), else None."""
    if isinstance(v, (str, bytes)) or not isinstance(v, (tuple, list, np.ndarray)) or len(v) != 2 \
            or (isinstance(v, np.ndarray) and v.ndim != 1):
        return None
    x, y = _real(v[0]), _real(v[1])
    return None if x is None or y is None else (x, y)


def _cov_problem(cov: object) -> str:
    """Why ``cov`` is no covariance of (rho, alpha) ("" when it is one): a 2x2 array of numbers,
    all nan (not known, the default) or finite, symmetric and positive semi-definite."""
    try:
        c = np.asarray(unmasked(cov), dtype=float)  # a masked item as nan (refused below), not its hidden data
    except (TypeError, ValueError, OverflowError):
        return "must be a 2x2 array of numbers"
    if c.shape != (2, 2):
        return f"must be a 2x2 array, not one of shape {c.shape}"
    if np.isnan(c).all():
        return ""
    if not np.isfinite(c).all():
        return "must be finite (or all nan: not known)"
    if not_covariance(c[None])[0]:
        if abs(c[0, 1] - c[1, 0]) > COV_SLACK * float(np.abs(c).max()):
            return "must be symmetric"
        return "must be positive semi-definite (a variance below 0, or a correlation beyond 1)"
    return ""


def check_line(line: Line) -> None:
    """InputError naming the field of ``line`` that is outside its documented meaning: rho a finite
    number >= 0 m, alpha a finite angle in (-pi, pi] rad, start and end two finite numbers each,
    first and last whole beam indices with 0 <= first <= last, n_points a whole number in
    [0, last - first + 1] (0: not known), cov a 2x2 covariance (all nan: not known). Found by
    fuzzing the Python API: a Line was checked only inside a FeatureSet, so a nan, negative or
    inverted one reached the scoring and the SLAM observations built by hand."""
    rho, alpha = _real(line.rho), _real(line.alpha)
    if rho is None or rho < -RHO_SLACK:
        raise InputError(f"Line.rho: must be a finite number >= 0 m (the line's distance from the origin), got {shown(line.rho)}")
    if alpha is None or abs(alpha) > math.pi + ALPHA_SLACK:
        raise InputError(f"Line.alpha: must be a finite angle in (-pi, pi] rad (the line's normal; wrap it), got {shown(line.alpha)}")
    for name in ("start", "end"):
        if _point(getattr(line, name)) is None:
            raise InputError(f"Line.{name}: must be two finite numbers (x, y m), got {shown(getattr(line, name))}")
    first, last, n = whole_number(line.first), whole_number(line.last), whole_number(line.n_points)
    if first is None or last is None or not 0 <= first <= last:
        raise InputError(f"Line.first, Line.last: must be whole beam indices with 0 <= first <= last, "
                         f"got {shown(line.first)}, {shown(line.last)}")
    if n is None or not 0 <= n <= last - first + 1:
        raise InputError(f"Line.n_points: must be a whole number in [0, {last - first + 1}] (the beams {first}..{last} "
                         f"that support the line; 0: not known), got {shown(line.n_points)}")
    problem = _cov_problem(line.cov)
    if problem:
        raise InputError(f"Line.cov: {problem} (the covariance of rho, alpha), got {shown(line.cov)}")


def check_corner(corner: Corner) -> None:
    """InputError naming the field of ``corner`` outside its documented meaning: x, y finite
    numbers (m), angle in (0, pi) rad, index a whole beam index >= 0, lines two different whole
    line indices >= 0 (a tuple, list or array). Found by fuzzing: a Corner was checked only inside
    a FeatureSet, and an angle of 0, 4 rad or nan or a corner of one line with itself was taken there."""
    for name in ("x", "y"):
        if _real(getattr(corner, name)) is None:
            raise InputError(f"Corner.{name}: must be a finite number (m), got {shown(getattr(corner, name))}")
    angle = _real(corner.angle)
    if angle is None or not 0 < angle < math.pi:
        raise InputError(f"Corner.angle: must be in (0, pi) rad (the angle between its two lines), got {shown(corner.angle)}")
    index = whole_number(corner.index)
    if index is None or index < 0:
        raise InputError(f"Corner.index: must be a whole beam index >= 0, got {shown(corner.index)}")
    try:
        pair = tuple(corner.lines) if not isinstance(corner.lines, (str, bytes)) else ()
    except TypeError:
        pair = ()
    whole = [whole_number(v) for v in pair]
    if len(whole) != 2 or None in whole or min(w for w in whole if w is not None) < 0 or whole[0] == whole[1]:
        raise InputError(f"Corner.lines: must be two different whole line indices >= 0, got {shown(corner.lines)}")


def row_index(i: Any, n: int, what: str) -> int | slice | np.ndarray:
    """The rows ``i`` selects of ``n`` (``what``: "lines" or "corners"): an int (negative from the
    end), or a slice, a 1-D integer array or list, or a boolean mask of length ``n``, which select
    a subset. IndexError for an int out of range (the Sequence protocol's), InputError naming the
    index for anything else: a list index was "list index out of range", a boolean mask numpy's
    "cannot reshape array of size 32 into shape (2,2)" (a library walkthrough filtered
    ``fs.lines[fs.lines.length > 0.5]``)."""
    if isinstance(i, slice):
        return i
    if isinstance(i, (int, np.integer)) and not isinstance(i, (bool, np.bool_)):
        k = int(i)
        if not -n <= k < n:
            raise IndexError(f"{what}: index {k} is out of range for {n} {what}")
        return k
    idx = np.asarray(i) if isinstance(i, (list, tuple, np.ndarray)) else None
    if idx is not None and idx.ndim == 1 and idx.dtype == bool and idx.size == n:
        return idx
    if idx is not None and idx.ndim == 1 and (idx.size == 0 or np.issubdtype(idx.dtype, np.integer)):
        idx = idx.astype(np.int64)
        bad = idx[(idx < -n) | (idx >= n)]
        if bad.size:
            raise IndexError(f"{what}: index {int(bad[0])} is out of range for {n} {what}")
        return idx
    raise InputError(f"{what}: an index must be an int, a slice, a 1-D array or list of ints, or a boolean mask of "
                     f"{n} values, got {type(i).__name__}" + (f" of shape {idx.shape} and dtype {idx.dtype}" if idx is not None else ""))


def check_line_rows(rows: np.ndarray, name: str) -> None:
    """InputError naming ``name`` and the first bad line of ``rows`` ((k, 8) float: rho, alpha,
    x0, y0, x1, y1, first, last, ``FeatureSet.line_array()``'s) unless every line has finite
    values, rho >= 0 m and beams 0 <= first <= last, whole numbers (any finite alpha names a
    normal; a line through the origin may carry either). Found by fuzzing the Python API: a
    hand-built Line with a nan, negative or inf rho or first > last scored a nan ray RMSE and
    explained fraction, silently."""
    if rows.shape[0] == 0:
        return
    rho, first, last = rows[:, 0], rows[:, 6], rows[:, 7]
    with np.errstate(invalid="ignore"):
        checks = (
            (~np.isfinite(rows).all(axis=1), "its values must be finite"),
            (rho < -RHO_SLACK, "rho must be >= 0 m"),  # a line through the origin: rounding may leave -1e-12
            ((first < 0) | (first > last) | (first != np.floor(first)) | (last != np.floor(last)),
             "its beams must be whole numbers with 0 <= first <= last"),
        )
    for bad, what in checks:
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            shown = ", ".join(f"{v:g}" for v in rows[i].tolist())
            raise InputError(f"{name}: line {i}: {what} (rho, alpha, x0, y0, x1, y1, first, last = {shown})")


def _storage(values: object, beams: object, name: str) -> tuple[np.ndarray, np.ndarray]:
    """``values`` (k, 10 or 3) float64 and ``beams`` (k, 3) int64 arrays of one row count, as
    ``Lines`` / ``Corners`` hold them; InputError naming ``name`` otherwise."""
    cols = 10 if name == "lines" else 3
    if not (isinstance(values, np.ndarray) and isinstance(beams, np.ndarray) and values.dtype == np.float64
            and np.issubdtype(beams.dtype, np.integer) and values.ndim == 2 and values.shape[1] == cols
            and beams.shape == (values.shape[0], 3)):
        raise InputError(f"{name}: its values must be a (k, {cols}) float64 array and its beams a (k, 3) integer array, "
                         f"got {getattr(values, 'shape', type(values).__name__)} and {getattr(beams, 'shape', type(beams).__name__)}")
    return values, beams


def check_lines(lines: Lines) -> None:
    """InputError naming the first bad row of ready ``Lines`` (a user's extractor builds them with
    ``Lines.from_arrays``, unchecked): the storage's shapes, :func:`check_line_rows`, n_points in
    [0, last - first + 1] and each covariance finite or all nan. Found by fuzzing: a FeatureSet of
    Lines with nan rho was taken whole, and scored a nan ray RMSE, silently."""
    values, beams = _storage(lines.values, lines.beams, "lines")
    check_line_rows(np.column_stack((values[:, :6], beams[:, :2])), "lines")
    n, span = beams[:, 2], beams[:, 1] - beams[:, 0] + 1
    cov = values[:, 6:10]
    for bad, what in (((n < 0) | (n > span), "n_points must be in [0, last - first + 1]"),
                      (~np.isfinite(cov).all(axis=1) & ~np.isnan(cov).all(axis=1), "its cov must be finite or all nan (not known)")):
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise InputError(f"lines: line {i}: {what} (first, last, n_points = {beams[i].tolist()}, cov = {cov[i].tolist()})")


def check_corners(corners: Corners) -> None:
    """InputError naming the first bad row of ready ``Corners``: the storage's shapes, x and y
    finite, angle in (0, pi) rad, beam and line indices >= 0 (as :func:`check_corner`)."""
    values, beams = _storage(corners.values, corners.beams, "corners")
    with np.errstate(invalid="ignore"):
        bad = ~np.isfinite(values).all(axis=1) | ~((values[:, 2] > 0) & (values[:, 2] < math.pi)) | (beams < 0).any(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise InputError(f"corners: corner {i}: x, y must be finite, angle in (0, pi) rad, its beam and lines >= 0 "
                         f"(x, y, angle = {values[i].tolist()}, beam, lines = {beams[i].tolist()})")


def check_feature_set(fs: FeatureSet) -> None:
    """InputError naming the first bad row of ``fs``'s lines or corners (:func:`check_lines`,
    :func:`check_corners`): what ``extract``, ``extract_many`` and ``compare`` run on the result of
    a method that is not built in, outside the timed span (in ``FeatureSet()`` it cost a user's
    extractor 50-70 us a scan of its timing)."""
    check_lines(fs.lines)
    check_corners(fs.corners)


def read_only(a: np.ndarray) -> np.ndarray:
    """A view of ``a`` that cannot be written through (``a`` itself stays writable): what the
    Line / Corner records and the column properties of Lines / Corners hand out, so that
    ``fs.lines[0].cov[0, 0] = 5`` or ``fs.lines.rho[0] = 7`` is numpy's "assignment destination is
    read-only" instead of a silent change of the FeatureSet (copy it to change it: ``cov.copy()``)."""
    v = a.view()
    v.flags.writeable = False
    return v


class Lines(Sequence):
    """The lines of one scan as arrays, in beam order; ``lines[i]`` is the ``Line`` of row i.

    Attributes:
        values: (L, 10) float64, columns ``LINE_COLUMNS``: rho (m), alpha (rad), start x0, y0 and
            end x1, y1 (m), covariance of (rho, alpha) row by row (m^2, m rad, m rad, rad^2).
        beams: (L, 3) int64: first beam, last beam (inclusive), number of supporting points.
    """

    __slots__ = ("values", "beams")

    def __init__(self, values: np.ndarray, beams: np.ndarray) -> None:
        self.values = values
        self.beams = beams

    @classmethod
    def empty(cls) -> Lines:
        return cls(np.empty((0, 10)), np.empty((0, 3), np.int64))

    @classmethod
    def from_arrays(cls, rho: np.ndarray, alpha: np.ndarray, start: np.ndarray, end: np.ndarray,
                    cov: np.ndarray, first: np.ndarray, last: np.ndarray, n_points: np.ndarray) -> Lines:
        """Lines from per-line arrays: rho, alpha (L,), start, end (L, 2), cov (L, 2, 2), first,
        last, n_points (L,). The arguments' lengths and beams are checked here, the values (a nan
        rho, first > last) where a method's result is taken (``extract`` / ``extract_many`` /
        ``compare``: :func:`check_lines`); the baselines build theirs with the unchecked ``Lines.of``.

        Raises:
            InputError: an argument of another length than rho's (a length-1 array broadcast to
                every line, silently), other shapes than these, not numbers (fuzzing: a broadcast
                ValueError), or beams (first, last, n_points) that are not whole numbers (2.7 was cut
                to 2, silently).
        """
        shapes = "rho, alpha (L,), start, end (L, 2), cov (L, 2, 2), first, last and n_points (L,)"
        # a masked array's masked items as nan (lms200.codes.unmasked): refused as beams here, as values by check_lines
        rho, alpha, start, end, cov, first, last, n_points = (
            unmasked(a) for a in (rho, alpha, start, end, cov, first, last, n_points))  # type: ignore[misc]
        args = (("alpha", alpha), ("start", start), ("end", end), ("cov", cov), ("first", first), ("last", last),
                ("n_points", n_points))
        try:
            n = len(rho)
            lengths = [(name, len(a)) for name, a in args]
        except TypeError:
            raise InputError(f"Lines.from_arrays: {shapes} must be arrays (or lists), one item a line") from None
        wrong = next(((name, k) for name, k in lengths if k != n), None)
        if wrong is not None:
            raise InputError(f"Lines.from_arrays: {wrong[0]} has {wrong[1]} item{'' if wrong[1] == 1 else 's'} for "
                             f"{n} line{'' if n == 1 else 's'} (rho's); {shapes}")
        if n == 0:
            return cls.empty()
        for name, a in args[4:]:
            b = a if isinstance(a, np.ndarray) else np.asarray(a)
            if b.dtype.kind == "f":
                with np.errstate(invalid="ignore"):
                    bad = ~(np.isfinite(b) & (b == np.floor(b)))
                if bad.any():
                    raise InputError(f"Lines.from_arrays: {name} must be whole numbers (beam indices, counts), "
                                     f"got {shown(b[bad].ravel()[0].item())} at line {int(np.flatnonzero(bad.reshape(n, -1).any(axis=1))[0])}")
        try:
            return cls.of(rho, alpha, start, end, cov, first, last, n_points)
        except (TypeError, ValueError, OverflowError) as exc:
            raise InputError(f"Lines.from_arrays: {shapes} must be numbers of these shapes, one a line "
                             f"({' '.join(str(exc).split())})") from None

    @classmethod
    def of(cls, rho: np.ndarray, alpha: np.ndarray, start: np.ndarray, end: np.ndarray,
           cov: np.ndarray, first: np.ndarray, last: np.ndarray, n_points: np.ndarray) -> Lines:
        """``from_arrays`` without its checks of the arguments (the baselines' fast path, as
        ``FeatureSet.of``: their arrays are of one length and whole beams by construction; the
        checks cost 12 us a scan): numpy's errors, and a length-1 array broadcast, as numpy does."""
        n = len(rho)
        values = np.empty((n, 10))
        values[:, 0], values[:, 1] = rho, alpha
        values[:, 2:4], values[:, 4:6] = start, end
        values[:, 6:10] = np.asarray(cov, dtype=float).reshape(n, 4)
        beams = np.empty((n, 3), np.int64)
        beams[:, 0], beams[:, 1], beams[:, 2] = first, last, n_points
        return cls(values, beams)

    @classmethod
    def from_lines(cls, lines: Sequence[Line]) -> Lines:
        """Lines from ``Line`` records.

        Raises:
            InputError: an item that is no Line, or a Line whose fields are not numbers of their
                shapes or fail :func:`check_line_rows` (fuzzing: text was numpy's ValueError, a
                start of three numbers a broadcast error, first = 10**30 an OverflowError).
        """
        if not lines:
            return cls.empty()
        for i, line in enumerate(lines):
            if not isinstance(line, Line):
                raise InputError(f"lines[{i}]: must be a features.Line, got {type(line).__name__}")
            for field_name in ("first", "last", "n_points"):  # the int64 beams array truncated 2.5 to 2
                v = getattr(line, field_name)
                if whole_number(v) is None:
                    raise InputError(f"lines[{i}].{field_name}: must be a whole number (a beam index or count), got {shown(v)}")
        try:
            out = cls.from_arrays(
                [l.rho for l in lines], [l.alpha for l in lines], [l.start for l in lines], [l.end for l in lines],
                np.array([np.asarray(unmasked(l.cov), dtype=float).reshape(2, 2) for l in lines]),
                [whole_number(l.first) for l in lines], [whole_number(l.last) for l in lines],
                [whole_number(l.n_points) for l in lines],
            )
        except (TypeError, ValueError, OverflowError) as exc:
            raise InputError(f"lines: each Line must hold numbers: rho, alpha, start and end (x, y), a 2x2 cov, "
                             f"whole first, last and n_points ({exc})") from None
        check_line_rows(np.column_stack((out.values[:, :6], out.beams[:, :2])), "lines")
        return out

    # the columns as read-only views (read_only): ``values`` and ``beams`` are the storage
    rho = property(lambda self: read_only(self.values[:, 0]), doc="(L,) distance of each line from the origin (m)")
    alpha = property(lambda self: read_only(self.values[:, 1]), doc="(L,) normal angle (rad, (-pi, pi])")
    start = property(lambda self: read_only(self.values[:, 2:4]), doc="(L, 2) endpoint at the first beam (m)")
    end = property(lambda self: read_only(self.values[:, 4:6]), doc="(L, 2) endpoint at the last beam (m)")
    first = property(lambda self: read_only(self.beams[:, 0]), doc="(L,) first beam (inclusive)")
    last = property(lambda self: read_only(self.beams[:, 1]), doc="(L,) last beam (inclusive)")
    n_points = property(lambda self: read_only(self.beams[:, 2]), doc="(L,) number of supporting valid beams")

    @property
    def cov(self) -> np.ndarray:
        """(L, 2, 2) covariance of (rho, alpha) of each line (a read-only view)."""
        return read_only(self.values[:, 6:10].reshape(-1, 2, 2))

    @property
    def length(self) -> np.ndarray:
        """(L,) length of each segment (m)."""
        d = self.values[:, 4:6] - self.values[:, 2:4]
        return np.hypot(d[:, 0], d[:, 1])

    def __len__(self) -> int:
        return self.values.shape[0]

    def __getitem__(self, i: Any) -> Any:
        """``lines[k]``: the ``Line`` of row k; a slice, integer array or boolean mask: those rows
        as ``Lines`` (``fs.lines[fs.lines.length > 0.5]``)."""
        i = row_index(i, len(self), "lines")
        if not isinstance(i, int):
            return Lines(self.values[i], self.beams[i])
        v = self.values[i].tolist()
        b = self.beams[i].tolist()
        line = object.__new__(Line)  # the frozen dataclass without its per-field setattr
        line.__dict__.update(rho=v[0], alpha=v[1], start=(v[2], v[3]), end=(v[4], v[5]), first=b[0], last=b[1],
                             cov=read_only(self.values[i, 6:10].reshape(2, 2)), n_points=b[2])
        return line

    def __iter__(self) -> Iterator[Line]:
        return (self[i] for i in range(len(self)))

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Sequence) and not isinstance(other, Lines):
            other = Lines.from_lines(list(other)) if len(other) else Lines.empty()
        if not isinstance(other, Lines):
            return NotImplemented
        return np.array_equal(self.values, other.values, equal_nan=True) and np.array_equal(self.beams, other.beams)

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"Lines({len(self)})"


class Corners(Sequence):
    """The corners of one scan as arrays; ``corners[i]`` is the ``Corner`` of row i.

    Attributes:
        values: (C, 3) float64: x, y (m), interior angle (rad, in (0, pi)).
        beams: (C, 3) int64: beam index of the corner, indices of its two lines (line i, i + 1).
    """

    __slots__ = ("values", "beams")

    def __init__(self, values: np.ndarray, beams: np.ndarray) -> None:
        self.values = values
        self.beams = beams

    @classmethod
    def empty(cls) -> Corners:
        return cls(np.empty((0, 3)), np.empty((0, 3), np.int64))

    @classmethod
    def from_corners(cls, corners: Sequence[Corner]) -> Corners:
        """Corners from ``Corner`` records.

        Raises:
            InputError: an item that is no Corner, or one whose x, y, angle are not finite numbers
                or whose index and lines are not whole numbers (fuzzing: a float item was an
                AttributeError, text numpy's ValueError, index 2.5 truncated to 2, silently).
        """
        if not corners:
            return cls.empty()
        for i, c in enumerate(corners):
            if not isinstance(c, Corner):
                raise InputError(f"corners[{i}]: must be a features.Corner, got {type(c).__name__}")
            try:  # lines: any two whole numbers (a tuple, a list, an array), as np.array took them before
                pair = tuple(c.lines) if not isinstance(c.lines, (str, bytes)) else ()
            except TypeError:
                pair = ()
            whole = [whole_number(v) for v in (c.index, *pair)] if len(pair) == 2 else []
            if len(whole) != 3 or None in whole:
                raise InputError(f"corners[{i}]: index and lines must be whole numbers (a beam, two line indices), "
                                 f"got {shown(c.index)}, {shown(c.lines)}")
            try:
                ok = all(np.isfinite(float(v)) for v in (c.x, c.y, c.angle))
            except (TypeError, ValueError, OverflowError):
                ok = False
            if not ok:
                raise InputError(f"corners[{i}]: x, y and angle must be finite numbers, got {shown(c.x)}, {shown(c.y)}, {shown(c.angle)}")
        values = np.array([(c.x, c.y, c.angle) for c in corners], dtype=float)
        beams = np.array([[whole_number(v) for v in (c.index, *tuple(c.lines))] for c in corners], dtype=np.int64)
        return cls(values, beams)

    x = property(lambda self: read_only(self.values[:, 0]), doc="(C,) x of each corner (m)")
    y = property(lambda self: read_only(self.values[:, 1]), doc="(C,) y of each corner (m)")
    angle = property(lambda self: read_only(self.values[:, 2]), doc="(C,) interior angle (rad, (0, pi))")
    beam = property(lambda self: read_only(self.beams[:, 0]), doc="(C,) beam index of each corner")
    line_pair = property(lambda self: read_only(self.beams[:, 1:3]), doc="(C, 2) indices of the two lines of each corner")

    def __len__(self) -> int:
        return self.values.shape[0]

    def __getitem__(self, i: Any) -> Any:
        """``corners[k]``: the ``Corner`` of row k; a slice, integer array or boolean mask: those
        rows as ``Corners``."""
        i = row_index(i, len(self), "corners")
        if not isinstance(i, int):
            return Corners(self.values[i], self.beams[i])
        x, y, angle = self.values[i].tolist()
        index, a, b = self.beams[i].tolist()
        corner = object.__new__(Corner)  # rows already checked or an extractor's: no per-access check
        corner.__dict__.update(x=x, y=y, angle=angle, index=index, lines=(a, b))
        return corner

    def __iter__(self) -> Iterator[Corner]:
        return (self[i] for i in range(len(self)))

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Sequence) and not isinstance(other, Corners):
            other = Corners.from_corners(list(other))
        if not isinstance(other, Corners):
            return NotImplemented
        return np.array_equal(self.values, other.values, equal_nan=True) and np.array_equal(self.beams, other.beams)

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"Corners({len(self)})"


class FeatureSet:
    """The features extracted from one scan: ``lines`` (``Lines``) and ``corners`` (``Corners``),
    arrays in the scan's sensor frame, and the ``method`` that found them.

    Built from ``Lines`` / ``Corners`` as they are (cheap: a user's extractor builds one a scan
    inside ``compare``'s timed span; :func:`check_feature_set` checks their rows, which
    ``extract``, ``extract_many`` and ``compare`` run on a method's result outside that span), or
    from sequences of ``Line`` / ``Corner`` records (each checked when it was built, by
    :func:`check_line` / :func:`check_corner`). The extractors use ``FeatureSet.of``.
    """

    __slots__ = ("lines", "corners", "method")

    def __init__(self, lines: Lines | Sequence[Line] = (), corners: Corners | Sequence[Corner] = (),
                 method: str = "") -> None:
        for name, value, kind in (("lines", lines, Lines), ("corners", corners, Corners)):
            if not isinstance(value, (kind, Iterable)) or isinstance(value, (str, bytes)):
                raise InputError(f"{name}: must be a features.{kind.__name__} or a sequence of "
                                 f"features.{kind.__name__[:-1]}, got {type(value).__name__}")
        self.lines = lines if isinstance(lines, Lines) else Lines.from_lines(list(lines))
        self.corners = corners if isinstance(corners, Corners) else Corners.from_corners(list(corners))
        self.method = method

    @classmethod
    def of(cls, lines: Lines, corners: Corners, method: str) -> FeatureSet:
        """The FeatureSet of ready arrays, without checks (the extractors' fast path)."""
        fs = object.__new__(cls)
        fs.lines, fs.corners, fs.method = lines, corners, method
        return fs

    def line_array(self) -> np.ndarray:
        """(n, 8) array: rho, alpha, x0, y0, x1, y1, first, last (for tables and plots)."""
        return np.column_stack((self.lines.values[:, :6], self.lines.beams[:, :2]))

    def corner_array(self) -> np.ndarray:
        """(m, 4) array: x, y, angle, index."""
        return np.column_stack((self.corners.values, self.corners.beams[:, 0]))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, FeatureSet):
            return NotImplemented
        return self.method == other.method and self.lines == other.lines and self.corners == other.corners

    __hash__ = None  # type: ignore[assignment]

    def __getstate__(self) -> tuple:
        return (self.lines.values, self.lines.beams, self.corners.values, self.corners.beams, self.method)

    def __setstate__(self, state: tuple) -> None:
        lv, lb, cv, cb, method = state
        self.lines, self.corners, self.method = Lines(lv, lb), Corners(cv, cb), method

    def __repr__(self) -> str:
        return f"FeatureSet({len(self.lines)} lines, {len(self.corners)} corners, method={self.method!r})"


_LINES_SLOT = FeatureSet.__dict__["lines"]  # the base class's slots, where BatchFeatureSet caches its views
_CORNERS_SLOT = FeatureSet.__dict__["corners"]


class BatchFeatureSet(FeatureSet):
    """The FeatureSet of scan ``s`` of an ``extract_many`` batch: built without per-scan work, its
    ``lines`` and ``corners`` become views of the batch's concatenated rows on first access (then
    kept). Equal to, and used as, a FeatureSet; pickles and copies as one."""

    __slots__ = ("_rows", "_s")

    @classmethod
    def cut(cls, rows: tuple, s: int, method: str) -> BatchFeatureSet:
        """Scan ``s``'s FeatureSet of ``rows`` = (line values, line beams, corner values, corner
        beams, line offsets, corner offsets) as Python lists of offsets (the batch's rows)."""
        fs = object.__new__(cls)
        fs._rows, fs._s, fs.method = rows, s, method
        return fs

    @property  # type: ignore[override]
    def lines(self) -> Lines:
        try:
            return _LINES_SLOT.__get__(self, FeatureSet)  # type: ignore[no-any-return]
        except AttributeError:
            lv, lb, _, _, lo, _ = self._rows
            a, b = lo[self._s], lo[self._s + 1]
            lines = Lines(lv[a:b], lb[a:b])
            _LINES_SLOT.__set__(self, lines)
            return lines

    @lines.setter
    def lines(self, value: Lines) -> None:
        _LINES_SLOT.__set__(self, value)

    @property  # type: ignore[override]
    def corners(self) -> Corners:
        try:
            return _CORNERS_SLOT.__get__(self, FeatureSet)  # type: ignore[no-any-return]
        except AttributeError:
            _, _, cv, cb, _, co = self._rows
            a, b = co[self._s], co[self._s + 1]
            corners = Corners(cv[a:b], cb[a:b])
            _CORNERS_SLOT.__set__(self, corners)
            return corners

    @corners.setter
    def corners(self, value: Corners) -> None:
        _CORNERS_SLOT.__set__(self, value)

    def __reduce__(self) -> tuple:
        return FeatureSet, (self.lines, self.corners, self.method)

