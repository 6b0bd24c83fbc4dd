"""A folder given as a log whose scans.clf is there but no regular file (a fuzzing round): every command
said "(no scans.clf)" of it; the message now says what is in its place."""

from __future__ import annotations

import os
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
