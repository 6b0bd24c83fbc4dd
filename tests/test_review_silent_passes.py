"""Silent passes and unhelpful messages found by a review (session of the fix helper): each test
fails on the code before its fix."""

from __future__ import annotations

import bz2
import gzip
from pathlib import Path

import pytest

from lms200 import read_log
from lms200.errors import LogFormatError


# -- 1. a log of no laser line ----------------------------------------------------------------------
@pytest.mark.parametrize("name, data, reason", [
    ("empty.clf", b"", r"an empty file \(0 bytes\): no laser lines"),
    ("empty.clf.gz", gzip.compress(b""), r"its gzip data decompresses to nothing: an empty log, no laser lines"),
    ("empty.clf.bz2", bz2.compress(b""), r"its bzip2 data decompresses to nothing"),
    ("quiet.clf", b"# header\n\n   \n# more\n", r"holds only blank or comment lines \(4\): no laser lines"),
    ("odom.clf", b"ODOM 0 0 0 0 0 0 1 h 1\nODOM 0 0 0 0 0 0 2 h 2\nPARAM x 1\n",
     r"holds no laser lines \(FLASER, .*\), only other messages: ODOM \(2\), PARAM \(1\)"),
])
@pytest.mark.parametrize("skip", [False, True])
def test_a_log_of_no_laser_line_is_refused_naming_the_file(tmp_path: Path, name: str, data: bytes, reason: str,
                                                          skip: bool) -> None:
    """A zero-byte log, a gzip of nothing, a file of comments read as no records, silently."""
    (tmp_path / name).write_bytes(data)
    with pytest.raises(LogFormatError, match=rf"{name.replace('.', '[.]')}:1: {reason}"):
        list(read_log(tmp_path / name, skip_bad_lines=skip))


def test_a_log_of_junk_skipped_under_skip_bad_lines_says_what_it_skipped(tmp_path: Path) -> None:
    """Lines skipped are the reader's word (stats.skipped): no error for the lack of a laser line then."""
    (tmp_path / "bad.clf").write_text("FLASER 3 1 2\n")
    reader = read_log(tmp_path / "bad.clf", skip_bad_lines=True)
    assert list(reader) == [] and reader.stats.skipped_count == 1
