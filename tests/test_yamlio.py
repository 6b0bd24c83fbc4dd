"""YAML numbers as written: 1e9 and 5e-3 are floats (PyYAML's YAML 1.1 reads them as text)."""

from __future__ import annotations

import datetime
import re

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


UNDERSCORES = "YAML 1.1 drops a number's underscores (the command line refuses them)"
BASE_60 = "YAML 1.1 reads digits between colons in base 60 (a time or an angle)"
OCTAL = "YAML 1.1 reads a whole number with a leading 0 in octal"


@pytest.mark.parametrize("text, message", [
    ("k: 1_0\n", f"line 1, column 4: key 'k': 1_0 is read as 10: {UNDERSCORES}"),
    ("duration: 1:30\n", f"line 1, column 11: key 'duration': 1:30 is read as 90: {BASE_60}"),
    ("seed: 010\n", f"line 1, column 7: key 'seed': 010 is read as 8: {OCTAL}"),
    ("a: 1\nx: 1_000.5\n", f"line 2, column 4: key 'x': 1_000.5 is read as 1000.5: {UNDERSCORES}"),
    ("t: 12:30:00\n", f"line 1, column 4: key 't': 12:30:00 is read as 45000: {BASE_60}"),
    ("t: -1:30.5\n", f"line 1, column 4: key 't': -1:30.5 is read as -90.5: {BASE_60}"),
    ("h: 0x1_0\n", f"line 1, column 4: key 'h': 0x1_0 is read as 16: {UNDERSCORES}"),
    ("grid:\n  extractor.k: [3, 1_0]\n", f"line 2, column 20: key 'extractor.k', item 2: 1_0 is read as 10: {UNDERSCORES}"),
    ("robot: {v_max: 1:30}\n", f"line 1, column 16: key 'v_max': 1:30 is read as 90: {BASE_60}"),
    ("- [1_0]\n", f"line 1, column 4: 1_0 is read as 10: {UNDERSCORES}"),  # no key: the place alone
    ("1_0: x\n", f"line 1, column 1: 1_0 is read as 10: {UNDERSCORES}"),
])
def test_numbers_yaml_1_1_reads_otherwise_are_refused_at_their_key_and_line(text: str, message: str) -> None:
    """PyYAML follows YAML 1.1: ``k: 1_0`` read as 10, ``duration: 1:30`` as 90 (base 60) and
    ``seed: 010`` as 8 (octal), silently (``simulate --config`` with ``seed: 1:30`` simulated seed
    90, with ``seed: 010`` seed 8; ``n_beams: 18_1`` in a sensor file 181 beams). YAML 1.2, Python
    and the command line (``experiments.options.plain_number``) read none of them so: each is
    refused, naming the key and line; quoted, it is text, which the field's own check refuses."""
    from lms200.yamlio import Malformed

    value = message.split(" is read as ")[0].rsplit(" ", 1)[-1]
    with pytest.raises(Malformed) as info:
        load(text)
    assert str(info.value) == f"{message}; write the number as a plain decimal, or quote it ('{value}') for text"
    assert load(text.replace(value, f"'{value}'")) is not None  # quoted: text


UNDERFLOW = "rounds to 0 in float64 (its smallest nonzero number is 4.9e-324); write 0 for zero"


@pytest.mark.parametrize("text, message", [
    ("noise_sigma: 1e-400\n", f"line 1, column 14: key 'noise_sigma': 1e-400 {UNDERFLOW}"),
    ("sensor:\n  noise_sigma: -2.5E-999\n", f"line 2, column 16: key 'noise_sigma': -2.5E-999 {UNDERFLOW}"),
    ("grid:\n  sensor.noise_sigma: [0.01, .1e-330]\n", f"line 2, column 30: key 'sensor.noise_sigma', item 2: .1e-330 "
                                                      f"{UNDERFLOW}"),
    ("x: !!float 1e-400\n", f"line 1, column 4: key 'x': 1e-400 {UNDERFLOW}"),
])
def test_a_nonzero_float_that_underflows_to_0_is_refused_at_its_key_and_line(text: str, message: str) -> None:
    """``noise_sigma: 1e-400`` read as 0.0 without a word: a noise-free run. A zero written as one
    (0e-400, 0.0e-5) and a subnormal float64 holds (5e-324) read as before."""
    from lms200.yamlio import Malformed

    with pytest.raises(Malformed) as info:
        load(text)
    assert str(info.value) == message
    assert load("a: 0e-400\nb: -0.0e-5\nc: 5e-324\nd: 1e-300\n") == {"a": 0.0, "b": 0.0, "c": 5e-324, "d": 1e-300}


def test_numbers_read_as_before() -> None:
    """Every number YAML 1.2 and YAML 1.1 read alike reads as it did: ints, floats with or
    without a dot or exponent, hexadecimal and binary, infinities and nan; and text that only
    looks like the refused forms stays text."""
    import math

    text = ("a: 1\nb: 1.5\nc: 1e-3\nd: -2\ne: .5\nf: 0x10\ng: 0b101\nh: 0\ni: -0\nj: +1\nk: 1E6\nl: 1.0e+3\nm: 0.0\n"
            "n: 01.5\no: 1.\np: .inf\nq: -.inf\nr: 09\ns: 1:60\nt: a:b\nu: _1\nv: '1_0'\nw: \"1:30\"\nx: 2026-01-02\n")
    got = load(text)
    nan = load("z: .nan\n")["z"]
    assert math.isnan(nan)
    assert got == {"a": 1, "b": 1.5, "c": 1e-3, "d": -2, "e": 0.5, "f": 16, "g": 5, "h": 0, "i": 0, "j": 1, "k": 1e6,
                   "l": 1000.0, "m": 0.0, "n": 1.5, "o": 1.0, "p": float("inf"), "q": float("-inf"), "r": "09", "s": "1:60",
                   "t": "a:b", "u": "_1", "v": "1_0", "w": "1:30", "x": datetime.date(2026, 1, 2)}
    assert [type(got[k]) for k in "adfghij"] == [int] * 7 and [type(got[k]) for k in "bcekl"] == [float] * 5


def test_a_whole_number_beyond_float64s_range_is_refused_at_its_place(tmp_path, capsys) -> None:
    """Found by fuzzing configs: a whole number of 401 digits (below Python's 4300-digit limit) loaded
    as an int, and failed where a setting was cast to float: `simulate --config` with such a duration
    or rate_hz said 'internal error: OverflowError: int too large to convert to float', exit 1. Every
    YAML the project reads refuses it at its line; the largest float64-sized ones load as before."""
    from experiments.cli import main

    big = "1" + "0" * 400
    for text, place in ((f"duration: {big}\n", "line 1, column 11: a whole number of 401"),
                        (f"a: [1, {{b: -{big}}}]\n", "line 1, column 12: a whole number of 402"),
                        (f"? {big}\n: 3\n", "line 1, column 3: a whole number of 401")):
        with pytest.raises(yaml.YAMLError) as info:
            load(text)
        assert str(info.value) == f"{place} characters, beyond float64's range, +-1.8e308: no setting takes it"
    assert load(f"a: {'1' + '0' * 308}\nb: {-(2**1023)}\n") == {"a": 10**308, "b": -(2**1023)}
    config = tmp_path / "config.yaml"
    config.write_text(f"world: office\nduration: {big}\n")
    assert main(["simulate", "--config", str(config), "--out", str(tmp_path / "run"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "line 2, column 11: a whole number of 401 characters, beyond float64's range" in err
    assert not (tmp_path / "run").exists()


BOOL_TEXT = "is read as text here, but is YAML 1.1's boolean word for"


@pytest.mark.parametrize("text, message", [
    ("deskew: yes\n", "line 1, column 9: key 'deskew': yes is read as true (YAML 1.1), but as text by YAML 1.2"),
    ("a: 1\ninterlaced: No\n", "line 2, column 13: key 'interlaced': No is read as false (YAML 1.1), but as text by YAML 1.2"),
    ("sensor: {flag: ON}\n", "line 1, column 16: key 'flag': ON is read as true (YAML 1.1), but as text by YAML 1.2"),
    ("grid:\n  mode: [true, off]\n", "line 2, column 16: key 'mode', item 2: off is read as false (YAML 1.1), but as text by YAML 1.2"),
    ("k: y\n", f"line 1, column 4: key 'k': y {BOOL_TEXT} true"),
    ("k: N\n", f"line 1, column 4: key 'k': N {BOOL_TEXT} false"),
    ("k: yEs\n", f"line 1, column 4: key 'k': yEs {BOOL_TEXT} true"),
    ("k: &a on\n", "line 1, column 4: key 'k': on is read as true (YAML 1.1), but as text by YAML 1.2"),
    ("- [n]\n", f"line 1, column 4: n {BOOL_TEXT} false"),  # no key: the place alone
    ("yes\n", "line 1, column 1: yes is read as true (YAML 1.1), but as text by YAML 1.2"),  # a --set value
])
def test_yaml_1_1_boolean_words_are_refused_at_their_key_and_line(text: str, message: str) -> None:
    """PyYAML follows YAML 1.1: ``deskew: yes`` / ``no`` / ``on`` / ``off`` read as True / False,
    silently (``simulate --config`` with ``sensor: {interlaced: no}`` ran, exit 0), where YAML 1.2,
    Python and the command line read text; ``y`` and ``n`` it reads as text, where YAML 1.1 has a
    boolean. Each, in any case, written unquoted as a value is refused naming the key and line;
    quoted it is text, and true / false read as before."""
    from lms200.yamlio import Malformed

    value = message.split(": ")[-1].split(" ")[0]
    with pytest.raises(Malformed) as info:
        load(text)
    assert str(info.value) == f"{message}; write true or false, or quote it ('{value}') for text"
    quoted = re.sub(rf"\b{value}\b", f"'{value}'", text)
    assert quoted.count("'") == 2 and f"'{value}'" in repr(load(quoted))  # quoted: text


def test_true_false_quoted_and_tagged_words_and_keys_read_as_before() -> None:
    """Only an unquoted, untagged boolean word as a value is refused: true / false in any of
    YAML's spellings, a quoted or explicitly tagged word, text that merely starts like one, and a
    key read as they did."""
    text = ("a: true\nb: False\nc: TRUE\nd: 'yes'\ne: \"off\"\nf: !!str no\ng: !!bool yes\nh: none\ni: yess\nj: [true, 'n']\n"
            "on: 1\n")
    assert load(text) == {"a": True, "b": False, "c": True, "d": "yes", "e": "off", "f": "no", "g": True, "h": "none",
                          "i": "yess", "j": [True, "n"], True: 1}


def test_dump_quotes_what_load_refuses_plain_so_its_text_reads_back() -> None:
    """yaml.safe_dump wrote the text ``n``, ``y`` (and ``yEs``) plain, as PyYAML reads them as text;
    the loader refuses them as YAML 1.1 boolean words, so a config lmsbench wrote (a grid of
    ``['y', 'n']``, a log named ``n``) was refused when read back. ``yamlio.dump`` quotes them."""
    from lms200.yamlio import dump

    data = {"grid": ["y", "n", "Y", "N", "yEs", "no", "On", "OFF", "true", True, False, "none", "ny", 1, 1.5], "n": "y"}
    text = dump(data, sort_keys=False)
    assert text.startswith("grid:\n- 'y'\n- 'n'\n- 'Y'\n- 'N'\n- 'yEs'\n- 'no'\n- 'On'\n- 'OFF'\n- 'true'\n- true\n- false\n- none\n")
    assert load(text) == data


def test_a_merged_key_that_is_a_boolean_word_reads_as_a_written_one() -> None:
    """A key such as ``on:`` is read as PyYAML reads it; brought in by a merge (``<<``) it was
    refused as a value ("on is read as true"), since the merge's keys were not marked as keys."""
    assert load("a:\n  <<: {on: 1}\n  b: 2\n") == {"a": {True: 1, "b": 2}}
    assert load("base: &b {on: 1}\na:\n  <<: *b\n") == {"base": {True: 1}, "a": {True: 1}}
    with pytest.raises(yaml.YAMLError, match="no is read as false"):
        load("a:\n  <<: {x: no}\n")  # a merged value is still one


def test_words_reads_yaml_not_written_for_lmsbench_as_pyyaml_does() -> None:
    """``load(text, words=True)``: a ROS 2 bag's metadata.yaml (rosbag2 writes it) and the records
    an earlier version wrote with yaml.safe_dump (``scans: n`` plain) read as PyYAML reads them."""
    text = "custom_data: {operator: n, heated: yes}\nscans: y\n"
    with pytest.raises(yaml.YAMLError, match="YAML 1.1"):
        load(text)
    assert load(text, words=True) == {"custom_data": {"operator": "n", "heated": True}, "scans": "y"}
    with pytest.raises(yaml.YAMLError, match="octal"):  # the other checks stay
        load("seed: 010\n", words=True)


def test_a_ros2_bag_whose_metadata_holds_a_boolean_word_is_read_by_the_command_line(tmp_path, capsys) -> None:
    """check_log read a ROS 2 bag's metadata.yaml with the loader that refuses YAML 1.1's boolean
    words, so `info BAG` refused a bag whose metadata held ``operator: n`` (custom data rosbag2
    writes as given), which read_log and rosbags read (review)."""
    from experiments.cli import main
    from lms200 import Record, Scan, read_log
    from lms200.bag import write_bag

    bag = tmp_path / "r2"
    write_bag(bag, [Record(Scan.lms200([1.0 + 0.01 * i] * 361, stamp=float(i))) for i in range(3)])
    meta = bag / "metadata.yaml"
    text = meta.read_text()
    assert text.count("  custom_data: null\n") == 1
    meta.write_text(text.replace("  custom_data: null\n", "  custom_data:\n    operator: n\n    heated: no\n"))
    assert len(list(read_log(bag))) == 3
    assert main(["info", str(bag)]) == 0, capsys.readouterr().err
    assert "scans           3" in capsys.readouterr().out


def test_a_slam_folder_an_earlier_version_wrote_with_a_plain_n_is_rerun_into(tmp_path, capsys, monkeypatch) -> None:
    """An earlier version wrote config.yaml with yaml.safe_dump (``scans: n`` plain): the check of
    --out read it with the loader that refuses ``n``, and took the folder for none of slam's ("no
    earlier lmsbench slam run wrote"); a record is read as PyYAML reads it (review)."""
    from experiments.cli import main
    from lms200 import Record, Scan, write_log

    monkeypatch.chdir(tmp_path)
    write_log(tmp_path / "n", [Record(Scan.lms200([2.0] * 361, stamp=0.1 * i)) for i in range(5)])
    assert main(["slam", "n", "--out", "o", "--quiet"]) == 0, capsys.readouterr().err
    cfg = tmp_path / "o" / "config.yaml"
    cfg.write_text(cfg.read_text().replace("scans: 'n'", "scans: n"))  # as yaml.safe_dump wrote it
    assert "scans: n\n" in cfg.read_text()
    assert main(["slam", "n", "--out", "o", "--quiet"]) == 0, capsys.readouterr().err
