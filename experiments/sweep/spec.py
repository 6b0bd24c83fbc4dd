"""Sweep files: what to vary, and the list of cells (parameter sets) they expand to.

A sweep file is YAML::

    name: k_vs_noise          # names the output folder by default
    kind: extract             # the cell kind (see experiments.sweep.cells), or "pkg.module:function"
    fixed:                    # the same in every cell
      world: office
      duration: 4.0
    grid:                     # every combination of these (Cartesian product)
      extractor.k: [5, 10, 15]
      sensor.noise_sigma: [0.0, 0.005, 0.01]
    random:                   # optional: `samples` draws from these, crossed with the grid
      extractor.ad_threshold: {uniform: [0.02, 0.2]}
    samples: 8                # number of random draws (needs `random`)
    sample_seed: 0            # seeds the draws (numpy Generator), so the cells are reproducible
    seeds: [0, 1, 2]          # crossed with everything; each cell gets a `seed` column

``seeds:`` and every grid entry are lists: a bare value is refused (``seeds: 3`` ran the one seed 3
where three seeds were meant; ``extractor.k: 3, 5, 10`` is the one string "3, 5, 10" in YAML).

Parameters that must change together are linked: a grid key of comma-separated names takes
tuples, e.g. ``"sensor.noise_sigma,extractor.sigma_r": [[0.002, 0.002], [0.01, 0.01]]``.

Random distributions: ``{uniform: [lo, hi]}``, ``{loguniform: [lo, hi]}``, ``{int: [lo, hi]}``
(inclusive), ``{choice: [a, b, ...]}``. Parameter names are free; the built-in cell kinds read
``extractor.*`` (extractor parameters), ``sensor.*`` (``SensorConfig`` fields), ``slam.*``
(``SlamConfig`` fields) and plain names (``method``, ``world``, ``duration``, ...). Every
parameter becomes a column of the result table, under the name written here.
"""

from __future__ import annotations

from lms200.finite import printable, shown
from lms200.yamlio import SWEEP_SIZE_HINT, load as load_yaml, size_problem

import hashlib
import itertools
from collections import Counter
import json
import math
import re
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from lms200 import LmsbenchError

Scalar = str | int | float | bool | None
_DISTRIBUTIONS = ("uniform", "loguniform", "int", "choice")
MAX_CELLS = 100_000  # cells of one sweep at most: each is a simulated run; the cell list stays small in memory
MAX_SEED = 2**32 - 1  # as the CLI's --seed (numpy seeds a Generator from any int; worlds take 32 bits)
_KEYS = {"name", "kind", "fixed", "grid", "random", "samples", "sample_seed", "seeds", "description"}


class SweepSpecError(LmsbenchError):
    """A sweep file that cannot be expanded; the message says which field and what to fix."""


@dataclass(frozen=True)
class SweepSpec:
    """A parsed sweep file. :meth:`cells` expands it into parameter sets, in a stable order."""

    name: str
    kind: str
    fixed: dict[str, Scalar] = field(default_factory=dict)
    grid: dict[str, list[Scalar]] = field(default_factory=dict)
    random: dict[str, dict[str, list[Any]]] = field(default_factory=dict)
    samples: int = 0
    sample_seed: int = 0
    seeds: list[int] = field(default_factory=lambda: [0])
    description: str = ""

    def __post_init__(self) -> None:
        for f in fields(self):  # np.linspace's values, as researchers write them (np.int64 samples, np.str_ names)
            object.__setattr__(self, f.name, _plain(getattr(self, f.name)))
        _check(self)

    @classmethod
    def from_dict(cls, raw: dict[str, Any], default_name: str = "sweep", where: str | None = None) -> "SweepSpec":
        """The spec of a sweep file's mapping; ``where`` (the file) names it in the warning for an old
        degree parameter (see :func:`_degree_parameters`)."""
        if not isinstance(raw, dict):
            raise SweepSpecError("a sweep file must be a YAML mapping (name, kind, grid, ...)")
        raw = _plain(raw)
        unknown = set(raw) - _KEYS
        if unknown:
            raise SweepSpecError(f"unknown key(s) {sorted(unknown, key=str)} in the sweep file; known: {sorted(_KEYS)}")
        if "kind" not in raw:
            raise SweepSpecError("the sweep file needs `kind:` (a cell kind such as extract or slam)")
        if not isinstance(raw["kind"], str):  # str() of it ran: an int of 5,000 digits was an internal error
            raise SweepSpecError(f"kind: must be text (a cell kind such as extract or slam, or MODULE:FUNCTION), "
                                 f"got {type(raw['kind']).__name__} {shown(raw['kind'], 60)}")
        for key in ("fixed", "grid", "random"):
            if raw.get(key) is not None and not isinstance(raw[key], dict):
                raise SweepSpecError(f"{key} must be a mapping of parameter -> "
                                     f"{'value' if key == 'fixed' else 'values' if key == 'grid' else 'distribution'}, "
                                     f"got {type(raw[key]).__name__} {shown(raw[key], 60)}")
        seeds = raw.get("seeds", [0])
        if isinstance(seeds, int) and not isinstance(seeds, bool):  # `seeds: 3` ran the one seed 3
            n = seeds if 2 <= seeds <= 10 else 3
            one = shown(seeds)
            raise SweepSpecError(f"`seeds: {one}` is one number: write a list, `seeds: {list(range(n))}` for {n} "
                                 f"seeds, `seeds: [{one}]` for the one seed {one}")
        for key, values in (raw.get("grid") or {}).items():
            if not isinstance(values, (list, tuple)):  # `k: 3, 5, 10` is the one string '3, 5, 10' in YAML
                raise SweepSpecError(f"grid.{key}: {shown(values, 80)} is a single value: write a list of the values to vary "
                                     f"(`[{values if isinstance(values, str) else shown(values, 80)}]` for this one, or put it under fixed:)")
        name = raw.get("name", default_name)
        if not isinstance(name, str):
            raise SweepSpecError(f"name: must be a string (it names the output folder results/sweeps/NAME), got {shown(name, 80)}")
        if "name" not in raw and not _plain_name(name):  # "name: 'my sweep' must be ..." blamed a key not written
            raise SweepSpecError(f"no `name:` given, and the file's name {name!r} cannot name the output folder "
                                 f"results/sweeps/NAME ({NAME_RULE}); add a `name:`")
        spec = cls(
            name=name,
            kind=raw["kind"],
            fixed=dict(raw.get("fixed") or {}),
            grid={k: list(v) for k, v in (raw.get("grid") or {}).items()},
            random=dict(raw.get("random") or {}),
            samples=_whole("samples", raw.get("samples", 0), MAX_CELLS),
            sample_seed=_whole("sample_seed", raw.get("sample_seed", 0), MAX_SEED),
            seeds=_seeds(seeds),
            description=_description(raw.get("description")),
        )
        _degree_parameters(spec, where)
        return spec

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"name": self.name, "kind": self.kind}
        if self.description:
            out["description"] = self.description
        for key in ("fixed", "grid", "random"):
            if getattr(self, key):
                out[key] = getattr(self, key)
        if self.random:
            out["samples"] = self.samples
            out["sample_seed"] = self.sample_seed
        out["seeds"] = list(self.seeds)
        return out

    def cells(self) -> list[dict[str, Scalar]]:
        """Every parameter set: fixed x grid product x random draws x seeds, in that nesting order."""
        combos = []
        for values in itertools.product(*self.grid.values()):
            combo: dict[str, Scalar] = {}
            for key, value in zip(self.grid, values):
                combo.update(zip(_names(key), value) if "," in key else {key: value})
            combos.append(combo)
        draws = _draw(self.random, self.samples, self.sample_seed) if self.random else [{}]
        cells = []
        for combo in combos:
            for draw in draws:
                for seed in self.seeds:
                    cells.append({**self.fixed, **combo, **draw, "seed": seed})
        return cells

    def repeated_draws(self) -> tuple[int, int | None]:
        """How many of the ``samples`` random draws repeat an earlier one (the same value of every random
        parameter, so the same cells: a cell runs once, and the sweep has that many draws fewer than
        asked), and the number of points of the random space when it is finite (every law ``int``,
        ``choice``, or a ``uniform`` / ``loguniform`` of low == high; None otherwise)."""
        if not self.random:
            return 0, None
        draws = _draw(self.random, self.samples, self.sample_seed)
        distinct = {json.dumps(draw, sort_keys=True) for draw in draws}  # as cell_key tells cells apart
        return len(draws) - len(distinct), _space_points(self.random)


def _space_points(space: dict[str, dict[str, list[Any]]]) -> int | None:
    """The number of points of a random space (their product over the parameters), None for a
    continuous one."""
    points = 1
    for dist in space.values():
        (law, args), = dist.items()
        if law == "int":
            points *= int(args[1]) - int(args[0]) + 1
        elif law == "choice":
            points *= len({json.dumps(v) for v in args})
        elif args[0] != args[1]:
            return None
    return points


def load_sweep(path: str | Path) -> SweepSpec:
    """Read and check a sweep YAML file.

    Raises:
        LmsbenchError: a path that is no str / PathLike, missing, a folder, a device or a pipe (a raw
            FileNotFoundError or IsADirectoryError), or a file that is no sweep (``SweepSpecError``).
    """
    from lms200.logs import regular_file

    path = regular_file(path, "sweep file")
    too_big = size_problem(path.stat().st_size, "a sweep file", SWEEP_SIZE_HINT) if path.is_file() else None
    if too_big:  # refused unread: a 1.5 MB file took 81 s to parse and check
        raise SweepSpecError(f"{path}: {too_big}")
    try:
        raw = load_yaml(path.read_text())
    except yaml.YAMLError as exc:
        raise SweepSpecError(f"{path}: not valid YAML: {exc}") from exc
    try:
        return SweepSpec.from_dict(raw, default_name=path.stem, where=str(path))
    except SweepSpecError as exc:
        raise SweepSpecError(f"{path}: {exc}") from exc


def _whole(name: str, value: Any, maximum: int) -> int:
    """A whole number in [0, maximum] from the sweep file (not a bool, string or fraction)."""
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= maximum:
        raise SweepSpecError(f"`{name}:` must be a whole number in [0, {maximum}], got {shown(value, 80)}")
    return value


def _description(raw: Any) -> str:
    """The ``description:`` text ('' when absent or empty): anything else was written as its Python
    text into sweep.yaml (`description:` with no value as 'None', a list as "[1, 2]"), exit 0."""
    if raw is None:
        return ""
    if not isinstance(raw, str):
        raise SweepSpecError(f"description: must be text (quote it if YAML reads it otherwise), got "
                             f"{type(raw).__name__} {shown(raw, 60)}")
    return raw


def _seeds(raw: Any) -> list[int]:
    """The ``seeds:`` list: whole numbers (a bare number is refused before: ``seeds: 3`` is ambiguous)."""
    if not isinstance(raw, (list, tuple)) or not all(isinstance(s, int) and not isinstance(s, bool) for s in raw):
        raise SweepSpecError(f"`seeds:` must be a list of whole numbers >= 0, got {shown(raw, 80)}")
    return list(raw)


def _degree_parameters(spec: SweepSpec, where: str | None) -> None:
    """Say, in one warning each, a ``sensor.*`` parameter of the old degree spelling
    (``sensor.resolution_deg``: sweep files written before the sensor config held radians, issue
    #16) with the radians to write instead; such a sweep still runs, each cell's value converted
    (``SensorConfig.replace``), and its cells and table keep the name as written, so a sweep of an
    old file resumes where it stopped. Both spellings of one field are refused.

    Raises:
        SweepSpecError: for ``sensor.resolution_deg`` and ``sensor.resolution`` in one sweep.
    """
    import warnings

    from lms200.errors import LmsbenchWarning
    from sim.sensor import DEGREE_FIELDS

    names = {*spec.fixed, *(n for key in spec.grid for n in _names(key)), *spec.random}
    place = f"{where}: " if where else ""
    for old, new in DEGREE_FIELDS.items():
        old_name, new_name = f"sensor.{old}", f"sensor.{new}"
        if old_name not in names:
            continue
        if new_name in names:
            raise SweepSpecError(f"gives both {old_name} (deg, the old spelling) and {new_name} (rad); give {new_name} only")
        values: list[Any] = [spec.fixed[old_name]] if old_name in spec.fixed else []
        for key, grid_values in spec.grid.items():
            if old_name in _names(key):
                i = _names(key).index(old_name)
                values += [v[i] if "," in key and isinstance(v, (list, tuple)) and len(v) > i else v for v in grid_values]
        numbers = sorted({v for v in values if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)})
        instead = (f" ({', '.join(f'{v:g} deg = {math.radians(v)!r}' for v in numbers)})" if numbers else "")
        warnings.warn(f"{place}{old_name} (deg) is the old spelling of {new_name} (rad); read, each value converted; "
                      f"write {new_name} with the values in radians{instead} instead", LmsbenchWarning, stacklevel=3)


def cell_key(kind: str, params: dict[str, Scalar], inputs: dict[str, str] | None = None) -> str:
    """A stable 16-hex-digit hash of the cell kind and its parameters (key order does not matter)
    and ``inputs``, the digests of the files the cell reads (parameter name -> digest, the kind's
    ``input_digests``), so that a cell whose file changed is computed again; without any, the key
    is the one of before."""
    record: dict[str, Any] = {"kind": kind, "params": params}
    if inputs:
        record["inputs"] = inputs
    text = json.dumps(record, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _names(key: str) -> list[str]:
    """The parameter names of a grid key (several for a linked key "a,b")."""
    return [name.strip() for name in key.split(",")]


MAX_NAME_CHARS = 100
"""Longest sweep name: it names a folder, and a 300-character one failed only when the folder was
made ("File name too long"), after the sweep file had been read and checked."""
NAME_RULE = f"letters, digits, _ . -, not starting with . or -, at most {MAX_NAME_CHARS} characters"


def _plain_name(name: str) -> bool:
    """A name that is one plain folder name: no path separator, no `..`, no hidden or option-like name."""
    return len(name) <= MAX_NAME_CHARS and re.fullmatch(r"[A-Za-z0-9_][A-Za-z0-9_.-]*", name) is not None


#: the runner's own columns of a sweep's table (runner._row): a parameter of one of these names (a kind of
#: one's own takes any) had its values overwritten by them, the cells told apart by nothing, exit 0
RUNNER_COLUMNS = ("status", "error", "elapsed_s", "cell")
#: the largest whole number a sweep's table holds (int64): a grid value or a cell's metric of 10**30 was an
#: internal OverflowError where the cell's row was written, which ended the sweep
MAX_TABLE_INT = 2**63 - 1


#: what a metric's name may be: it names a column and the plots' files, sweep_NAME_METRIC.png ("rmse (m)" and
#: "F1@3cm" are names a file takes, and earlier sweeps hold them)
METRIC_NAME_RULE = (f"printable text of 1 to {MAX_NAME_CHARS} bytes in UTF-8, without / or \\ or $, not starting "
                    "with .")


def metric_name_problem(name: object) -> str | None:
    """Why ``name`` cannot be a sweep metric's name, or None: a cell's metric names a column of the
    sweep's tables and the figures' files of its plots (``sweep_NAME_METRIC.png``), so it is text a
    file name takes. A kind of one's own returned ``"a/b\\n"`` (its plot written as ``b\\n.png`` in a
    folder ``sweep_NAME_a/`` the next ``figures --out`` refused) or 5,000 characters (figures: internal
    MemoryError)."""
    # bytes, not characters: a file name takes 255 ('€' * 100 failed part-way, "file name too long"); no $,
    # which matplotlib's labels read as maths ('$x^^2$' was an internal error part-way through the plots)
    if (isinstance(name, str) and name.isprintable() and 0 < len(name.encode("utf-8", "replace")) <= MAX_NAME_CHARS  # a lone
            # surrogate (os.fsdecode of undecodable bytes) is not printable
            and not name.startswith(".") and not any(c in name for c in "/\\$")):
        return None
    text = repr(name)  # one line whatever the key: a long one cut, as _quoted cuts a name
    shown = _quoted(name) if isinstance(name, str) else f"{text if len(text) <= 60 else text[:40] + '...'} ({type(name).__name__})"
    return f"a metric named {shown}: a metric's name is {METRIC_NAME_RULE}, as it names a column and the plots' files"


def _quoted(name: str) -> str:
    """``name`` quoted for a one-line message, a long one cut to its start and end with its own length
    (``shown`` gives its quoted repr's: 302 characters for a name of 300)."""
    text = repr(name)
    return text if len(text) <= 60 else f"{name[:40]!r}...{name[-8:]!r} ({len(name):,} characters)"


def _check(spec: SweepSpec) -> None:
    if not _plain_name(spec.name):
        raise SweepSpecError(f"name: {_quoted(str(spec.name))} must be a plain folder name ({NAME_RULE}), "
                             "as it names the output folder results/sweeps/NAME")
    for part in ("fixed", "grid", "random"):  # `null: 3` or `1: 3` was an internal AttributeError at the kinds' check
        for key in getattr(spec, part):
            if not isinstance(key, str) or not all(_names(key)):  # "a,": a linked key of an empty second name
                raise SweepSpecError(f"{part}: parameter name {key!r} must be text (a name, or names linked by commas, "
                                     "none of them empty)")
    names = Counter([*spec.fixed, *(n for key in spec.grid for n in _names(key)), *spec.random])
    clashes = sorted({n for n, times in names.items() if times > 1} | ({"seed"} & set(names)))  # one pass (count() was n^2)
    if clashes:
        raise SweepSpecError(f"parameter(s) {clashes} given twice (fixed/grid/random/seeds); give each once")
    taken = sorted(set(names) & set(RUNNER_COLUMNS))
    if taken:
        raise SweepSpecError(f"parameter(s) {taken} named as a column the runner writes in every row "
                             f"({', '.join(RUNNER_COLUMNS)}), which would overwrite its values; name it otherwise")
    for name, value in spec.fixed.items():
        _check_scalar(f"fixed.{name}", value)
    for name, values in spec.grid.items():
        if not values:
            raise SweepSpecError(f"grid.{name} is empty; give at least one value")
        for value in values:
            if "," in name:
                if not isinstance(value, (list, tuple)) or len(value) != len(_names(name)):
                    raise SweepSpecError(f"grid.{name} links {len(_names(name))} parameters: each value must be "
                                         f"a list of {len(_names(name))}, got {shown(value, 80)}")
                for v in value:
                    _check_scalar(f"grid.{name}", v)
            else:
                _check_scalar(f"grid.{name}", value)
        # after the type checks (an np.int64 gets their message); `k: [3, 3]` ran one cell, one row, without
        # a word (seeds refuse it), and by value: [1, 1.0] or [0.0, -0.0] passed a comparison of repr
        seen: dict[Any, Any] = {}
        for value in values:
            key = _value_key(value)
            if key in seen:
                same = "" if repr(seen[key]) == repr(value) else f" (equal to {shown(seen[key], 80)})"
                raise SweepSpecError(f"grid.{name}: {shown(value, 80)} is given twice{same}; a grid point runs once, so "
                                     "give each value once (vary seeds: to repeat a run)")
            seen[key] = value
    for name, dist in spec.random.items():
        if not (isinstance(dist, dict) and len(dist) == 1 and next(iter(dist)) in _DISTRIBUTIONS):
            raise SweepSpecError(f"random.{name} must be one of {{{'|'.join(_DISTRIBUTIONS)}: [...]}}, got {dist!r}")
        (law, args), = dist.items()
        numeric = isinstance(args, list) and all(
            not isinstance(a, bool) and isinstance(a, (int, float)) and _finite(a) for a in args)
        if law != "choice" and (not numeric or len(args) != 2 or not args[0] <= args[1]):
            raise SweepSpecError(f"random.{name}: {law} needs [low, high], finite numbers with low <= high, got {shown(args, 80)}")
        if law == "int" and not all(isinstance(a, int) for a in args):
            raise SweepSpecError(f"random.{name}: int needs whole-number bounds [low, high], got {shown(args, 80)}")
        beyond = next((a for a in args if table_int_problem(a)), None) if law == "int" else None
        if beyond is not None:  # 10**24: numpy's "high is out of bounds"; a draw is a cell's value, as a grid's
            raise SweepSpecError(f"random.{name}: int's bounds must be within int64's range, [-2**63, 2**63 - 1], "
                                 f"that a sweep's table holds, got a whole number of {_digits(beyond)} digits "
                                 "(a wider range: uniform:)")
        if law == "uniform" and not math.isfinite(args[1] - args[0]):  # [-1e308, 1e308]: numpy's OverflowError
            raise SweepSpecError(f"random.{name}: uniform needs high - low finite, got {shown(args, 80)}")
        if law == "loguniform" and args[0] <= 0:
            raise SweepSpecError(f"random.{name}: loguniform needs low > 0, got {shown(args, 80)}")
        if law == "choice" and (not isinstance(args, list) or not args):
            raise SweepSpecError(f"random.{name}: choice needs a non-empty list, got {shown(args, 80)}")
        if law == "choice":  # each a cell's value, as a grid's: a list drawn was an internal TypeError, nan a cell
            for value in args:
                _check_scalar(f"random.{name}", value)
    if spec.random and spec.samples < 1:
        raise SweepSpecError("`random:` needs `samples:` >= 1 (the number of draws)")
    if not spec.random and (spec.samples or spec.sample_seed):  # ignored: `samples: 8` ran 1 cell, not 8, exit 0
        given = f"`samples: {shown(spec.samples)}`" if spec.samples else f"`sample_seed: {shown(spec.sample_seed)}`"
        raise SweepSpecError(f"{given} is for random draws, and the sweep has no `random:` parameters to draw "
                             "(each grid point would run once, not once a draw); add a `random:` mapping, "
                             "e.g. `random: {extractor.ad_tau: {uniform: [2.0, 8.0]}}`, or leave it out")
    if not spec.seeds:
        raise SweepSpecError("`seeds:` is empty; give at least one seed")
    if any(not 0 <= s <= MAX_SEED for s in spec.seeds) or len(set(spec.seeds)) != len(spec.seeds):
        raise SweepSpecError(f"`seeds:` must be distinct integers in [0, {MAX_SEED}], got {shown(spec.seeds, 80)}")
    n_cells = math.prod(len(v) for v in spec.grid.values()) * (spec.samples if spec.random else 1) * len(spec.seeds)
    if n_cells > MAX_CELLS:
        raise SweepSpecError(f"the sweep has {n_cells} cells (grid x samples x seeds), more than {MAX_CELLS}; "
                             "split it into several sweeps")


def _finite(value: int | float) -> bool:
    """Whether a number is finite as a float64: a whole number beyond +-1.8e308 is not (math.isfinite and
    numpy raised OverflowError on one of 401 digits, an internal error)."""
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


def _value_key(value: Any) -> Any:
    """What makes two checked grid values one grid point: numbers by value (1 and 1.0, 0.0 and -0.0
    are one), a bool apart from the numbers (True is not 1), a linked value item by item."""
    if isinstance(value, (list, tuple)):
        return tuple(_value_key(v) for v in value)
    return (isinstance(value, bool), value)  # an int equals a float of its value, and hashes alike


def _digits(n: int) -> str:
    """How many decimal digits the whole number ``n`` has; past Python's 4,300-digit limit on int-to-text
    conversion (``str`` raised ValueError: an internal error for a 5,000-digit value in a sweep file)
    the count from its bits, "about N"."""
    try:
        return str(len(str(abs(n))))
    except ValueError:
        return f"about {int(abs(n).bit_length() * math.log10(2)) + 1}"


#: deepest nesting a sweep's values may have (a linked key's points are lists of lists: 3 levels under
#: ``grid:``); a Python list nested 5,000 deep was a RecursionError
MAX_SPEC_DEPTH = 32


def _plain(value: Any, depth: int = 0) -> Any:
    """``value`` with numpy scalars as their Python values (``np.float64(0.5)`` as 0.5, ``np.str_``,
    ``np.bool_``, ``np.int64`` alike) and numpy arrays as lists of them (``np.linspace(0.1, 0.5, 5)``,
    ``np.arange(3)`` as seeds), lists, tuples and mappings item by item (keys too); anything else as
    given, for the checks after. A numpy scalar was refused ("give a Python one"): it passed as a float
    and failed as sweep.yaml was written (RepresenterError).

    Raises:
        SweepSpecError: nested deeper than MAX_SPEC_DEPTH.
    """
    if depth > MAX_SPEC_DEPTH:
        raise SweepSpecError(f"a sweep's value is nested deeper than {MAX_SPEC_DEPTH} levels (lists or mappings): "
                             "a value is a number, string, bool or null, a grid's points a list of them")
    if isinstance(value, np.ndarray):
        return _plain(value.tolist(), depth)  # an object array's items stay numpy's in tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, tuple):
        return tuple(_plain(v, depth + 1) for v in value)
    if isinstance(value, list):
        return [_plain(v, depth + 1) for v in value]
    if isinstance(value, dict):  # keys too: an np.str_ parameter name passed the name check as a str
        return {_plain(k, depth + 1): _plain(v, depth + 1) for k, v in value.items()}
    return value


def _check_scalar(where: str, value: Any) -> None:
    if not isinstance(value, (str, int, float, bool, type(None))):
        hint = " (to vary it, put it under grid:)" if where.startswith("fixed.") and isinstance(value, list) else ""
        raise SweepSpecError(f"{where} must be a number, string, bool or null, got {shown(value, 80)}{hint}")
    if isinstance(value, str) and printable(value) != value:  # "w\uDCFF.json": a table's text is UTF-8
        raise SweepSpecError(f"{where}: {shown(value, 80)} is not UTF-8 text (it holds a lone surrogate, "
                             f"a file name's undecodable byte); a sweep's table holds UTF-8 text: rename the file")
    if isinstance(value, (int, float)) and not _finite(value):
        text = repr(value) if isinstance(value, float) else f"a whole number of {_digits(value)} digits"
        raise SweepSpecError(f"{where} must be finite (within float64's range, +-1.8e308), got {text}")
    if (problem := table_int_problem(value)) is not None:
        raise SweepSpecError(f"{where}: {problem}")


def table_int_problem(value: Any) -> str | None:  # noqa: ANN401 - any value a sweep's table may be given
    """Why the whole number ``value`` (a parameter's, a random ``int:`` bound or a cell's metric; Python's
    or numpy's) cannot be a value of a sweep's table, or None (no whole number, or one within int64,
    ``MAX_TABLE_INT``): the one check and wording of that bound (the spec and the cells had one each)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        return None
    n = int(value)
    if -MAX_TABLE_INT - 1 <= n <= MAX_TABLE_INT:
        return None
    as_float = f" (a float holds it: {float(n):g})" if _finite(n) else ""  # 10**400 is beyond a float too
    return f"a whole number of {_digits(n)} digits, beyond int64's range (+-9.2e18) that a sweep's table holds{as_float}"


def _draw(space: dict[str, dict[str, list[Any]]], samples: int, seed: int) -> list[dict[str, Scalar]]:
    """``samples`` draws from ``space`` with a seeded Generator; plain Python scalars out."""
    rng = np.random.default_rng(seed)
    draws: list[dict[str, Scalar]] = [{} for _ in range(samples)]
    for name, dist in space.items():  # one parameter at a time: adding one keeps the others' draws
        (law, args), = dist.items()
        if law == "uniform":
            values = rng.uniform(args[0], args[1], samples).tolist()
        elif law == "loguniform":
            values = np.exp(rng.uniform(np.log(args[0]), np.log(args[1]), samples)).tolist()
        elif law == "int":
            values = rng.integers(int(args[0]), int(args[1]), samples, endpoint=True).tolist()
        else:
            values = [args[i] for i in rng.integers(0, len(args), samples)]
        for draw, value in zip(draws, values):
            draw[name] = value
    return draws
