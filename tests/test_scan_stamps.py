"""``lms200.Scan`` takes stamps in 0 .. 2^32 s (``lms200.scan.MAX_STAMP_S``), what every log reader
and writer takes: -1e300 s and 1e300 s were taken, and failed only where a log was written (or, as
a step of 1e200 s, in SLAM's motion model)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from lms200 import LmsbenchError, Scan
from lms200.errors import ScanError
from lms200.records import MAX_STAMP_S, stamp_problem


@pytest.mark.parametrize("stamp, shown", [(-1e300, "-1e+300"), (1e300, "1e+300"), (-1.0, "-1.000000"),
                                          (-5e-324, "-4.94066e-324"), (2.0**32 + 1, "4294967297.000000")])
def test_a_stamp_outside_0_to_2_32_s_is_refused_naming_the_field(stamp: float, shown: str) -> None:
    with pytest.raises(ScanError) as info:
        Scan(np.ones(3), 0.0, 0.01, 0.0, 8.0, stamp=stamp)
    # the readers' wording (lms200.records.stamp_problem, the same function); it said "stamp: must be in 0 .. 2^32 s
    # (4294967296 s, 2106-02-07), as every log reader and writer takes it (a clock's UNIX time or seconds since the
    # run's start), got V s", the one rule in two wordings
    assert str(info.value) == (f"stamp {shown} s is outside 0 .. 2^32 s (4294967296 s, 2106-02-07), the stamps every log "
                               "reader and writer takes: a clock's UNIX time, or seconds since the run's start")
    assert str(info.value) == stamp_problem(stamp, "stamp")
    assert isinstance(info.value, LmsbenchError) and isinstance(info.value, ValueError)
    with pytest.raises(ScanError, match=f"^stamp {re.escape(shown)} s is outside 0 .. 2"):
        Scan(np.ones(3), 0.0, 0.01, 0.0, 8.0).replace(stamp=stamp)


def test_the_ends_and_a_unix_time_are_taken() -> None:
    assert MAX_STAMP_S == 2.0**32
    assert [Scan(np.ones(3), 0.0, 0.01, 0.0, 8.0, stamp=t).stamp for t in (0.0, 1.7e9, MAX_STAMP_S)] == [0.0, 1.7e9, 2.0**32]
    assert Scan.lms200(np.full(361, 2.0), stamp=0).stamp == 0.0
