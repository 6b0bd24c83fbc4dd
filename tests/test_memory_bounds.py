"""Bounded memory: one extraction call on any scan a Scan accepts stays within 50 MB of address
space for every method (run in a subprocess under ``resource.setrlimit(RLIMIT_AS)``), answering
with a FeatureSet or a clear ValueError, never a MemoryError; alpha stays in (-pi, pi]."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from features import available_methods, extract
from lms200 import Scan
from lms200.errors import LmsbenchWarning

ROOT = Path(__file__).resolve().parents[1]
LIMIT_MB = 50

CHILD = r"""
import resource, sys
import numpy as np
from features import available_methods, extract
from features.registry import MAX_BEAMS
from lms200 import Scan

def room(n, inc, far=None, range_max=8.183):
    b = -0.5 * (n - 1) * inc + np.arange(n) * inc
    r = np.minimum(3.0 / np.maximum(np.abs(np.cos(b)), 1e-3), 2.5 / np.maximum(np.abs(np.sin(b)), 1e-3))
    r = r + 0.005 * np.random.default_rng(0).standard_normal(n)
    if far is not None:
        r[n // 3] = far
    return Scan(np.minimum(r, 0.99 * range_max), float(b[0]), inc, 0.0, range_max)

scans = {
    "lms200": room(361, np.deg2rad(0.5)),
    "one 50 km return": room(361, np.deg2rad(0.5), far=5e4, range_max=1e5),
    "1e300 returns": Scan(np.full(361, 1e300), -1.5, np.deg2rad(0.5), 0.0, 1e308),
    "1e-9 rad step": room(361, 1e-9),
    "max beams over 360 deg": room(MAX_BEAMS, 2 * np.pi / MAX_BEAMS, range_max=80.0),
    "max beams, 1e-7 rad step": room(MAX_BEAMS, 1e-7),
    "too many beams": room(MAX_BEAMS + 1, 2 * np.pi / (MAX_BEAMS + 1)),
}
methods = available_methods()
for m in methods:  # load the compiled kernels before the limit
    extract(scans["lms200"], m)
status = dict(line.split(":", 1) for line in open("/proc/self/status"))
vm = int(status["VmSize"].split()[0]) * 1024
limit = vm + LIMIT_MB * 2**20
resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
for name, scan in scans.items():
    for m in methods:
        try:
            fs = extract(scan, m)
            a = fs.lines.alpha
            assert np.all((a > -np.pi) & (a <= np.pi)), (name, m, a)
            print(f"{name}|{m}|ok {len(fs.lines)}")
        except ValueError as exc:
            print(f"{name}|{m}|ValueError {exc}")
        except MemoryError:
            print(f"{name}|{m}|MemoryError")
"""


@pytest.mark.slow
def test_one_call_stays_within_50_mb_on_any_scan() -> None:
    code = f"LIMIT_MB = {LIMIT_MB}\n" + CHILD
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    rows = [line.split("|", 2) for line in out.stdout.splitlines()]
    results = {(name, m): r for name, m, r in rows}
    assert len(results) == 7 * len(available_methods())
    assert not [k for k, r in results.items() if r.startswith("MemoryError")], results
    for m in available_methods():  # the ordinary scan and the many-beam scan work; beyond the limit, a clear error
        assert results[("lms200", m)].startswith("ok"), results
        assert results[("max beams over 360 deg", m)].startswith("ok"), results
        assert "split the scan into sectors" in results[("too many beams", m)], results
    # the sensor method's template is bounded: a step too fine for it is refused by name
    assert "angle_increment" in results[("1e-9 rad step", "sensor")]
    assert "hough: the accumulator" in results[("1e300 returns", "hough")]


def test_alpha_is_never_minus_pi() -> None:
    """A wall straight behind the sensor (normal angle pi), seen by a scan centred backwards: every
    method reports alpha = pi there, never -pi."""
    n = 361
    inc = np.deg2rad(0.5)
    b = np.pi - 0.5 * (n - 1) * inc + np.arange(n) * inc
    scan = Scan(np.clip(-2.0 / np.cos(b), 0, 7.0), float(b[0]), inc, 0.0, 8.183)
    for m in available_methods():
        a = extract(scan, m).lines.alpha
        assert a.size and np.all((a > -np.pi) & (a <= np.pi)), (m, a)


def test_a_window_wider_than_any_scan_is_a_config_error_not_an_allocation():
    """k sized the window-sum tables: k = 10**9 asked for 8 GB and the process was killed."""
    from features.errors import ConfigError
    from features.registry import MAX_BEAMS, make_config

    assert make_config("sensor", k=MAX_BEAMS // 2).k == MAX_BEAMS // 2
    with pytest.raises(ConfigError, match=r"^k: must be an integer >= 1 and <= 8192"):
        make_config("sensor", k=10**9)


def test_extreme_hough_steps_and_bad_corner_configs_are_clear_errors():
    """rho_step = 1e308 overflowed the accumulator size (OverflowError; now refused by the config, as
    1e-300); a corners field that is not a CornerConfig reached the extractor of hough / ransac
    (AttributeError). A geometry beyond a method's bound is a ScanGeometryError: a ValueError (issue 12) and an LmsbenchError (one line on the CLI)."""
    from features.errors import ConfigError, ScanGeometryError
    from features.registry import MAX_BEAMS, make_config
    from lms200 import LmsbenchError

    b = np.deg2rad(0.5) * (np.arange(361) - 180)
    scan = Scan(np.minimum(3.0 / np.maximum(np.abs(np.cos(b)), 1e-3), 8.0), float(b[0]), np.deg2rad(0.5), 0.0, 8.183)
    for step in (1e308, 1e-300):  # one rho cell, no line, F1 0; or the accumulator error at the run
        with pytest.raises(ConfigError, match=r"^rho_step: must be a width in \[0.0001, 1\] m"):
            make_config("hough", rho_step=step)
    with pytest.raises(ScanGeometryError, match="accumulator") as info:  # a small step still meets the accumulator's bound
        extract(scan, "hough", config=make_config("hough", rho_step=1e-4))
    assert isinstance(info.value, ValueError) and isinstance(info.value, LmsbenchError)
    for method in ("hough", "ransac", "split_merge", "iepf"):
        for corners in ("abc", None, 3.0):  # a mapping is the corner step's fields ({}: its defaults)
            with pytest.raises(ConfigError, match="^corners: must be a CornerConfig"):
                make_config(method, corners=corners)
        assert make_config(method, corners={}).corners == make_config(method).corners
    wide = Scan(np.full(MAX_BEAMS + 1, 2.0), -1.0, 1e-4, 0.0, 8.0)
    with pytest.raises(ScanGeometryError, match="beams is more than"):
        extract(wide, "split_merge")


FINE_STEPS = r"""
import resource
import numpy as np
from features import extract
from lms200 import Scan

extract(Scan.lms200(np.full(361, 2.0)))
vm = int([l for l in open("/proc/self/status") if l.startswith("VmSize:")][0].split()[1]) * 1024
resource.setrlimit(resource.RLIMIT_AS, (vm + LIMIT_MB * 2**20, vm + LIMIT_MB * 2**20))
finest = 4 * (0.5 * np.pi) / ((2**20 - 1) / 2 - 2) * 1.0000001  # the template bound at hough_subdiv 4
for j in range(6):
    inc = finest * (1 + 1e-3 * j)
    b = -1000 * inc + np.arange(2001) * inc
    try:
        print(j, "ok", len(extract(Scan(2.0 / np.cos(b), float(b[0]), inc, 0.0, 8.0)).lines))
    except MemoryError:
        print(j, "MemoryError")
"""


def test_sensor_grids_kept_between_calls_stay_bounded() -> None:
    """The sensor method's Log-Hough grids were kept in an lru_cache of 64: up to 16 MB each at the
    finest beam step allowed, so a process extracting from scans of a few fine steps ran out of a
    50 MB budget at the third step (71 of 3,000 fuzzed API calls: MemoryError). The kept grids are
    now bounded in bytes (GRID_CACHE_BYTES), and the template is built in place."""
    from features.sensor import grid

    out = subprocess.run([sys.executable, "-c", f"LIMIT_MB = {LIMIT_MB}\n" + FINE_STEPS], capture_output=True,
                         text=True, cwd=ROOT, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split("\n")[:6] == [f"{j} ok 0" for j in range(6)]
    inc = np.deg2rad(0.5) * (1 + np.arange(40) * 1e-3)
    for step in np.concatenate((inc, inc / 200)):  # 40 ordinary grids, then 40 of 0.0025 deg steps (4.6 MB each)
        grid.grid_constants(3, float(step), 4)
    kept = sum(grid.grid_bytes(g) for g in grid._GRIDS.values())
    assert 0 < kept <= grid.GRID_CACHE_BYTES == 8 << 20 and len(grid._GRIDS) <= grid.GRID_CACHE_SIZE
    g = grid.grid_constants(3, float(inc[-1] / 200), 4)  # a kept one is returned as kept
    assert g is grid.grid_constants(3, float(inc[-1] / 200), 4)


class _Stop(Exception):
    pass


def test_sim2real_keeps_only_the_scans_it_uses(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``--stride 100 --max-scans 1000`` on a 300-scan log uses 3 scans, but sim2real held all 300
    records until the simulation (every record between the scans used, for the odometry): memory
    grew with the log, up to stride x max-scans records. The motion limits still come from every
    record's odometry: the same as from the whole list."""
    import gc

    import sim
    from experiments import sim2real
    from lms200 import Record, read_log, write_log
    from sim import SensorConfig

    rng = np.random.default_rng(3)
    recs = [Record(Scan.lms200(2.0 + 0.01 * rng.standard_normal(361), stamp=0.1 * k),
                   odom=(0.05 * k, 0.01 * k, 0.02 * k + 0.01 * rng.standard_normal())) for k in range(300)]
    write_log(tmp_path / "log.clf", recs)
    del recs
    expected = sim2real.odometry_limits(np.array([(r.scan.stamp, *r.odom) for r in read_log(tmp_path / "log.clf")
                                                  if r.odom is not None],
                                                 dtype=float))
    seen: dict = {}

    def stop(*args, **kwargs):
        gc.collect()
        seen["scans"] = sum(type(o) is Scan for o in gc.get_objects())  # type(), not isinstance: a dead weakref.proxy raises ReferenceError
        seen["limits"] = kwargs["limits"]
        raise _Stop

    monkeypatch.setattr(sim, "simulate_records", stop)
    gc.collect()
    before = sum(type(o) is Scan for o in gc.get_objects())  # type(), not isinstance: a dead weakref.proxy raises ReferenceError
    with pytest.raises(_Stop), pytest.warns(LmsbenchWarning, match="only 3 real scans"):  # said before the work
        sim2real.sim2real(tmp_path / "log.clf", world="office", seeds=[1], stride=100, max_scans=1000,
                          sensor=SensorConfig())
    assert seen["scans"] - before <= 3, seen  # the 3 scans used (0, 100, 200); was 300
    assert seen["limits"] == expected
    assert 0.4 < expected.v_max < 0.6  # 0.05 m per 0.1 s of odometry
