"""Poses no log holds, which the CARMEN reader took (a fuzzing round): a FLASER line's poses of 1e308 m
(`compare --poses corrected` scored such a log's repeatability 0, exit 0) and an ODOM line of nan
(chained into the scans' odometry). Each is a malformed line, as the TUM and relations readers refuse
x or y beyond 1e9 m (lms200.logs.MAX_COORD_M)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from lms200 import LogFormatError, read_log


def _flaser(t: float, pose: str = "0 0 0", odom: str = "0 0 0") -> str:
    return f"FLASER 3 1 2 3 {pose} {odom} {t} h {t}\n"


@pytest.mark.parametrize("lines, message", [
    ([_flaser(1.0), _flaser(2.0, pose="1e308 0 0")],
     "2: malformed FLASER line: FLASER laser pose (1e+308, 0) m lies beyond +-1e+09 m (damaged, or not metres?)"),
    ([_flaser(1.0, odom="0 -2e9 0")],
     "1: malformed FLASER line: FLASER odometry pose (0, -2e+09) m lies beyond +-1e+09 m (damaged, or not metres?)"),
    (["ODOM nan 0 0 0 0 0 1.0 h 1.0\n", _flaser(2.0)], "1: malformed ODOM line: ODOM pose is not finite"),
    (["TRUEPOS 0 1e10 0 0 0 0 1.0 h 1.0\n", _flaser(1.0)],
     "1: malformed TRUEPOS line: TRUEPOS pose (0, 1e+10) m lies beyond +-1e+09 m (damaged, or not metres?)"),
    ([_flaser(1.0), _flaser(2.0, odom="0 0 1e300")],  # fuzz4: read as it was, every odometry turn from it noise
     "2: malformed FLASER line: FLASER odometry pose's heading 1e+300 rad lies beyond +-1e+06 rad (damaged? wrap it into (-pi, pi])"),
    (["ODOM 0 0 -2e6 0 0 0 1.0 h 1.0\n", _flaser(2.0)],
     "1: malformed ODOM line: ODOM pose's heading -2e+06 rad lies beyond +-1e+06 rad (damaged? wrap it into (-pi, pi])"),
])
def test_a_carmen_pose_beyond_1e9_m_or_not_finite_is_a_malformed_line(tmp_path: Path, lines, message) -> None:
    log = tmp_path / "a.log"
    log.write_text("".join(lines))
    with pytest.raises(LogFormatError) as err:  # old: read, 1e308 m and nan as poses
        list(read_log(log))
    assert str(err.value).startswith(f"{log}:{message}")
    assert len(list(read_log(log, skip_bad_lines=True))) == sum(line.startswith("FLASER") for line in lines) - (
        "FLASER" in message)
    ok = tmp_path / "ok.log"
    ok.write_text(_flaser(1.0, odom="1e9 -1e9 0"))
    assert [r.odom for r in read_log(ok)] == [(1e9, -1e9, 0.0)]  # the bound itself is a pose


def test_compare_refuses_a_log_of_a_pose_at_1e308_m(tmp_path: Path, capsys) -> None:
    from experiments.cli import main

    log = tmp_path / "far.log"
    log.write_text("".join(_flaser(float(k), pose=f"{1e308 if k == 3 else 0} 0 0") for k in range(1, 6)))
    assert main(["compare", str(log), "--poses", "corrected", "--methods", "sensor", "--sigma", "0.01",
                 "--out", str(tmp_path / "o"),
                 "--no-progress"]) == 2  # old: 0, repeatability 0
    assert capsys.readouterr().err == (f"lmsbench compare: error: {log}:3: malformed FLASER line: FLASER laser pose "
                                       "(1e+308, 0) m lies beyond +-1e+09 m (damaged, or not metres?) (--skip-bad-lines skips "
                                       "malformed lines, each reported)\n")


@pytest.mark.parametrize("which", ["odom", "truth"])
def test_write_carmen_refuses_a_pose_its_reader_refuses(tmp_path: Path, which: str) -> None:
    """write_carmen wrote an odometry or truth pose of 2e9 m, which read_log then refused as a malformed
    line: the log could not be read back (it already refuses such stamps, ranges and steps)."""
    from lms200 import InputError, Record, Scan
    from lms200.carmen import write_carmen

    scan = Scan.lms200([1.0] * 361, stamp=1.0)
    far = (2e9, 0.0, 0.0)
    records = [Record(scan, odom=(0.0, 0.0, 0.0), truth=(0.0, 0.0, 0.0)),
               Record(scan.replace(stamp=2.0), **{"odom": (0.0, 0.0, 0.0), "truth": (0.0, 0.0, 0.0), which: far})]
    with pytest.raises(InputError) as err:
        write_carmen(tmp_path / "a.log", records)
    assert str(err.value) == (f"records: item 1: {which} pose (2e+09, 0) m lies beyond +-1e+09 m (damaged, or not metres?), which the CARMEN "
                              "reader refuses (the log could not be read back)")
    turned = [Record(scan, **{"odom": (0.0, 0.0, 0.0), "truth": (0.0, 0.0, 0.0), which: (0.0, 0.0, 1e300)})]
    with pytest.raises(InputError, match=rf"^records: item 0: {which} pose's heading 1e\+300 rad lies beyond \+-1e\+06 rad"):
        write_carmen(tmp_path / "c.log", turned)
    edge = [Record(scan, odom=(1e9, -1e9, 1e6), truth=(-1e9, 1e9, -1e6))]
    assert write_carmen(tmp_path / "b.log", edge) == 1
    assert [(r.odom, r.truth) for r in read_log(tmp_path / "b.log")] == [((1e9, -1e9, 1e6), (-1e9, 1e9, -1e6))]


def test_the_bag_and_tum_writers_refuse_a_heading_that_holds_no_angle(tmp_path: Path) -> None:
    """fuzz4: a heading of 1e300 rad was written as the quaternion of its noise, which read back as a
    heading no one gave; as write_carmen, write_bag and write_tum refuse it (1e6 rad, the bound, is written)."""
    from lms200 import InputError, Record, Scan, write_log, write_tum

    scan = Scan.lms200([1.0] * 361, stamp=1.0)
    with pytest.raises(InputError, match=r"^records: item 0: odom pose's heading 1e\+300 rad lies beyond \+-1e\+06 rad"):
        write_log(tmp_path / "a.bag", [Record(scan, odom=(0.0, 0.0, 1e300))])
    assert not (tmp_path / "a.bag").exists()
    with pytest.raises(InputError, match=r"^poses: row 1: pose's heading -1e\+300 rad lies beyond \+-1e\+06 rad"):
        write_tum(tmp_path / "a.tum", [0.0, 1.0], [[0.0, 0.0, 0.0], [0.0, 0.0, -1e300]])
    write_tum(tmp_path / "b.tum", [0.0, 1.0], [[0.0, 0.0, float("nan")], [0.0, 0.0, 1e6]])  # a lost pose, the bound
    assert (tmp_path / "b.tum").read_text().count("\n") == 3


def test_every_pose_bound_check_words_it_alike_with_its_place(tmp_path: Path) -> None:
    """The x, y and heading bounds were checked in nine places in seven wordings ("x or y is beyond",
    "position (x, y) =", "row 1's heading", "roll, pitch or yaw is beyond", ...): one helper
    (lms200.records.pose_problem / poses_problem) words them now, each place adding where (file and line,
    item or row) and what refuses it."""
    import numpy as np

    from lms200 import InputError, LmsbenchError, Record, Scan, write_log, write_tum
    from slam.metrics import ate, read_relations
    from slam.run import in_scale

    far = "(2e+09, 0) m lies beyond +-1e+09 m (damaged, or not metres?)"
    turned = "'s heading 1e+300 rad lies beyond +-1e+06 rad (damaged? wrap it into (-pi, pi])"
    scan = Scan.lms200([1.0] * 361, stamp=1.0)
    truth = np.array([[0.0, 0.0, 0.0, 0.0], [1.0, 1.0, 0.0, 0.0]])
    for pose, words in (((2e9, 0.0, 0.0), f"odom pose {far}"), ((0.0, 0.0, 1e300), f"odom pose{turned}")):
        for name in ("a.log", "a.bag"):
            with pytest.raises(InputError, match="^" + re.escape(f"records: item 0: {words}, which the ")):
                write_log(tmp_path / name, [Record(scan, odom=pose)])
        with pytest.raises(LmsbenchError, match="^" + re.escape(f"records[0]: its {words}: SLAM's models")):
            list(in_scale([Record(scan, odom=pose)]))
        with pytest.raises(InputError, match="^" + re.escape(f"poses: row 1: {words[5:]}, which read_tum refuses")):
            write_tum(tmp_path / "a.tum", [0.0, 1.0], [[0.0, 0.0, 0.0], pose])
        est = truth.copy()
        est[1, 1:] = pose
        with pytest.raises(InputError, match="^" + re.escape(f"estimate: row 1: {words[5:]}") + "$"):
            ate(est, truth)
        log = tmp_path / "b.log"
        log.write_text(_flaser(1.0, odom=" ".join(map(repr, pose))))
        with pytest.raises(LogFormatError, match="^" + re.escape(f"{log}:1: malformed FLASER line: FLASER odometry {words[5:]}")):
            list(read_log(log))
        rel = tmp_path / "r.relations"
        rel.write_text(f"1 2 {pose[0]!r} {pose[1]!r} 0 0 0 {pose[2]!r}\n")
        said = f"relation row's motion{words[9:]}".replace("motion's heading", "yaw")  # a relation's heading is its yaw
        with pytest.raises(LogFormatError, match="^" + re.escape(f"{rel}:1: {said}") + "$"):
            read_relations(rel)
