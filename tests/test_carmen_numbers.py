"""How the CARMEN reader parses numbers: the fast paths (range words parsed once a pass, a few numbers
by float()) give exactly what ``_floats`` (numpy's parse with its checks) gives, values bit for bit
and the same error for every bad word, and keep bounded memory."""

from __future__ import annotations

import itertools
import random
import struct

import numpy as np
import pytest

from lms200 import read_log
from lms200 import carmen
from lms200.carmen import MAX_CACHED_WORD_CHARS, MAX_CACHED_WORDS, _few_floats, _floats, _range_floats, _RangeWords

# valid words (signed zeros, nan and inf words, subnormals, underflow, a sum that overflows) and every
# kind of bad one (an underscore, an overflow, no number, hex)
WORDS = ["1.5", "-0", "0", "81.91", "nan", "-nan", "NaN", "inf", "-Infinity", "+inf", "1e308", "4.9e-324",
         "1e-400", "1.", ".5", "1E5", "1e400", "-1e400", "1_0", "x", "0x10", "1e"]


def _bits(values: object) -> list[str]:
    return [struct.pack("<d", v).hex() for v in np.asarray(values, dtype=np.float64).tolist()]


def _outcome(parse, words: list[str]) -> tuple[str, object]:
    try:
        return "values", _bits(parse(words, "FLASER ranges"))
    except ValueError as exc:
        return "error", str(exc)


@pytest.mark.parametrize("size", [1, 2, 3])
def test_fast_parses_give_what_floats_gives_for_every_word(size: int) -> None:
    warm = _RangeWords()  # one cache over every group: words met before come from it
    for words in itertools.product(WORDS, repeat=size):
        group = list(words)
        expected = _outcome(_floats, group)
        assert _outcome(_few_floats, group) == expected, group
        assert _outcome(lambda w, what: _range_floats(w, what, _RangeWords()), group) == expected, group
        assert _outcome(lambda w, what: _range_floats(w, what, warm), group) == expected, group


def _flaser(ranges: str, stamp: float) -> str:
    return f"FLASER {len(ranges.split())} {ranges} 1 2 0.5 1 2 0.5 {stamp} host {stamp}\n"


def test_valid_lines_never_reach_the_numpy_parse(tmp_path, monkeypatch) -> None:
    # was: every laser, ODOM and TRUEPOS line went through _floats (numpy's parse of a list of words, its
    # '_' and overflow checks): 9-24 % slower reads; the checks cost as much as the parse on ODOM lines
    path = tmp_path / "same.log"
    path.write_text("".join("ODOM 1 2 0.5 0 0 0 {t} h {t}\nTRUEPOS 3 4 0.5 1 2 0.5 {t} h {t}\n".format(t=i / 10)
                            + _flaser("1.00 2.00 81.91 nan inf", i / 10) for i in range(50)))
    calls: list[str] = []
    real = carmen._floats
    monkeypatch.setattr(carmen, "_floats", lambda words, what: calls.append(what) or real(words, what))
    records = list(read_log(path))
    assert len(records) == 50 and calls == []
    assert records[-1].odom == (1.0, 2.0, 0.5) and records[-1].truth == (3.0, 4.0, 0.5)
    assert records[-1].scan.stamp == 4.9 and _bits(records[-1].scan.ranges) == _bits([1.0, 2.0, np.nan, np.nan, np.inf])


def test_a_bad_word_is_still_named_by_floats_message(tmp_path) -> None:
    path = tmp_path / "bad.log"
    path.write_text(_flaser("1.00 2.00", 1.0) + _flaser("1.00 x 1_0", 2.0) + "ODOM 0 0 1e400 0 0 0 3 h 3\n")
    reader = read_log(path, skip_bad_lines=True)
    assert len(list(reader)) == 1
    assert reader.stats.skipped == [(2, "FLASER: FLASER ranges: '1_0' is not a number (no '_' in a CARMEN number)"),
                                    (3, "ODOM: ODOM: '1e400' is beyond float64's range")]


def test_a_word_of_bytes_that_are_not_ascii_is_said_so(tmp_path) -> None:
    """An Arabic-Indic digit (two UTF-8 bytes) read as two replacement characters was quoted alone: '\ufffd\ufffd'
    is not a number, mojibake on a terminal (round 11's probe)."""
    path = tmp_path / "ar.log"
    path.write_bytes(_flaser("1.00 2.00", 1.0).encode() + _flaser("1.00 \u0663", 2.0).encode("utf-8"))
    reader = read_log(path, skip_bad_lines=True)
    assert len(list(reader)) == 1
    assert reader.stats.skipped == [(2, "FLASER: FLASER ranges: '\ufffd\ufffd' (2 bytes not ASCII, each shown as "
                                        "U+FFFD) is not a number")]


def test_the_range_words_kept_are_bounded() -> None:
    cache = _RangeWords()
    words = [f"{i / 1000:.3f}" for i in range(MAX_CACHED_WORDS + 1000)]
    assert _range_floats(words, "r", cache).tolist() == [float(w) for w in words]
    assert len(cache) == 1000  # emptied when full at the next new word: the last 1,000 kept, not the first
    long = "1." + "0" * MAX_CACHED_WORD_CHARS
    cache = _RangeWords()
    assert _range_floats([long, "2.5"], "r", cache).tolist() == [1.0, 2.5] and list(cache) == ["2.5"]


def _count_new_words(monkeypatch, path) -> tuple[list, list[int]]:
    """The records of a log and how many range words each laser line parsed one by one in Python."""
    per_line = [0]
    missing = _RangeWords.__missing__

    def counted(self, word):
        per_line[-1] += 1
        return missing(self, word)

    monkeypatch.setattr(_RangeWords, "__missing__", counted)
    records = []
    for record in read_log(path):
        records.append(record)
        per_line.append(0)
    return records, per_line[:-1]


def _flasers(path, lines) -> None:
    path.write_text("PARAM lmsbench_range_units cm\n" + "".join(_flaser(" ".join(w), i * 0.1) for i, w in enumerate(lines)))


def test_unique_and_noisy_start_words_are_not_parsed_one_by_one(tmp_path, monkeypatch) -> None:
    """f45759a parsed every new range word in Python (~550 ns, numpy 190-310): a log of
    full-precision floats (2.1M distinct words, as converted from ROS) read 44 % slower than numpy
    alone, and one whose first 59 scans were so (filling the cache, which then kept no later word)
    39 %; those parsed 72,200 and 86,640 words one by one here (36,100 in the last 100 scans of
    each), lines of both kinds in turn 36,891. Now lines of many new words go to numpy for a while
    unless their sampled words were met before, and a full cache is emptied: 3,249, 3,318 (40 in
    the last 100 scans) and 4,762; the records are numpy's; a log of few words still parses each
    word once."""
    rng = random.Random(0)
    unique = [[repr(rng.uniform(0.1, 8.0)) for _ in range(361)] for _ in range(200)]
    codes = [[f"{rng.randint(10, 800) / 100:.2f}" for _ in range(361)] for _ in range(200)]
    noisy_start = unique[:60] + codes[:180]  # 21,660 distinct words first: more than MAX_CACHED_WORDS
    in_turn = [w for pair in zip(unique[:100], codes) for w in pair]
    for name, lines, most in (("unique", unique, 4_000), ("noisy", noisy_start, 4_000), ("codes", codes, 791),
                              ("in turn", in_turn, 6_000)):
        path = tmp_path / f"{name}.log"
        _flasers(path, lines)
        records, per_line = _count_new_words(monkeypatch, path)
        expected = [carmen._ranges(np.array(w, dtype=np.float64), "cm", "FLASER")[0] for w in lines]
        assert [_bits(r.scan.ranges) for r in records] == [_bits(e) for e in expected], name
        assert sum(per_line) <= most, (name, sum(per_line))  # 791: each code once
        if name == "noisy":  # the code scans after the noisy start are parsed through the cache again
            assert sum(per_line[-100:]) <= 100 and per_line[-1] == 0, per_line[-100:]


def test_a_nonzero_number_below_float64_makes_its_line_malformed_as_one_beyond_it_does(tmp_path) -> None:
    """A range written 1e-400 was read as 0.0 m, a logger's "no reading", silently, where 1e400 made its
    line malformed: strtod says ERANGE for both. Both are now malformed, in a range (through the pass's
    word cache, warm or not) or a pose; a zero written as one (0, 0.00, 0e-400, -0) is 0 as before."""
    path = tmp_path / "tiny.log"
    path.write_text(_flaser("1.00 2.00", 1.0) + _flaser("1e-400 2.00", 2.0) + _flaser("1.00 2.00", 3.0)
                    + _flaser("1.00 1e-400", 4.0) + "ODOM 1e-400 0 0 0 0 0 5 h 5\n"
                    + _flaser("0 0.00 0e-400 -0", 6.0))
    reader = read_log(path, skip_bad_lines=True)
    records = list(reader)
    assert [r.scan.stamp for r in records] == [1.0, 3.0, 6.0]
    assert records[-1].scan.ranges.tolist() == [0.0, 0.0, 0.0, 0.0]
    assert reader.stats.skipped == [
        (2, "FLASER: FLASER ranges: '1e-400' is below float64's range (nonzero, it would read as 0)"),
        (4, "FLASER: FLASER ranges: '1e-400' is below float64's range (nonzero, it would read as 0)"),
        (5, "ODOM: ODOM: '1e-400' is below float64's range (nonzero, it would read as 0)")]
    for parse in (_floats, _few_floats, lambda w, what: _range_floats(w, what, _RangeWords())):
        with pytest.raises(ValueError, match=r"^r: '-2\.5e-999' is below float64's range"):
            parse(["1.0", "-2.5e-999"], "r")


def test_a_zero_written_without_an_exponent_is_not_asked_whether_it_underflowed(tmp_path, monkeypatch) -> None:
    """A review: underflow_problem was asked of every word read as 0 (the Intel log's 45,737 '0' ranges:
    ~30 % of its reading). A word with no 'e' shorter than 320 characters cannot be a nonzero number read
    as 0 (that needs 323 zeros after the point), so it is not asked; those that can still are refused."""
    asked: list[str] = []
    real = carmen.underflow_problem

    def counted(text: str, value: float) -> str | None:
        asked.append(text)
        return real(text, value)

    monkeypatch.setattr(carmen, "underflow_problem", counted)
    path = tmp_path / "zeros.log"
    path.write_text(_flaser("0 0.00 -0 1.5", 1.0) + _flaser("0 2.0 0 0", 2.0) + "ODOM 0 0 0 0 0 0 3 h 3\n")
    records = list(read_log(path))
    assert [r.scan.ranges.tolist() for r in records] == [[0.0, 0.0, 0.0, 1.5], [0.0, 2.0, 0.0, 0.0]]
    assert asked == []
    for parse in (_floats, _few_floats, lambda w, what: _range_floats(w, what, _RangeWords())):
        assert list(parse(["0", "0.000", "0e5"], "r")) == [0.0, 0.0, 0.0]
        tiny = "0." + "0" * 400 + "1"  # no exponent, nonzero, read as 0
        with pytest.raises(ValueError, match=r"^r: '0\.0000.*1' is below float64's range"):
            parse(["1.0", tiny], "r")
    assert asked and all("e" in w or len(w) > 320 for w in asked)
