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


LAUGHS = "[" + ", ".join(["&c0 [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]"] + [f"&c{i} [" + ", ".join([f"*c{i - 1}"] * 10) + "]"
                                                                 for i in range(1, 9)]) + "]"  # 10^9 values, 600 bytes


@pytest.mark.parametrize("text, error, message", [
    (f"noise_sigma: {LAUGHS}\n", "AliasBomb", "its aliases (*name) expand it to more than 1,000,000 values (a 'billion "
                                              "laughs'); write the values out"),
    ("a: &a [1, *a]\n", "SelfReference", "a value holds itself through an alias (&name ... *name inside it)"),
    ("a: &a {b: *a}\n", "SelfReference", "a value holds itself through an alias (&name ... *name inside it)"),
    (f"a: {'9' * 5000}\n", "Malformed", "line 1, column 4: a whole number of more than 4300 digits"),  # was a ValueError
    # a date that cannot be, or a tag's value it cannot make: Python's ValueError, an internal error at yamlio.load
    ("seed: 2025-02-30\n", "Malformed", "line 1, column 7: '2025-02-30' is not a valid date or time (day is out of "
                                       "range for month)"),
    ("a: 1\nb: [2025-01-01, {c: 2025-13-01 10:00:00}]\n", "Malformed",
     "line 2, column 21: '2025-13-01 10:00:00' is not a valid date or time (month must be in 1..12)"),
    ("a: !!float abc\n", "Malformed", "line 1, column 4: 'abc' is not a valid float (could not convert string to "
                                     "float: 'abc')"),
    ("a: !!timestamp abc\n", "Malformed", "line 1, column 4: 'abc' is not a valid date or time"),  # an AttributeError
])
def test_aliases_that_explode_or_loop_and_endless_numbers_are_refused(text: str, error: str, message: str) -> None:
    """A 'billion laughs' (nine lines of anchors, 10^9 values) loads at once, the objects shared;
    the first error message that printed the value (``noise_sigma: must be a number, got [[...``)
    hung `simulate --sensor`, `compare --sensor` and `sim2real --sensor` past 60 s and 500 MB, and
    a self-referencing value is endless to anything that walks it. A 5000-digit integer raised
    Python's ValueError (ints of more than 4300 digits), not a YAML error."""
    with pytest.raises(yaml.YAMLError) as info:
        load(text)
    assert type(info.value).__name__ == error and str(info.value) == message


def test_aliases_within_bounds_and_long_documents_load(monkeypatch) -> None:
    """Shared values below the bound load as before; the bound never refuses a document without
    aliases, however long (its values are at most its characters)."""
    from lms200 import yamlio

    assert load("a: &a [1, 2]\nb: [*a, *a, *a]\n") == {"a": [1, 2], "b": [[1, 2]] * 3}
    monkeypatch.setattr(yamlio, "MAX_EXPANDED_VALUES", 10)
    assert load("a: [" + ", ".join(["1"] * 50) + "]\n") == {"a": [1] * 50}
    text = "a: &a [1,1,1,1,1,1,1,1,1,1]\nb: [*a, *a, *a]\n"  # 44 characters, 48 values
    with pytest.raises(yamlio.AliasBomb, match=f"more than {len(text)} values"):
        load(text)
