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

