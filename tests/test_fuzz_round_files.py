"""Bad input found by a fuzz round over YAML files, output locations, inputs, interrupts and the
environment (2026-12-06). Each test failed on the code before its fix."""

from __future__ import annotations

from pathlib import Path

import pytest

from experiments.sweep.spec import SweepSpecError, load_sweep
from lms200 import LmsbenchError
from slam.config import SlamConfig, SlamConfigError


# YAML keys may be null, numbers or true/false: with two or more unknown keys, one of them not text,
# sorting them for the message raised TypeError ('<' not supported between 'NoneType' and 'str'), an
# internal error: `lmsbench slam RUN --config C` and `lmsbench sweep F` with `~: 1` beside a misspelt key.

def test_a_slam_config_of_a_null_key_beside_an_unknown_one_names_both() -> None:
    with pytest.raises(SlamConfigError, match=r"^unknown SLAM config field\(s\) \[None, 'world'\]; known: "):
        SlamConfig.from_dict({None: 1, "world": "office"})
    with pytest.raises(SlamConfigError, match=r"^unknown field\(s\) \[1, 'x'\] in SLAM config section 'loop_closure'"):
        SlamConfig.from_dict({"loop_closure": {1: 2, "x": 3}})


def test_a_sweep_file_of_a_null_key_beside_an_unknown_one_names_both(tmp_path: Path) -> None:
    f = tmp_path / "s.yaml"
    f.write_text("~: 1\nworld: office\n")
    with pytest.raises(SweepSpecError, match=r"unknown key\(s\) \[None, 'world'\] in the sweep file") as err:
        load_sweep(f)
    assert isinstance(err.value, LmsbenchError)



def test_an_overlong_line_is_refused_without_reading_it_to_its_end(tmp_path: Path,
                                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """Without --skip-bad-lines a line over MAX_LINE_CHARS is refused as soon as it is found: the reader
    read it to its end first, so a gzip of 4 GB of 'x' after a log's first scans (4 MB on disk) took 42 s
    of `lmsbench info` to be refused (memory bounded, time not)."""
    import lms200.carmen as carmen
    from lms200 import LogFormatError, read_log

    monkeypatch.setattr(carmen, "MAX_LINE_CHARS", 500)
    read = []
    real_open_text = carmen.open_text

    class Counting:
        def __init__(self, f) -> None:
            self.f = f

        def readline(self, n: int = -1) -> str:
            line = self.f.readline(n)
            read.append(len(line))
            return line

        def __enter__(self) -> Counting:
            return self

        def __exit__(self, *exc: object) -> None:
            self.f.close()

    monkeypatch.setattr(carmen, "open_text", lambda path: Counting(real_open_text(path)))
    scan = "FLASER 5 2.0 2.0 2.0 2.0 2.0 1 2 0.5 1 2 0.5 10.0 host 10.0"
    path = tmp_path / "bomb.clf"
    path.write_text(scan + "\n" + "x" * 2_000_000)
    with pytest.raises(LogFormatError, match=r"bomb\.clf:2: malformed overlong line: longer than 500 characters"):
        list(read_log(path))
    assert sum(read) < 20_000  # it read all 2,000,000 characters of the line before refusing it
    reader = read_log(path, skip_bad_lines=True)  # skipping it reads on, as it must, to the line's end
    assert [r.scan.stamp for r in reader] == [10.0] and reader.stats.skipped[0][:1] == (2,)
