"""YAML numbers as written: 1e9 and 5e-3 are floats (PyYAML's YAML 1.1 reads them as text)."""

from __future__ import annotations

import datetime

import yaml

from lms200.yamlio import load


def test_exponent_floats_are_numbers_and_everything_else_is_pyyaml():
    text = "a: 1e9\nb: 5e-3\nc: 1E6\nd: -2e+2\ne: .5e1\nf: 12\ng: 1.5\nh: abc\ni: '1e9'\nj: 2026-01-02\nk: [1e-3, 2]\nl: .inf\n"
    got = load(text)
    assert got == {"a": 1e9, "b": 5e-3, "c": 1e6, "d": -200.0, "e": 5.0, "f": 12, "g": 1.5, "h": "abc", "i": "1e9",
                   "j": datetime.date(2026, 1, 2), "k": [1e-3, 2], "l": float("inf")}
    assert type(got["f"]) is int and type(got["a"]) is float
    plain = yaml.safe_load(text)  # the difference is exactly the exponent floats
    assert plain["a"] == "1e9" and plain["b"] == "5e-3" and {k: plain[k] for k in "fghijl"} == {k: got[k] for k in "fghijl"}
