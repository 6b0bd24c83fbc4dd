"""A folder given as a log whose scans.clf is there but no regular file (a fuzzing round): every command
said "(no scans.clf)" of it; the message now says what is in its place."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest


@pytest.mark.parametrize("kind, why", [
    ("missing", "no scans.clf"),
    ("folder", "its scans.clf is a folder"),
    ("fifo", "its scans.clf is not a regular file but a pipe, a device or a socket"),
    ("dev_zero", "its scans.clf is not a regular file but a pipe, a device or a socket"),
    ("loop", "its scans.clf is a link to scans.clf, which does not exist (or a loop of links)"),
])
def test_info_names_what_is_in_place_of_a_folders_scans_clf(tmp_path: Path, capsys, kind, why) -> None:
    from experiments.cli import main

    run = tmp_path / "run"
    run.mkdir()
    (run / "groundtruth.tum").write_text("0 0 0 0 0 0 0 1\n")
    log = run / "scans.clf"
    {"missing": lambda: None, "folder": log.mkdir, "fifo": lambda: os.mkfifo(log),
     "dev_zero": lambda: log.symlink_to("/dev/zero"), "loop": lambda: log.symlink_to("scans.clf")}[kind]()
    assert main(["info", str(run)]) == 2
    assert capsys.readouterr().err == (f"lmsbench info: error: {run} is a folder but neither a ROS 2 bag (no "
                                       f"metadata.yaml) nor a lmsbench simulate folder ({why})\n")  # old: (no scans.clf)


@pytest.mark.parametrize("kind, why", [
    ("folder", "its metadata.yaml is a folder"),
    ("fifo", "its metadata.yaml is not a regular file but a pipe, a device or a socket"),
    ("loop", "its metadata.yaml is a link to metadata.yaml, which does not exist (or a loop of links)"),
])
def test_info_and_read_log_name_what_is_in_place_of_a_bags_metadata_yaml(tmp_path: Path, capsys, kind, why) -> None:
    """The same of a ROS 2 bag's metadata.yaml (fuzz4): `info` and `read_log` said "no metadata.yaml"."""
    from experiments.cli import main
    from lms200 import read_log
    from lms200.errors import LogNotFoundError

    bag = tmp_path / "bag"
    bag.mkdir()
    meta = bag / "metadata.yaml"
    {"folder": meta.mkdir, "fifo": lambda: os.mkfifo(meta), "loop": lambda: meta.symlink_to("metadata.yaml")}[kind]()
    assert main(["info", str(bag)]) == 2
    assert capsys.readouterr().err == (f"lmsbench info: error: {bag} is a folder but neither a ROS 2 bag ({why}) nor a "
                                       "lmsbench simulate folder (no scans.clf)\n")  # old: (no metadata.yaml)
    with pytest.raises(LogNotFoundError, match=f"^{re.escape(f'{bag} is a folder but not a ROS 2 bag ({why})')}$"):
        read_log(bag)
