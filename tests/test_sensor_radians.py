"""Issue #16: one angle unit in configs. An audit found ``sim.SensorConfig`` still held
``resolution_deg`` and ``beam_width_deg``, so every sensor YAML (calibrate, sim2real, the demo,
``--sensor``), sweep axis and resolved config beside results carried degrees. The fields are now
``resolution`` and ``beam_width`` in radians; files of the old spelling are read, converted, with
a one-line warning naming the file and the radians to write; both spellings in one file are
refused; the scans do not change by a bit."""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml

from lms200 import LmsbenchError
from lms200.errors import InputError, LmsbenchWarning
from sim import SensorConfig, make_world, simulate_records

RES_1DEG = 0.017453292519943295  # math.radians(1.0), as written to files
HALF_DEG = 0.008726646259971648  # math.radians(0.5)


def _scans(sensor: SensorConfig, world: str = "pillars", seed: int = 2) -> list:
    return simulate_records(make_world(world, seed), seed, 1.5, sensor)


def _same_scans(a: list, b: list) -> bool:
    return len(a) == len(b) and all(
        np.array_equal(x.scan.ranges, y.scan.ranges, equal_nan=True) and x.scan.angle_min == y.scan.angle_min
        and x.scan.angle_increment == y.scan.angle_increment and x.scan.stamp == y.scan.stamp
        and np.array_equal(x.scan.angles, y.scan.angles) for x, y in zip(a, b))


def _no_degrees(node: object, where: str = "") -> list[str]:
    """Every key of a YAML tree that ends in _deg (nothing written to a config is in degrees)."""
    if isinstance(node, dict):
        return [f"{where}{k}" for k in node if str(k).endswith("_deg")] + [
            hit for k, v in node.items() for hit in _no_degrees(v, f"{where}{k}.")]
    if isinstance(node, list):
        return [hit for v in node for hit in _no_degrees(v, where)]
    return []


def test_the_fields_are_radians_with_exact_defaults() -> None:
    s = SensorConfig()
    assert s.resolution == math.radians(0.5) == HALF_DEG and s.beam_width == math.radians(0.5)
    assert SensorConfig.lms200_1deg().resolution == math.radians(1.0)
    assert SensorConfig.lms200_quarter_deg().resolution == math.radians(0.25)
    assert s.angle_increment == s.resolution and s.fov_deg == 180.0 and s.resolution_deg == 0.5  # display only
    written = s.to_dict()
    assert "resolution" in written and "beam_width" in written and _no_degrees(written) == []


@pytest.mark.parametrize("preset", ["lms200_1deg", "__call__", "lms200_quarter_deg"])
def test_the_geometry_is_that_of_the_degree_arithmetic_to_the_bit(preset: str) -> None:
    """What main computed from resolution_deg: angle_min = -deg2rad((n-1) * deg) / 2, the beams'
    times i * deg / 360 of a turn; the radians config gives the same floats."""
    s = getattr(SensorConfig, preset)() if preset != "__call__" else SensorConfig()
    deg = {181: 1.0, 361: 0.5, 401: 0.25}[s.n_beams]
    assert s.angle_increment == float(np.deg2rad(deg))
    assert s.angle_min == -np.deg2rad((s.n_beams - 1) * deg) / 2
    assert np.array_equal(s.angles, -np.deg2rad((s.n_beams - 1) * deg) / 2 + np.arange(s.n_beams) * float(np.deg2rad(deg)))


def test_an_old_sensor_yaml_loads_with_a_warning_and_gives_the_same_scans(tmp_path: Path) -> None:
    old = tmp_path / "old.yaml"
    old.write_text("n_beams: 181\nresolution_deg: 1.0\nbeam_width_deg: 0.4\nunits: cm\n")
    new = tmp_path / "new.yaml"
    new.write_text(f"n_beams: 181\nresolution: {RES_1DEG!r}\nbeam_width: {math.radians(0.4)!r}\nunits: cm\n")
    with pytest.warns(LmsbenchWarning) as said:
        from_old = SensorConfig.from_yaml(old)
    assert [str(w.message) for w in said] == [
        f"{old}: resolution_deg: 1.0 (deg) is the old spelling, read as resolution: 0.017453292519943295 (rad); "
        "write `resolution: 0.017453292519943295` instead",
        f"{old}: beam_width_deg: 0.4 (deg) is the old spelling, read as beam_width: 0.006981317007977318 (rad); "
        "write `beam_width: 0.006981317007977318` instead"]
    with warnings.catch_warnings():
        warnings.simplefilter("error", LmsbenchWarning)  # the new spelling reads silently
        from_new = SensorConfig.from_yaml(new)
    assert from_old == from_new == SensorConfig.lms200_1deg(beam_width=math.radians(0.4), units="cm")
    assert _same_scans(_scans(from_old), _scans(from_new))
    # the value the warning says to write reads back to the same config
    advised = tmp_path / "advised.yaml"
    advised.write_text("n_beams: 181\nresolution: 0.017453292519943295\nbeam_width: 0.006981317007977318\nunits: cm\n")
    assert SensorConfig.from_yaml(advised) == from_old


def test_both_spellings_in_one_file_are_refused(tmp_path: Path) -> None:
    both = tmp_path / "both.yaml"
    both.write_text(f"resolution_deg: 1.0\nresolution: {RES_1DEG}\nn_beams: 181\n")
    with pytest.raises(InputError, match=rf"^{both}: gives both resolution_deg \(deg, the old spelling\) and "
                                         r"resolution \(rad\); give resolution only$"):
        SensorConfig.from_yaml(both)
    with pytest.raises(InputError, match="gives both beam_width_deg"):
        SensorConfig.from_dict({"beam_width_deg": 0.5, "beam_width": 0.01})
    with pytest.raises(InputError, match="gives both resolution_deg"):
        SensorConfig().replace(resolution_deg=1.0, resolution=RES_1DEG)


def test_degrees_given_as_radians_are_refused_with_the_hint(tmp_path: Path) -> None:
    """A file of the old spelling with the key renamed but the value kept (0.5, meant as degrees):
    29 deg a beam, refused, saying why."""
    f = tmp_path / "renamed.yaml"
    f.write_text("resolution: 0.5\n")
    with pytest.raises(LmsbenchError, match=r"^" + str(f) + r": resolution: must be in \[0.004363, 0.017453\] rad "
                                            r"\(0.25-1 deg, the LMS200's steps\), got 0.5 \(degrees given as radians\?\)$"):
        SensorConfig.from_yaml(f)
    # the bounds as the message writes them (6 decimals) are taken: 401 beams at 0.004363 rad
    assert SensorConfig(n_beams=401, resolution=0.004363).turns_per_scan == 4
    assert SensorConfig(n_beams=181, resolution=0.017453).fov_deg == pytest.approx(180.0, abs=0.01)
    with pytest.raises(InputError, match=r"^n_beams, resolution: field of view 180.028 deg exceeds 180 deg"):
        SensorConfig(n_beams=361, resolution=0.008728)  # 1.6 parts in 10^4 over 0.5 deg: not 0.5 deg written short
    with pytest.raises(InputError, match=r"^n_beams, resolution: field of view 181 deg exceeds 180 deg"):
        SensorConfig(n_beams=182, resolution=RES_1DEG)
    with pytest.raises(InputError, match=r"^beam_width: must be in \[0, 0.174533\] rad \(0-10 deg\), got 0.4 "
                                         r"\(degrees given as radians\?\)$"):
        SensorConfig(beam_width=0.4)


def test_an_old_simulate_folder_reruns_and_compares_with_one_line_warnings(tmp_path: Path, capsys) -> None:
    """A config.yaml written beside results before (sensor in degrees): `simulate --config` reruns
    it to the same scans and `compare` reads the folder, each saying the old spelling in one line;
    what they write holds radians."""
    from experiments.cli import main

    assert main(["simulate", "--duration", "1", "--resolution-deg", "1", "--out", str(tmp_path / "a"), "--quiet"]) == 0
    cfg = yaml.safe_load((tmp_path / "a" / "config.yaml").read_text())
    assert cfg["sensor"]["resolution"] == RES_1DEG and _no_degrees(cfg) == []
    cfg["sensor"]["resolution_deg"] = 1.0  # as main wrote it
    cfg["sensor"]["beam_width_deg"] = 0.5
    del cfg["sensor"]["resolution"], cfg["sensor"]["beam_width"]
    (tmp_path / "a" / "config.yaml").write_text(yaml.safe_dump(cfg, sort_keys=False))
    capsys.readouterr()
    assert main(["simulate", "--config", str(tmp_path / "a" / "config.yaml"), "--out", str(tmp_path / "b"),
                 "--quiet"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err == [f"lmsbench simulate: warning: {tmp_path / 'a' / 'config.yaml'}: sensor: resolution_deg: 1.0 (deg) "
                   "is the old spelling, read as resolution: 0.017453292519943295 (rad); write `resolution: "
                   "0.017453292519943295` instead",
                   f"lmsbench simulate: warning: {tmp_path / 'a' / 'config.yaml'}: sensor: beam_width_deg: 0.5 (deg) "
                   "is the old spelling, read as beam_width: 0.008726646259971648 (rad); write `beam_width: "
                   "0.008726646259971648` instead"]
    assert (tmp_path / "a" / "scans.clf").read_bytes() == (tmp_path / "b" / "scans.clf").read_bytes()
    assert _no_degrees(yaml.safe_load((tmp_path / "b" / "config.yaml").read_text())) == []
    assert main(["compare", str(tmp_path / "a"), "--methods", "iepf", "--out", str(tmp_path / "c")]) == 0
    err = capsys.readouterr().err
    assert "lmsbench compare: warning: " in err and "resolution_deg: 1.0 (deg) is the old spelling" in err
    written = yaml.safe_load((tmp_path / "c" / "config.yaml").read_text())
    assert _no_degrees(written) == [] and repr(RES_1DEG) in str(written)


def test_an_old_sweep_axis_runs_converted_with_one_warning_naming_the_file(tmp_path: Path) -> None:
    from experiments.evaluate import sensor_config
    from experiments.sweep.spec import SweepSpecError, load_sweep

    f = tmp_path / "old.yaml"
    f.write_text('name: old\nkind: extract\ngrid:\n  "sensor.resolution_deg,sensor.n_beams": [[0.5, 361], [1.0, 181]]\n')
    with pytest.warns(LmsbenchWarning) as said:
        spec = load_sweep(f)
    assert [str(w.message) for w in said] == [
        f"{f}: sensor.resolution_deg (deg) is the old spelling of sensor.resolution (rad); read, each value converted; "
        "write sensor.resolution with the values in radians (0.5 deg = 0.008726646259971648, 1 deg = "
        "0.017453292519943295) instead"]
    cells = spec.cells()
    assert [c["sensor.resolution_deg"] for c in cells] == [0.5, 1.0]  # the cells keep their names: a sweep resumes
    with pytest.warns(LmsbenchWarning):
        built = sensor_config({"resolution_deg": 1.0, "n_beams": 181})
    assert built == SensorConfig.lms200_1deg(interlaced=False)
    f.write_text("name: old\nkind: extract\nfixed: {sensor.resolution: 0.0175}\ngrid:\n  sensor.resolution_deg: [1.0]\n")
    with pytest.raises(SweepSpecError, match=rf"^{f}: gives both sensor.resolution_deg \(deg, the old spelling\) and "
                                             r"sensor.resolution \(rad\); give sensor.resolution only$"):
        load_sweep(f)


def test_the_resolution_sweep_varies_radians_and_draws_degrees() -> None:
    from experiments.style import label_of, shown
    from experiments.sweep.spec import load_sweep

    root = Path(__file__).resolve().parents[1]
    with warnings.catch_warnings():
        warnings.simplefilter("error", LmsbenchWarning)
        spec = load_sweep(root / "sweeps" / "extractors_vs_resolution.yaml")
    values = sorted({c["sensor.resolution"] for c in spec.cells()})
    assert values == [math.radians(0.25), math.radians(0.5), math.radians(1.0)]
    assert list(shown("sensor.resolution", np.array(values))) == [0.25, 0.5, 1.0]
    assert label_of("sensor.resolution") == "angular resolution (deg)"
    assert shown("sensor.noise_sigma", 0.01) == 0.01


def test_calibrate_writes_radians_that_read_back_to_an_equal_config(tmp_path: Path) -> None:
    from lms200.carmen import write_carmen

    from experiments.calibrate import calibrate_log, write_sensor_yaml

    truth = SensorConfig.lms200_1deg(units="cm", noise_sigma=0.008, beam_width=math.radians(0.5))
    write_carmen(tmp_path / "log.clf", simulate_records("office", seed=3, duration=12.0, sensor=truth, rate_hz=4.0))
    result = calibrate_log(tmp_path / "log.clf", fit_duration=2.0)
    out = tmp_path / "sensor.yaml"
    write_sensor_yaml(result, out, "log.clf")
    raw = yaml.safe_load(out.read_text())
    assert _no_degrees(raw) == [], out.read_text()
    assert raw["resolution"] == RES_1DEG and 0 < raw["beam_width"] <= 2 * RES_1DEG  # at most 2 beam steps, rad
    assert "simulated_mixed_share_by_beam_width" in raw["calibration"]
    with warnings.catch_warnings():
        warnings.simplefilter("error", LmsbenchWarning)
        back = SensorConfig.from_yaml(out)
    assert back == result.sensor
    # the fitted width is the degree grid's, rounded to 1e-4 deg as before, in radians
    assert round(math.degrees(back.beam_width), 4) == pytest.approx(math.degrees(back.beam_width), abs=1e-9)


def test_half_a_degree_written_to_6_decimals_spans_180_deg_and_is_taken(tmp_path: Path) -> None:
    """`resolution: 0.008727` (0.5 deg to the 6 decimals the bounds' message shows) over 361 beams
    was refused, "field of view 180.007 deg exceeds 180 deg": f33cca8 loosened the bounds by 1 part
    in 10^4, not the field of view. Found by the session's review. It is simulated as written; the
    exact step's scans do not change by a bit."""
    f = tmp_path / "s.yaml"
    f.write_text("n_beams: 361\nresolution: 0.008727\n")
    short = SensorConfig.from_yaml(f)
    assert short.resolution == 0.008727 and short.fov_deg == pytest.approx(180.0073, abs=1e-4)
    assert short.angle_increment == 0.008727 and short.turns_per_scan == 2 and short.angles[-1] > math.pi / 2
    assert len(_scans(short)[0].scan) == 361
    exact = SensorConfig(n_beams=361, resolution=HALF_DEG)
    assert exact.angle_min == -math.pi / 2 and np.array_equal(exact.angles, -np.deg2rad(180.0) / 2 + np.arange(361) * HALF_DEG)
    assert _same_scans(_scans(exact), _scans(SensorConfig()))
    assert not _same_scans(_scans(short), _scans(exact))  # as written, not snapped to 0.5 deg


def test_a_sweeps_old_sensor_file_is_warned_of_once(tmp_path: Path) -> None:
    """`lmsbench sweep` checked the spec before compiling the kernels and run_sweep checked it
    again, each reading the sensor_file: every old-spelling warning was said twice. Found by the
    session's review."""
    import os
    import subprocess
    import sys

    old = tmp_path / "OLD.yaml"
    old.write_text("resolution_deg: 0.5\nbeam_width_deg: 0.4\n")
    sweep = tmp_path / "sf.yaml"
    sweep.write_text(f"name: sf\nkind: extract\nfixed: {{sensor_file: {old}, duration: 1.0}}\ngrid: {{method: [sensor]}}\n")
    root = Path(__file__).resolve().parents[1]
    run = subprocess.run([sys.executable, "-m", "experiments.cli", "sweep", str(sweep), "--inprocess", "--quiet",
                          "--out", str(tmp_path / "out")], env={**os.environ, "PYTHONPATH": str(root)}, cwd=tmp_path,
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    assert run.stderr.splitlines() == [
        f"lmsbench sweep: warning: {old}: resolution_deg: 0.5 (deg) is the old spelling, read as resolution: "
        f"{HALF_DEG!r} (rad); write `resolution: {HALF_DEG!r}` instead",
        f"lmsbench sweep: warning: {old}: beam_width_deg: 0.4 (deg) is the old spelling, read as beam_width: "
        "0.006981317007977318 (rad); write `beam_width: 0.006981317007977318` instead"]
    assert "sf: 1 cells, 1 computed" in run.stdout


@pytest.mark.parametrize("argv", [["simulate", "--sensor", "{old}", "--rate-hz", "1e9", "--out", "{out}"],
                                  ["compare", "office", "--sensor", "{old}", "--rate", "1e9", "--out", "{out}"],
                                  ["sim2real", "{log}", "--sensor", "{old}", "--rate-hz", "1e9", "--out", "{out}"]])
def test_an_option_refused_after_an_old_sensor_yaml_is_read_is_its_error_alone(tmp_path: Path, capsys, argv) -> None:
    """The rate is checked against the sensor file's step, so after the file is read: its old spelling's
    warning came first, then the rate's error (a user error is one line). The checks' warnings are held
    (options.warnings_after_checks) and said once they pass; a refused run says its error alone."""
    from experiments.cli import main
    from lms200 import Record, Scan, write_log

    old = tmp_path / "old.yaml"
    old.write_text("resolution_deg: 1.0\nn_beams: 181\n")
    log = tmp_path / "run.clf"
    write_log(log, [Record(Scan(np.full(181, 2.0), -np.pi / 2, np.pi / 180, 0.0, 8.183, stamp=float(k))) for k in range(3)])
    status = main([a.format(old=old, out=tmp_path / "out", log=log) for a in argv])
    err = capsys.readouterr().err.splitlines()
    assert (status, len(err)) == (2, 1) and "1e+09 scans/s is more than the sensor gives" in err[0], err


def test_the_checks_hold_the_showing_of_warnings_not_the_filters() -> None:
    """A user's cell module that silences its own warnings when a check imports it kept them silenced
    before options.warnings_after_checks; the first version (catch_warnings) put the filters back."""
    import warnings

    from experiments.options import warnings_after_checks

    with warnings.catch_warnings():  # this test's own: the filters and showwarning put back after it
        warnings.simplefilter("always")
        shown: list[str] = []
        warnings.showwarning = lambda message, *_: shown.append(str(message))
        with warnings_after_checks():
            warnings.warn("held until the checks pass")
            warnings.filterwarnings("ignore", message="noisy")  # as a cell module's import does
            assert shown == []
        assert shown == ["held until the checks pass"]
        warnings.warn("noisy thing")
        assert shown == ["held until the checks pass"]
        try:
            with warnings_after_checks():
                warnings.warn("the run it refused")
                raise ValueError("a check failed")
        except ValueError:
            pass
        assert shown == ["held until the checks pass"]  # a refused run says its error alone
