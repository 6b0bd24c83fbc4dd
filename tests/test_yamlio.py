"""YAML numbers as written: 1e9 and 5e-3 are floats (PyYAML's YAML 1.1 reads them as text)."""

from __future__ import annotations

import datetime

import pytest

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


@pytest.mark.parametrize("text, message", [
    ("a: [1, 2\n", "line 2, column 1: expected ',' or ']', but got '<stream end>' (while parsing a flow sequence at "
                   "line 1, column 4)"),
    ("a: 1\n  x: : 3\n", "line 2, column 4: mapping values are not allowed here"),
    ("a: *nope\n", "line 1, column 4: found undefined alias 'nope'"),
    ("a: 1\nb: \x01\n", "line 2, column 4: unacceptable character #x0001: special characters are not allowed"),
    ("a: !!python/object:os.system x\n", "line 1, column 4: could not determine a constructor for the tag "
                                          "'tag:yaml.org,2002:python/object:os.system'"),
    ('a: "x\n', "line 2, column 1: found unexpected end of stream (while scanning a quoted scalar at line 1, column 4)"),
])
def test_malformed_yaml_is_one_line_with_its_place(text: str, message: str) -> None:
    """PyYAML's messages span lines, quote the text under a caret and name the source
    "<unicode string>" (read as a file name after the real one); load's say the place first."""
    from lms200.yamlio import Malformed

    with pytest.raises(Malformed) as info:
        load(text)
    assert str(info.value) == message
    line, column = (int(v) for v in message.split(":")[0].replace("line ", "").split(", column "))
    assert (info.value.line, info.value.column) == (line, column)
    assert isinstance(info.value, yaml.YAMLError)
