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
                         anchor_stamped: bool = False, t0: float = 100.0, rear: bool = False,
                         bad_line: int | None = None, cut_after: int | None = None, lead: bool = True,
                         sparse: bool = False) -> tuple:
    """A corrected log as Radish writes them: FLASER at the corrected pose, its ODOM anchor (a junk
    stamp), then three ODOM lines of raw odometry from that anchor, the last at the next scan.
    ``rear``: each FLASER's anchor is followed by an RLASER line at the pose turned by pi and its
    anchor, from which the ODOM lines then go on; ``bad_line``: that FLASER line is malformed (its
    anchor stays); ``cut_after``: the log ends right after that scan's FLASER line; ``lead``: an ODOM
    line before the first scan (else the log begins with that scan's FLASER line); ``sparse``: no raw
    odometry after the even-numbered scans (their anchors stay)."""
    corrected, raw = _trajectories(n)
    lines = ["# a Radish-style corrected log", "PARAM robot_frontlaser_offset 0.0 host 0"]
    if lead:  # odometry before the first scan, as Intel and ACES have
        lines.append(f"ODOM 0 0 0 0 0 0 {t0 - 0.05:.4f} host 0")
    for k in range(n):
        t = t0 + 2.5 * k
        x, y, th = corrected[k]
        ranges = " ".join(f"{r:.3f}" for r in _ranges(corrected[k]))
        count = "x" if k == bad_line else BEAMS
        lines.append(f"FLASER {count} {ranges} {x:.6f} {y:.6f} {th:.6f} {x:.6f} {y:.6f} {th:.6f} {t:.4f} host {t:.4f}")
        if k == cut_after:
            break
        origin = _matrix(corrected[k])
        if anchors and k != drop_anchor:
            stamp = f"{t:.4f}" if anchor_stamped else "1.08499e-42"  # stamped with the scan: a real ODOM line
            lines.append(f"ODOM {x:.6f} {y:.6f} {th:.6f} 0 0 0 {stamp} host 0")
        if rear:
            rx, ry, rth = _pose(origin @ _matrix((0.0, 0.0, math.pi)))
            lines.append(f"RLASER {BEAMS} {ranges} {rx:.6f} {ry:.6f} {rth:.6f} {rx:.6f} {ry:.6f} {rth:.6f} "
                         f"{t:.4f} host {t:.4f}")
            lines.append(f"ODOM {rx:.6f} {ry:.6f} {rth:.6f} 0 0 0 0 host 0")
            origin = _matrix((float(f"{rx:.6f}"), float(f"{ry:.6f}"), float(f"{rth:.6f}")))
        if k + 1 < n and not (sparse and k % 2 == 0):
            start = np.linalg.inv(raw[k])
            for j, f in enumerate((0.3, 0.7, 1.0)):  # raw odometry samples towards the next scan
                step = start @ raw[k + 1]
                part = _matrix((f * step[0, 2], f * step[1, 2], f * math.atan2(step[1, 0], step[0, 0])))
                ox, oy, oth = _pose(origin @ part)
                ts = t + 2.5 * f
                lines.append(f"ODOM {ox:.9f} {oy:.9f} {oth:.9f} 0.4 0 0 {ts:.4f} host {ts:.4f}")
    path.write_text("\n".join(lines) + "\n")
    return corrected, raw


def _dead_reckoning(n: int, keep=None) -> np.ndarray:
    """The raw odometry of ``_trajectories(n)``, computed independently: dead reckoning in the frame
    where it starts at the first scan's corrected pose (``keep``: the scans read)."""
    corrected, raw = _trajectories(n)
    poses = np.array([_pose(_matrix(corrected[0]) @ np.linalg.inv(raw[0]) @ raw[k]) for k in range(n)])
    return poses if keep is None else poses[keep]


def _assert_odometry(recs, expected: np.ndarray) -> None:
    got = np.array([r.odom for r in recs])
    np.testing.assert_allclose(got[:, :2], expected[:, :2], atol=2e-5)  # the log's 6-9 digits
    np.testing.assert_allclose(np.angle(np.exp(1j * (got[:, 2] - expected[:, 2]))), 0, atol=2e-5)


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


def test_a_corrected_log_with_sparse_odometry_is_read_corrected(tmp_path):
    """A review: two anchors with no ODOM step between them handed both scans back as read, and the
    chain waited for the next anchored scan, so chains started only in pairs: a corrected log with
    no raw ODOM line after every other scan (Intel's log so cut: 0 of 910 scans corrected, before
    the ODOM-step rule 910) read entirely raw. The second scan now starts a chain."""
    corrected, _ = _trajectories(12)
    _write_corrected_log(tmp_path / "sparse-corrected.log", 12, sparse=True)
    recs = list(read_log(tmp_path / "sparse-corrected.log"))
    assert len(recs) == 12
    assert [r.corrected is not None for r in recs] == [k >= 1 for k in range(12)]  # old: all False
    assert recs[0].odom == pytest.approx(np.round(corrected[0], 6))  # as read: its pose fields
    assert recs[1].odom == pytest.approx(np.round(corrected[1], 6))  # the chain starts at its own pose
    np.testing.assert_allclose([r.corrected for r in recs[1:]], np.round(corrected, 6)[1:], atol=1e-12)
    # no raw odometry after scan 2: the odometry stands still to scan 3, and goes on from there
    assert recs[3].odom == pytest.approx(recs[2].odom)
    assert recs[2].odom != pytest.approx(recs[2].corrected, abs=1e-4)


def test_a_damaged_corrected_log_keeps_its_chain_and_a_raw_log_is_read_as_before(tmp_path):
    """A review: one anchor missing (a cut log, a damaged anchor skipped) handed its scan back as
    read, its pose fields as odometry: a 22-29 m jump in Intel's odometry, and slam lost its score
    (every scan needs a corrected pose); a malformed FLASER line's anchor, or a rear laser's,
    was read as a step of the odometry (0.26 m off by the end). Now a running chain (two anchors in a row) takes a missing anchor as read
    and moves to another line's anchor; the raw odometry is the same dead reckoning throughout."""
    corrected, _ = _trajectories(12)
    expected = _dead_reckoning(12)
    cases = {"missing.log": ({"drop_anchor": 5}, range(12)), "rear.log": ({"rear": True}, range(12)),
             "cut.log": ({"cut_after": 7}, range(8)),
             "bad.log": ({"bad_line": 4}, [k for k in range(12) if k != 4])}
    for name, (options, keep) in cases.items():
        _write_corrected_log(tmp_path / name, 12, **options)
        recs = list(read_log(tmp_path / name, skip_bad_lines=True))
        assert [r.corrected is not None for r in recs] == [True] * len(keep), name
        np.testing.assert_allclose([r.corrected for r in recs], np.round(corrected, 6)[list(keep)], atol=1e-12)
        _assert_odometry(recs, expected[list(keep)])
    # before two anchors in a row the chain does not run: a second scan without its anchor is read as
    # written, and so is the first (one anchor is no chain), and the chain starts again at the next anchor
    _write_corrected_log(tmp_path / "second.log", 12, drop_anchor=1)
    recs = list(read_log(tmp_path / "second.log"))
    assert [r.corrected is not None for r in recs] == [k >= 2 for k in range(12)]
    assert recs[0].odom == pytest.approx(np.round(corrected[0], 6))  # as read: its pose fields
    assert recs[1].odom == pytest.approx(np.round(corrected[1], 6))  # as read: its pose fields
    assert recs[2].odom == pytest.approx(np.round(corrected[2], 6))  # a new chain starts at its own pose
    for name, options in (("plain.log", {"anchors": False}), ("standing.log", {"anchor_stamped": True})):
        # CARMEN's usual log: ODOM lines are odometry, and one at a scan's pose, stamped with it, is a
        # robot standing still, not an anchor
        _write_corrected_log(tmp_path / name, 12, **options)
        recs = list(read_log(tmp_path / name))
        assert all(r.corrected is None for r in recs), name
        np.testing.assert_allclose([r.odom for r in recs], np.round(corrected, 6), atol=1e-12)


def test_a_corrected_log_that_begins_with_a_scan_is_corrected_from_it(tmp_path):
    """A corrected log whose first line is a laser line (Intel or ACES cut before a scan) read its
    first anchor as a step of the odometry: no ODOM step had yet given the clock its junk stamp is
    judged by, so the first scan had no corrected pose and `slam` scored none of the run (every scan
    needs one; a review). The line at the first scan's pose is now its anchor when its stamp lies
    more than 10 s before both the next ODOM line's and the scan's own; raw logs that begin with a
    laser line, an ODOM line at its pose after it, still read as written."""
    corrected, _ = _trajectories(12)
    _write_corrected_log(tmp_path / "cut-corrected.log", 12, lead=False)
    recs = list(read_log(tmp_path / "cut-corrected.log"))
    assert [r.corrected is not None for r in recs] == [True] * 12
    np.testing.assert_allclose([r.corrected for r in recs], np.round(corrected, 6), atol=1e-12)
    _assert_odometry(recs, _dead_reckoning(12))
    for name, options in (("plain.log", {"anchors": False}), ("standing.log", {"anchor_stamped": True})):
        _write_corrected_log(tmp_path / name, 12, lead=False, **options)
        recs = list(read_log(tmp_path / name))
        assert all(r.corrected is None for r in recs), name
        np.testing.assert_allclose([r.odom for r in recs], np.round(corrected, 6), atol=1e-12)
    ranges = " ".join(["2.00"] * BEAMS)
    for name, laser_t, first_odom_t, next_odom_t in (("laser clock 15 s ahead", 115.0, 100.0, 100.1),
                                                     ("15 s gap in the odometry", 100.0, 100.0, 115.0)):
        # a robot standing at (0, 0, 0): its first ODOM line is at the scan's pose, and its stamp lies
        # 15 s before one of the two clocks but not the other
        lines = [f"FLASER {BEAMS} {ranges} 0 0 0 0 0 0 {laser_t} host {laser_t}", f"ODOM 0 0 0 0 0 0 {first_odom_t} host 0",
                 f"ODOM 0.1 0 0 0 0 0 {next_odom_t} host 0",
                 f"FLASER {BEAMS} {ranges} 0.1 0 0 0.1 0 0 {laser_t + 0.2} host {laser_t + 0.2}",
                 f"ODOM 0.1 0 0 0 0 0 {next_odom_t + 0.2} host 0"]
        (tmp_path / "raw.log").write_text("\n".join(lines) + "\n")
        recs = list(read_log(tmp_path / "raw.log"))
        assert [(r.odom, r.corrected) for r in recs] == [((0.0, 0.0, 0.0), None), ((0.1, 0.0, 0.0), None)], name


@pytest.mark.parametrize("odom_stamp", ["skew 1.5", "skew 15", "zero"])
def test_a_raw_log_whose_clocks_disagree_is_no_corrected_log(tmp_path, odom_stamp):
    """Reviews: a raw FLASER + ODOM log of two hosts, the laser's clock 1.5 s ahead and the robot
    standing still, had the ODOM line after each standing scan (at its pose, 1.5 s "before" it) taken
    for an anchor (50 of 100 scans 'corrected'); with the clock 15 s ahead, or ODOM lines all stamped
    0 (a converter), every scan was 'corrected' and the odometry froze at its first pose (x 0 to the
    end against 2.94 m). An anchor's stamp is now judged by the odometry's own clock."""
    lines = []
    for k in range(100):
        t = 100.0 + 0.2 * k
        x = 0.01 * (k // 2) + (0.0 if k < 10 else 0.3 * (k - 10) / 10)  # standing still at first
        ranges = " ".join(["2.00"] * BEAMS)
        laser_t = t + (15.0 if odom_stamp == "skew 15" else 1.5)
        lines.append(f"FLASER {BEAMS} {ranges} {x} 0 0 {x} 0 0 {laser_t:.3f} host {laser_t:.3f}")
        o = 0.0 if odom_stamp == "zero" else t
        lines.append(f"ODOM {x} 0 0 0 0 0 {o:.3f} host {o:.3f}")
    (tmp_path / "raw.log").write_text("\n".join(lines) + "\n")
    recs = list(read_log(tmp_path / "raw.log"))
    assert len(recs) == 100 and all(r.corrected is None for r in recs)
    assert [r.odom[0] for r in recs] == [float(line.split()[BEAMS + 5]) for line in lines[::2]]  # as written


def test_overlapping_passes_each_keep_their_held_record(tmp_path):
    """A review: the record a pass holds for the next line was kept on the reader, so a second pass
    started meanwhile took its place and the first pass lost it before a bad line's error."""
    from lms200 import LogFormatError

    _write_corrected_log(tmp_path / "c.log", 6, bad_line=3)
    reader = read_log(tmp_path / "c.log")
    first, second = iter(reader), iter(reader)
    got = [next(first).scan.stamp, next(first).scan.stamp]
    next(second)
    with pytest.raises(LogFormatError):
        while True:
            got.append(next(first).scan.stamp)
    assert got == [100.0, 102.5, 105.0]


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
    stamps = 100.0 + 2.5 * np.arange(40)
    odometry = np.array([_pose(_matrix(corrected[0]) @ np.linalg.inv(raw[0]) @ raw[k]) for k in range(40)])
    reference = np.column_stack((stamps, np.round(corrected, 6)))
    expected = ate(np.column_stack((stamps, odometry)), reference).rmse
    assert rows["raw odometry"]["ate_rmse"] == pytest.approx(expected, abs=1e-4)
    assert rows["raw odometry"]["ate_rmse"] > 0.02  # before: 0 (the reference itself)


@pytest.mark.shared_data
@pytest.mark.parametrize("name", ["intel-corrected.log.gz", "aces-corrected.log.gz"])
def test_the_real_corrected_logs_cut_before_their_first_scan_read_the_same(shared_data, tmp_path, name):
    """Intel and ACES from their first laser line on (their ODOM lines before it dropped): the same
    records, corrected from the first scan on; before, the first scan had no corrected pose."""
    import gzip

    full = list(read_log(shared_data / name))
    with gzip.open(shared_data / name, "rt") as fh:
        lines = fh.readlines()
    first = next(i for i, line in enumerate(lines) if line.startswith("FLASER"))
    assert any(line.startswith("ODOM") for line in lines[:first])
    (tmp_path / "cut.log").write_text("".join(lines[first:]))
    recs = list(read_log(tmp_path / "cut.log"))
    assert [(r.scan.stamp, r.odom, r.corrected) for r in recs] == [(r.scan.stamp, r.odom, r.corrected) for r in full]
    assert recs[0].corrected is not None


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


@pytest.mark.parametrize("jumped", ["both clocks", "odometry clock"])
def test_a_raw_log_whose_clock_jumps_back_while_the_robot_stands_is_no_corrected_log(tmp_path, capsys, jumped):
    """Found by fuzzing: a raw FLASER + ODOM log whose clock jumped back 100 s (two runs joined, a
    clock set back) while the robot stood still had every later ODOM line junk by the odometry's
    clock, and the one at a standing scan's pose was taken for its anchor: 51 of 100 scans were read
    as a corrected log's (pose fields as corrected poses) and their odometry froze at x 4.75 m (3 m
    off at the end). An anchor's stamp must also lie ANCHOR_STAMP_GAP_S before its laser line's own
    (21 s or more in Intel and ACES). The scan just before the jump still found its "anchor" (the
    first ODOM line after the jump, at its pose, 100 s before it by both clocks) and read as corrected,
    `info` saying "corrected poses 1 scans": a chain's first anchored scan is now held until a second
    anchor in a row confirms the chain, and read as written when none does. With the odometry host's
    clock alone set back (two hosts), every ODOM line after the jump lay 100 s before both clocks, the
    one after each standing scan at its pose: a chain ran, 51 scans "corrected", the odometry frozen at
    4.75 m (7.75 m at the end). A chain is now confirmed only with an ODOM step on the odometry's own
    clock between its first two anchors, as a corrected log has (at least two in Intel's and ACES's)."""
    lines, x = [], 0.0
    ranges = " ".join(["2.00"] * BEAMS)
    for k in range(200):
        x += 0.0 if 95 <= k < 140 else 0.05
        t = 1000.0 + 0.1 * k - (100.0 if k >= 100 else 0.0)
        t_laser = t if jumped == "both clocks" else 1000.0 + 0.1 * k
        lines.append(f"ODOM {x:.3f} 0 0 0 0 0 {t:.3f} h {t:.3f}")
        if k % 2:
            lines.append(f"FLASER {BEAMS} {ranges} {x:.3f} 0 0 {x:.3f} 0 0 {t_laser + 0.01:.3f} h {t_laser + 0.01:.3f}")
    (tmp_path / "joined.log").write_text("\n".join(lines) + "\n")
    recs = list(read_log(tmp_path / "joined.log"))
    fields = [float(line.split()[BEAMS + 5]) for line in lines if line.startswith("FLASER")]
    assert len(recs) == 100 and [r.odom[0] for r in recs] == fields  # old: 4.75 from scan 48 on
    anchored = [k for k, r in enumerate(recs) if r.corrected is not None]
    assert anchored == []  # both clocks, older: 51 scans, 49 to 99; old: [49]. odometry clock, old: 49 to 99
    from experiments.cli import main

    assert main(["info", str(tmp_path / "joined.log")]) == 0
    out = capsys.readouterr().out
    assert "corrected poses" not in out  # old: "corrected poses 1 scans" (odometry clock: 51 scans)
    assert "  odometry        yes\n" in out  # old: "yes (raw: the ODOM lines between scans, chained)"
