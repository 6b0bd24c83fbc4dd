"""Checks of command-line options and input files, run before any work starts.

Each ``argparse`` type here turns a bad value into a one-line error naming the option, its range
and what was given (``argument --duration: must be a finite number > 0 s, got 'inf'``); the
``check_*`` functions raise :class:`InputError` for files that are missing, unreadable or of the
wrong kind. ``experiments.cli`` prints either as ``lmsbench CMD: error: ...`` with exit status 2.
"""

from __future__ import annotations

import argparse
import fnmatch
import math
import os
import re
import stat
import tempfile
import sys
import threading
import warnings
from contextlib import contextmanager
from pathlib import Path
from dataclasses import dataclass, field
from typing import Any, Callable, Iterator, Mapping, NamedTuple, Sequence

import yaml

from lms200.carmen import COMPRESSION_SUFFIXES, PIPE_REASON, READ_ERRORS, compression, open_bytes
from lms200.errors import InputError as InputError  # bad option values and input files: the library's one class
from lms200.finite import underflow_problem
from lms200.logs import SIMULATE_LOG, SIMULATE_OTHER_FILES, head_problem
from lms200.timing import MAX_DURATION_S, MIN_DURATION_S  # a simulated run's bounds (s)
from lms200.yamlio import load as load_yaml, size_problem



def known_worlds() -> tuple[str, ...]:
    """The built-in worlds of the simulator (``sim.WORLD_NAMES``)."""
    from sim.worlds import WORLD_NAMES

    return tuple(WORLD_NAMES)


#: written in an option's help text, replaced by the simulator's world names (known_worlds) when the
#: help is shown: ``compare --help`` listed five of the seven worlds, written out by hand; the names
#: are not read when the parsers are built (that imports the simulator, for every command)
WORLDS = "{worlds}"


class HelpFormatter(argparse.HelpFormatter):
    """argparse's help, with WORLDS in a help text filled in."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = super()._get_help_string(action)
        if not text or WORLDS not in text:
            return text
        from lms200 import LmsbenchError

        try:
            names = ", ".join(known_worlds())
        except LmsbenchError:  # the simulator cannot load (numba missing): its error comes when it is used
            names = "a built-in world's name"
        return text.replace(WORLDS, names)


#: a quoted value of 80 characters or more: the opening quote not after a letter or digit, the closing
#: one not before one, so an apostrophe ("don't", "the log's") is not taken for a quote (the text
#: between it and a value's opening quote was cut instead of the value)
_LONG_QUOTED = re.compile(r"(?<![\w'])'([^'\n]{%d,})'(?![\w'])" % 80)


def shorten_quoted(message: str) -> str:
    """``message`` with every quoted value of 80 characters or more cut to its start and end and its
    length (`--seed 999...` of 5000 digits, a log line of NUL bytes, echoed whole, made an error
    line of kilobytes in which the option's name and the hint were lost)."""
    return _LONG_QUOTED.sub(lambda m: f"'{m[1][:40]}...{m[1][-8:]}' ({len(m[1])} characters)", message)


def mid_sentence(reason: str) -> str:
    """An OS or library reason ("No space left on device", "Port out of range 0-65535") as it reads
    after a colon inside a message: its first letter lower-cased."""
    return reason[:1].lower() + reason[1:]


UNRECOGNIZED = "unrecognized arguments: "  # argparse's message of words no option or argument took
NEAR_MISS_EDITS = 2  # edits (edits()) within which an unknown option of five letters or more is a near miss of a known one
#: a word that is a negative number, not an option: argparse 3.11 takes -5 and -.5 only, so `--seed -1e3`,
#: `--duration -inf` and a valid `--laser-angle-min-deg -9e1` (or -90.) said "expected one argument"
NEGATIVE_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|infinity|nan)$", re.IGNORECASE)


def edits(a: str, b: str) -> int:
    """The fewest single-letter insertions, deletions, substitutions and swaps of neighbours that
    turn ``a`` into ``b`` (optimal string alignment distance)."""
    d = [[i + j if i * j == 0 else 0 for j in range(len(b) + 1)] for i in range(len(a) + 1)]
    for i in range(1, len(a) + 1):
        for j in range(1, len(b) + 1):
            d[i][j] = min(d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] != b[j - 1]))
            if i > 1 and j > 1 and a[i - 1] == b[j - 2] and a[i - 2] == b[j - 1]:
                d[i][j] = min(d[i][j], d[i - 2][j - 2] + 1)
    return d[len(a)][len(b)]


class OneLineParser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line, ``PROG: error: MESSAGE``, exit status 2
    (argparse's own prints the usage first). Options are spelled out: no abbreviations (``--dur 3``
    ran as ``--duration 3``, and an option added later would change what an old command line means)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("allow_abbrev", False)
        kwargs.setdefault("formatter_class", HelpFormatter)
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NEGATIVE_NUMBER  # no option here looks like a number (-1): a value
        self.root: argparse.ArgumentParser | None = None  # the whole command line's parser (set_root): other commands' options

    def set_root(self) -> None:
        """Make this parser the root of every (sub)command parser below it, for :meth:`elsewhere`."""
        for _, parser in command_parsers(self):
            if isinstance(parser, OneLineParser):
                parser.root = self

    def _print_message(self, message: str, file: Any = None) -> None:
        """argparse's, except that a standard output that cannot be written (``--help > /dev/full``)
        raises the OSError (argparse swallowed it: nothing written, exit status 0); a reader that went
        away (BrokenPipeError) and a standard error that cannot be written are still passed over
        (``experiments.cli`` says the first as a shell does, and the second has nowhere to be said)."""
        if not message:
            return
        file = file or sys.stderr
        try:
            file.write(message)
            if file is sys.stdout:
                file.flush()
        except BrokenPipeError:
            pass
        except OSError:
            if file is sys.stdout:
                raise
        except AttributeError:  # no stream (pythonw): as argparse
            pass

    def error(self, message: str) -> None:  # type: ignore[override]
        elsewhere = ""
        if message.startswith(UNRECOGNIZED):
            words = message[len(UNRECOGNIZED):].split()
            message += self.near_misses(words)
            elsewhere = self.elsewhere(words)
        self.exit(2, f"{self.prog}: error: {shorten_quoted(message)} ({elsewhere}see {self.prog} --help)\n")

    def elsewhere(self, words: Sequence[str]) -> str:
        """"--max-scans is an option of: compare, slam; " for the unrecognized options among ``words``
        that other (sub)commands take, or "" for none: an option given to the wrong command said
        only "unrecognized arguments"."""
        if self.root is None:
            return ""
        where: dict[str, list[str]] = {}
        for word in words:
            name = word.split("=", 1)[0]
            if not name.startswith("-") or name in ("-", "--") or name in self._option_string_actions or name in where:
                continue
            owners = [" ".join(path) for path, parser in command_parsers(self.root)
                      if parser is not self and name in parser._option_string_actions]
            if owners:
                where[name] = owners
        return "".join(f"{name} is an option of lmsbench itself, given before the command; " if owners == [""] else
                       f"{name} is an option of: {', '.join(o or 'lmsbench' for o in owners)}; " for name, owners in where.items())

    def near_misses(self, words: Sequence[str]) -> str:
        """"; did you mean --seeds?" for the unrecognized option ``words`` that are a near miss of
        one of this parser's options (``compare --seed 1``: simulate and demo take --seed, compare
        and sim2real --seeds; argparse 3.11 says only "unrecognized arguments"), or "" for none:
        the start of exactly one option (abbreviations are not taken: ``--dur``), else within
        NEAR_MISS_EDITS edits (a letter added, left out, changed, or two swapped; one for names of
        up to four letters)."""
        options = [o for o in self._option_string_actions if o.startswith("--")]
        pairs = []
        for word in words:
            name = word.split("=", 1)[0]
            if not name.startswith("-") or name in ("-", "--") or name in self._option_string_actions:
                continue
            bare = name.lstrip("-")  # -seeds, ---seeds
            starts = [o for o in options if o.startswith("--" + bare)] if len(bare) > 1 else []
            if len(starts) == 1:
                pairs.append((name, starts[0]))
                continue
            allowed = 1 if len(bare) <= 4 else NEAR_MISS_EDITS
            distance, best = min(((edits(bare, o[2:]), o) for o in options), default=(allowed + 1, ""))
            if distance <= allowed:
                pairs.append((name, best))
        if not pairs:
            return ""
        if len(pairs) == 1:
            return f"; did you mean {pairs[0][1]}?"
        return "; did you mean " + ", ".join(f"{right} for {wrong}" for wrong, right in pairs) + "?"

    def parse_known_args(self, args: Sequence[str] | None = None, namespace: Any = None) -> Any:  # type: ignore[override]
        """As argparse, but an option that takes a value given twice is an error: argparse kept the
        last (``simulate --seed 1 ... --seed 2`` ran seed 2, ``--out a ... --out b`` wrote b).
        Repeatable options (``action="append"``: ``--set``, ``--sweep``) and flags pass."""
        import sys

        given: dict[str, list[str]] = {}
        for arg in (sys.argv[1:] if args is None else list(args)):
            if arg == "--":
                break
            name = arg.split("=", 1)[0] if arg.startswith("--") else arg
            action = self._option_string_actions.get(name)
            if action is None or action.nargs == 0 or isinstance(action, (argparse._AppendAction, argparse._CountAction)):
                continue
            given.setdefault(action.dest, []).append(name)
        for names in given.values():
            if len(names) > 1:
                self.error(f"argument {'/'.join(dict.fromkeys(names))}: given {len(names)} times; give it once")  # each spelling used
        return super().parse_known_args(args, namespace)


def command_parsers(parser: argparse.ArgumentParser, path: tuple[str, ...] = ()
                    ) -> list[tuple[tuple[str, ...], argparse.ArgumentParser]]:
    """``parser`` and every (sub)command parser below it, each once with its command words
    (``("lms200", "emulate")``; an alias's parser under its first name), depth first."""
    found = [(path, parser)]
    seen = {id(parser)}
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for word, sub in action.choices.items():
                if id(sub) not in seen:
                    seen.add(id(sub))
                    found += command_parsers(sub, (*path, word))
    return found


def number_text(value: float) -> str:
    """``value`` as a command line would give it back exactly: the short form (``40``, ``0.5``)
    where that reads back as the same float, else the shortest exact one (``repr``); a Reproduce
    line gave ``--duration 12.3457`` for a run of 12.3456789 s."""
    short = f"{value:g}"
    return short if float(short) == value else repr(float(value))


class Underflow(ValueError):
    """A number written nonzero that float64 reads as 0 (``lms200.finite.underflow_problem``)."""


def plain_number(text: str, integer: bool = False) -> float:
    """``int(text)`` or ``float(text)`` of a number as a command line writes it; ValueError also for
    underscores and non-ASCII digits, which Python reads ("1_0" as 10 and "٣" as 3: a typo of 1.0
    ran 10 s) and the CARMEN reader refuses, as strtod does; :class:`Underflow` (a ValueError, its
    message the reason) for a number written nonzero that reads as 0 (``--clutter 1e-400`` ran
    an empty office)."""
    if "_" in text or not text.isascii():
        raise ValueError(f"not a plain number: {text!r}")
    if integer:
        return int(text)
    value = float(text)
    problem = underflow_problem(text, value)
    if problem:
        raise Underflow(problem)
    return value


def plain(integer: bool = False) -> Callable[[str], float]:
    """An argparse type: ``plain_number`` of the word, for an option with ``choices`` (``simulate
    --resolution-deg``, ``lms200 record --baud / --fov-deg / --resolution-deg``), whose range the
    choices say. ``type=float`` / ``int`` took "1_80" as 180, "٣٨٤٠٠" as 38400 and "1\\xa0" as 1: a
    word that is no plain number is argparse's "invalid float value" (``int``: "invalid int value");
    one that underflows says so."""

    def parse(text: str) -> float:
        try:
            return plain_number(text, integer)
        except Underflow as exc:  # --resolution-deg 1e-400 said "invalid choice: 0.0"
            raise argparse.ArgumentTypeError(f"got {text!r}: {exc}") from None

    parse.__name__ = "int" if integer else "float"  # argparse's message: "invalid float value: '1_0'"
    return parse


def number(lo: float | None = None, hi: float | None = None, *, lo_open: bool = False, unit: str = "",
           integer: bool = False) -> Callable[[str], float]:
    """An argparse type: a finite number in [lo, hi] (lo excluded with ``lo_open``)."""
    parts = []
    shown = (lambda v: str(int(v))) if integer else (lambda v: f"{v:g}")  # a seed's 2**32 - 1, not 4.29497e+09
    if lo is not None:
        parts.append(f"{'>' if lo_open else '>='} {shown(lo)}")
    if hi is not None:
        parts.append(f"<= {shown(hi)}")
    what = ("a whole number" if integer else "a finite number") + (" " + " and ".join(parts) if parts else "")
    what += f" {unit}" if unit else ""

    def parse(text: str):
        try:
            value = plain_number(text, integer)
        except Underflow as exc:
            raise argparse.ArgumentTypeError(f"must be {what}, got {text!r}: {exc}") from None
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be {what}, got {text!r}") from None
        try:
            bad = not math.isfinite(value) or (lo is not None and (value <= lo if lo_open else value < lo)) \
                or (hi is not None and value > hi)
        except OverflowError:  # a whole number of 400 digits: --seed, --stride, --max-scans were a traceback
            # beyond a stated upper bound the range says why (--seed said it, then "too large for a float")
            why = "" if hi is not None else " (too large for a float)"
            raise argparse.ArgumentTypeError(f"must be {what}, got {text!r}{why}") from None
        if bad:
            raise argparse.ArgumentTypeError(f"must be {what}, got {text!r}")
        return value

    parse.__name__ = "integer" if integer else "number"  # argparse names the type in some messages
    return parse


def positive(unit: str = "") -> Callable[[str], float]:
    """A finite number > 0 (durations, rates, noise)."""
    return number(0.0, lo_open=True, unit=unit)


def scan_rate(text: str) -> float:
    """An argparse type: scans kept per second, a finite number >= ``lms200.timing.MIN_RATE_HZ`` (one
    scan an hour): `--rate-hz 1e-308` ran and kept the first scan alone. The sensor's own rate, the
    ceiling, depends on its resolution and is checked where that is known (``check_scan_rate``)."""
    from lms200.timing import MIN_RATE_HZ, RATE_FLOOR_TEXT

    value = positive("scans/s")(text)
    if value < MIN_RATE_HZ:
        raise argparse.ArgumentTypeError(f"must be at least {RATE_FLOOR_TEXT}, got {text!r}")
    return value


scan_rate.__name__ = "number"  # argparse names the type in some messages


#: the largest count an option takes without a bound of its own: int64's, as the library's counts
#: (``lms200.finite.check_integer``)
MAX_COUNT = 2**63 - 1


def count(lo: int = 1, hi: int | None = None) -> Callable[[str], float]:
    """A whole number >= lo (scan counts, strides, workers), at most ``hi`` or else int64's bound
    (``MAX_COUNT``): `compare --stride 99999999999999999999999` passed the options, compiled the
    kernels and read the log, then stopped on the library's "stride: must be an integer in 1..2^63 - 1"."""
    parse_number = number(lo, hi, integer=True)
    if hi is not None:
        return parse_number
    beyond = f"must be a whole number >= {lo} and at most 2^63 - 1, got {{!r}}"

    def parse(text: str) -> float:
        digits = text.strip().removeprefix("+").lstrip("0")
        if digits.isascii() and digits.isdigit() and len(digits) > 19:  # beyond 2^63 - 1 whatever its size: 309
            raise argparse.ArgumentTypeError(beyond.format(text))  # digits said "too large for a float", 5,000 "not a whole number"
        value = parse_number(text)
        if value > MAX_COUNT:
            raise argparse.ArgumentTypeError(beyond.format(text))
        return value

    parse.__name__ = "integer"
    return parse


def path_arg(text: str) -> Path:
    """An argparse type: a path, not empty. Path("") is "." (`--out "$OUT"` with OUT unset wrote
    into the current folder)."""
    if not text.strip():
        raise argparse.ArgumentTypeError(f"empty path {text!r}; give a file or folder name")
    if text == "-":  # no command streams a file: `simulate --out -` made a folder named '-', `calibrate --out -` a file
        raise argparse.ArgumentTypeError("'-' is no stream here: give a file or folder name (calibrate without --out "
                                         "prints its YAML)")
    return Path(text)


def text(what: str) -> Callable[[str], str]:
    """An argparse type: a word that is not empty nor blank, ``what`` naming what to give instead.
    An empty value read as "not given" (`--extractor "$M"` with M unset ran the default extractor,
    `--scheduler ""` a local cluster) or as everything (`--host ""` listened on every interface)."""

    def parse(value: str) -> str:
        if not value.strip():
            raise argparse.ArgumentTypeError(f"must not be empty, got {value!r}; give {what}")
        return value

    parse.__name__ = "text"
    return parse


SEED = count(0, 2**32 - 1)


def listed_seed(text: str) -> float:
    """A seed of a ``--seeds`` list (compare, sim2real): a range written as one word (``0-23``, as
    the README names seed sets) is refused saying how to list it; it said only "must be a whole number"."""
    try:
        return SEED(text)
    except argparse.ArgumentTypeError as error:
        span = re.fullmatch(r"(\d+)(?:-|\.\.|:)(\d+)", text.strip())
        if span is None or int(span[1]) >= int(span[2]):
            raise
        first, last = int(span[1]), int(span[2])
        listed = (" ".join(str(s) for s in range(first, last + 1)) if last - first < 6
                  else f"$(seq {first} {last}) in a shell, or {first} {first + 1} ... {last} written out")
        raise argparse.ArgumentTypeError(f"{error}; the seeds are listed one by one, not as a range: {listed}") from None


listed_seed.__name__ = "integer"
DURATION = number(MIN_DURATION_S, MAX_DURATION_S, unit="s")  # a simulated run: at least one scan
PORT = count(0, 65535)


def check_seeds(seeds: Sequence[int], flag: str = "--seeds") -> list[int]:
    """Seeds given once each (a repeated seed would count the same run twice in every mean). One
    count of them: a count per seed over a copy of the list was quadratic in it, and
    ``sim2real()`` passes a caller's list of any length."""
    from collections import Counter

    seen = sorted(s for s, n in Counter(seeds).items() if n > 1)
    if seen:
        raise InputError(f"{flag}: seed(s) {', '.join(map(str, seen))} given more than once")
    return list(seeds)


def world_name(text: str) -> str:
    """A built-in world's name."""
    if text not in known_worlds():
        raise argparse.ArgumentTypeError(f"unknown world {text!r}{world_hint(text)}; known worlds: "
                                         f"{', '.join(known_worlds())}")
    return text


def world_hint(text: str) -> str:
    """" (did you mean office?)" for a known world's name in other case or with spaces around it, and
    " (a folder holding world.json: give DIR/world.json)" for a simulate folder given as a world; else ""."""
    near = [w for w in known_worlds() if w == text.strip().lower()]
    if near:
        return f" (did you mean {near[0]}?)"
    try:
        held = (Path(text) / "world.json").is_file()
    except (OSError, ValueError):  # a name too long for a path, a NUL in it
        held = False
    return f" (a folder holding world.json: give {Path(text) / 'world.json'})" if held else ""


def _head(path: Path, n: int = 4096, what: str = "an input") -> bytes:
    """The first ``n`` bytes of a regular file. A pipe with no writer (``mkfifo``) hung the command
    on open(); one with a writer (``<(zcat log.gz)``) would lose these bytes to the check. A pipe
    (``--config <(cat x.yaml)``, ``--config /dev/stdin`` fed by a pipe) is refused saying why: a
    file is checked before it is read."""
    if path.exists() and not path.is_dir() and not path.is_file():
        if stat.S_ISFIFO(path.stat().st_mode):
            raise InputError(f"{path}: not a regular file but a pipe (<(cat FILE), /dev/stdin fed by a pipe, a FIFO): "
                             f"{what} must be a regular file, as it is checked before it is read and a pipe's bytes "
                             "are gone once read; give the file itself (or save the stream to a file first)")
        raise InputError(f"{path}: not a regular file (a device or a socket); give the file itself")
    try:
        with open(path, "rb") as fh:
            return fh.read(n)
    except PermissionError:
        raise InputError(f"{path}: not readable (permission denied)") from None
    except IsADirectoryError:
        raise InputError(f"{path} is a folder, not a file") from None
    except OSError as exc:  # /proc/self/mem: "[Errno 5] Input/output error", without the file's name
        raise InputError(f"{path}: cannot be read ({exc.strerror or exc})") from None


MAX_ODD_BYTES = 0.05  # share of a log's first 4 KB that may be control bytes or >= 0x80 (a latin-1 comment)


def _text_head(path: Path, what: str, utf8: bool = True, head: bytes | None = None) -> None:
    """Raise InputError unless the file starts with text (not binary, not a mislabelled or broken
    compressed file, not an archive), read through gzip / bzip2 / xz where compressed. ``utf8``:
    the text must be UTF-8 (YAML, read as UTF-8); else (a log, read as ASCII with other bytes
    replaced) a byte that is not UTF-8 is text too, unless control bytes or bytes >= 0x80 make up
    more than MAX_ODD_BYTES of the head (a latin-1 comment in a log's first 4 KB refused a log
    that the same comment further down did not). ``head``: the file's first 4 KB where the caller
    read them already (``check_log``), else read here."""
    head = _head(path, what=what) if head is None else head
    kind = compression(head)
    named = COMPRESSION_SUFFIXES.get(path.suffix)
    if named and kind != named:
        raise InputError(f"{path}: named {path.suffix} but not {named}-compressed")
    if kind and utf8:  # YAML is read as plain text: a .gz passed the check, then 'utf-8' codec can't decode 0x8b
        raise InputError(f"{path}: {head_problem(head, what)}")
    if kind:
        try:
            with open_bytes(path) as fh:
                head = fh.read(4096)
        except READ_ERRORS as exc:
            raise InputError(f"{path}: broken {kind} file ({exc})") from None
    problem = head_problem(head, what, packed=False, carmen=utf8)  # an archive or binary data, compressed or not;
    # a CARMEN log where a YAML file is read (a log itself is read with utf8=False)
    if problem:
        raise InputError(f"{path}: {problem}")
    if not utf8:
        odd = sum(1 for b in head if b >= 0x80 or (b < 0x20 and b not in b"\t\n\r\f\v"))
        if odd > MAX_ODD_BYTES * len(head):
            raise InputError(f"{path}: a binary file ({odd} of its first {len(head)} bytes are not ASCII text), "
                             f"not {what}")
        return
    try:
        head.decode("utf-8")
    except UnicodeDecodeError as exc:
        if exc.start < len(head) - 4:  # a multi-byte character cut at the end of the block is fine
            raise InputError(f"{path}: not text (byte {exc.start} is not UTF-8), not {what}") from None


def missing_message(p: Path, what: str) -> str:
    """Why an input path does not exist: no such file, or a symbolic link to nothing (data moved, a loop)."""
    if p.is_symlink():
        try:
            target = os.readlink(p)
        except OSError:
            target = "?"
        return f"{p}: a symbolic link to {target}, which does not exist (or a loop of links)"
    return f"{p}: no such {what}{_near_name(p)}"


def _near_name(p: Path) -> str:
    """" (did you mean NAME?)" for a missing path whose folder holds it compressed (`info mit-csail.clf`
    beside mit-csail.clf.gz: "no such log", and no more) or a name one slip away; else ""."""
    import difflib

    folder = p.parent
    try:
        names = [e.name for _, e in zip(range(10_000), os.scandir(folder))]  # a huge folder: the first 10,000
    except OSError:
        return ""
    found = [p.name + suffix for suffix in COMPRESSION_SUFFIXES if p.name + suffix in names]
    found = found or difflib.get_close_matches(p.name, names, n=1, cutoff=0.85)
    return f" (did you mean {folder / found[0] if str(folder) != '.' else found[0]}?)" if found else ""


def check_file(path: str | os.PathLike, what: str = "a file") -> Path:
    """An existing, readable regular file."""
    p = Path(path)
    if not p.exists():
        raise InputError(missing_message(p, "file"))
    if p.is_dir():
        raise InputError(f"{p} is a folder, not {what}")
    _head(p, 1, what)
    return p


def check_world_file(world: str) -> None:
    """A world named by its world.json (``simulate --world``, a sweep's ``world``; a relative path is
    read from the current folder): loaded now, so that a missing or bad one is an error before
    anything is simulated. A built-in world's name passes."""
    if not world.endswith(".json"):
        return
    from lms200 import LmsbenchError
    from sim import World

    check_file(world, "a world.json")
    try:
        World.from_json(world)
    except LmsbenchError:
        raise
    except (ValueError, KeyError, TypeError) as exc:
        raise InputError(f"{world}: not a world.json ({type(exc).__name__}: {' '.join(str(exc).split())})") from None


#: what the size refusal of a simulate folder's config.yaml names it, and how large one is
SIMULATE_CONFIG = "a simulate folder's config.yaml"
SIMULATE_CONFIG_SIZE = "lmsbench simulate writes one of a few KB at most"


def simulate_config_size_problem(cfg: Path) -> str | None:
    """Why a simulate folder's config.yaml ``cfg`` is not read for its size (None: it may be), from its
    size alone; raises (``regular_file``) where it is no regular file."""
    from lms200.logs import regular_file

    return size_problem(regular_file(cfg, "simulate config").stat().st_size, SIMULATE_CONFIG, SIMULATE_CONFIG_SIZE)


def load_simulate_config(cfg: Path) -> Any:
    """The parsed config.yaml ``cfg`` of a simulate folder, as ``compare`` and ``slam`` both read it:
    with YAML 1.1's words (``lms200.yamlio.load(words=True)``: a record of an earlier version, or
    one edited by hand, may say ``interlaced: no``). slam read it with the strict loader and refused
    a ``name: n`` that compare read (a review). Raises what ``load`` raises, and OSError /
    UnicodeDecodeError of reading it; the callers name the file."""
    return load_yaml(cfg.read_text(), words=True)


def check_yaml(path: str | os.PathLike, what: str = "a YAML file", sized: bool = True,
               size_hint: str = "they are a few KB") -> Path:
    """An existing, readable text file, of at most ``lms200.yamlio.MAX_YAML_BYTES`` when ``sized`` (a
    file the user writes; not the sweep.yaml a sweep wrote, which lists a grid one value a line). YAML
    is parsed by the caller, which names its errors."""
    p = check_file(path, what)
    _text_head(p, what)
    too_big = size_problem(p.stat().st_size, what, size_hint) if sized else None
    if too_big:
        raise InputError(f"{p}: {too_big}")
    _utf8(p, what)
    return p


def _utf8(p: Path, what: str) -> None:
    """Raise InputError unless the whole file is UTF-8, as its reader decodes it: the head's check
    (:func:`_text_head`, 4 KB) passed a byte beyond it, and one in the last 4 bytes of a short file
    (taken for a character cut at the end of the block), and ``read_text`` failed after: `slam
    --config`, `simulate --config` and `figures --sweep` said "internal error: UnicodeDecodeError"."""
    try:
        p.read_bytes().decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(f"{p}: not text (byte {exc.start} is not UTF-8), not {what}") from None


def check_simulate_finished(path: str | os.PathLike) -> None:
    """Raise InputError when ``path``, a folder or one of the files ``lmsbench simulate`` writes
    (SIMULATE_OUTPUTS; through a link: where it points), is in a folder whose simulate run did not
    finish (its SIMULATE_UNFINISHED file is there): its scans.clf may be cut short, or an earlier
    run's beside the new run's config.yaml. The file holds that run's settings (a simulate config,
    since the marker held them), so the error names ``simulate --config DIR/.simulate-unfinished
    --out DIR``: "run lmsbench simulate --out DIR again" ran the defaults, and config.yaml may still
    be the earlier run's (a run stopped before writing it)."""
    p = Path(path)
    folders = [p] if p.is_dir() else [q.parent for q in _output_names(p, SIMULATE_OUTPUTS)]
    for folder in folders:
        if not os.access(folder, os.X_OK):  # said "FOLDER/.simulate-unfinished: permission denied", a file not given
            raise InputError(f"{folder}: folder cannot be read (permission denied: its files cannot be opened)")
        marker = folder / SIMULATE_UNFINISHED
        if marker.exists():
            rerun = (f"rerun it with lmsbench simulate --config {marker} --out {folder} (that file holds its settings)"
                     if SIMULATE_OWNER.records["config.yaml"](marker) else  # a marker from before it held them
                     f"run lmsbench simulate --out {folder} again with the options the run was given")
            raise InputError(f"{folder}: the lmsbench simulate run that wrote this folder did not finish (it was stopped "
                             f"or killed while writing its files; {SIMULATE_UNFINISHED} is left), so its scans.clf may be "
                             f"cut short or an earlier run's; {rerun}")


def check_sim2real_finished(path: str | os.PathLike, flag: str = "") -> None:
    """Raise InputError when ``path`` (``flag``'s value; through a link: where it points) is a file
    ``lmsbench sim2real`` writes (SIM2REAL_OUTPUTS: its sensor.yaml is a sensor model of its own) in a
    folder whose run did not finish (its SIM2REAL_UNFINISHED file is there): the file is then an
    earlier run's, beside the new run's tables, or the tables are cut short of it."""
    for q in _output_names(Path(path), SIM2REAL_OUTPUTS):
        if (q.parent / SIM2REAL_UNFINISHED).exists():
            raise InputError(f"{flag + ' ' if flag else ''}{path}: the lmsbench sim2real run that wrote {q.parent} did not finish (it was "
                             f"stopped or killed while writing its files; {SIM2REAL_UNFINISHED} is left, holding its "
                             f"settings), so its {q.name} is an earlier run's or of a run cut short; run that "
                             f"lmsbench sim2real --out {q.parent} again")


def _output_names(p: Path, outputs: tuple[str, ...]) -> list[Path]:
    """``p`` and, through a link, where it points, those of them named as one of a command's ``outputs``."""
    try:
        real = p.resolve()
    except (OSError, RuntimeError):  # a loop of links: the reader says so
        real = p
    return [q for q in dict.fromkeys((p, real)) if q.name in outputs]


def simulate_log(path: str | os.PathLike) -> Path | None:
    """The log of a ``lmsbench simulate`` output folder, its scans.clf (a CARMEN log with the true
    poses), or None when ``path`` is not such a folder. The one test of every command that reads a
    log: slam and compare took a simulate folder, info, calibrate, sim2real, figures --log and
    lms200 emulate --log said it was "a folder but not a ROS 2 bag"."""
    p = Path(path)
    log = p / SIMULATE_LOG
    return log if p.is_dir() and log.is_file() else None


def not_a_log_folder(path: str | os.PathLike) -> str:
    """The message of a folder given as a log that is neither kind of folder a log may be. A scans.clf
    that is there but no regular file is named so: it said "(no scans.clf)" of a folder, a pipe, a link to
    /dev/zero or to nothing in its place (fuzzing); so is a metadata.yaml (it said "no metadata.yaml": fuzz4)."""
    from lms200.logs import missing_file_reason

    meta, log = missing_file_reason(Path(path) / "metadata.yaml"), missing_file_reason(Path(path) / SIMULATE_LOG)
    return f"{path} is a folder but neither a ROS 2 bag ({meta}) nor a lmsbench simulate folder ({log})"


def real_path(path: str | os.PathLike) -> Path:
    """``path`` with its links followed (``os.path.realpath``): ``Path.resolve()`` raised RuntimeError
    ("Symlink loop from ...") on a loop of links, an internal error (`compare LOOP`, `simulate
    --config LOOP`); a loop is left as it is, for the check that says so by name."""
    return Path(os.path.realpath(path))


def check_log(path: str | os.PathLike) -> Path:
    """The log to read for ``path``, checked: a CARMEN log (plain text, or compressed with gzip,
    bzip2 or xz), a ROS 1 ``.bag``, a ROS 2 bag folder, or a ``lmsbench simulate`` folder (its
    scans.clf is returned: :func:`simulate_log`), by its content: a binary file, an archive, a
    plain file named ``.gz``, a folder that is neither kind are errors; so is the scans.clf (or
    folder) of a ``lmsbench simulate`` run that did not finish (check_simulate_finished)."""
    if not str(path).strip():  # Path("") is the current folder
        raise InputError(f"empty path {str(path)!r} given as a log; give {'a CARMEN log, ROS 1 .bag or ROS 2 bag folder'}")
    p = Path(path)
    check_simulate_finished(p)
    what = "a CARMEN log, ROS 1 .bag or ROS 2 bag folder"
    if not p.exists():
        raise InputError(missing_message(p, "log"))
    sim_log = simulate_log(p)
    if sim_log is not None:
        return check_log(sim_log)
    if p.is_dir():
        meta = p / "metadata.yaml"
        if not meta.is_file():
            raise InputError(not_a_log_folder(p))
        from lms200.bag import check_metadata_size

        check_metadata_size(p)  # before anything parses it: a 5.5 MB one took minutes, 1 GB
        _text_head(meta, "a ROS 2 bag's metadata.yaml")
        _utf8(meta, "a ROS 2 bag's metadata.yaml")
        try:  # rosbags said "Could not load YAML ... in "<unicode string>", line 1, ..." over several lines
            info = load_yaml(meta.read_text(encoding="utf-8"), words=True)  # rosbag2 writes it, not our users
        except yaml.YAMLError as exc:
            raise InputError(f"{meta}: not valid YAML ({exc})") from None
        if not isinstance(info, dict) or not isinstance(info.get("rosbag2_bagfile_information"), dict):
            raise InputError(f"{meta}: not a ROS 2 bag's metadata.yaml (no rosbag2_bagfile_information mapping)")
        return p
    if stat.S_ISFIFO(p.stat().st_mode):  # <(zcat LOG): refused as every pipe is, saying why
        raise InputError(f"{p}: a pipe (such as <(zcat LOG)), not a file: {PIPE_REASON}")
    from lms200.logs import bag_member_message, simulate_member_message

    # a bag's .db3 was "a binary file", its metadata.yaml "not a CARMEN log"; a simulate folder's world.json too
    member = bag_member_message(p) or simulate_member_message(p, give_folder=True)
    if member is not None:
        raise InputError(member)
    head = _head(p)
    if p.suffix == ".bag":
        if not head.startswith(b"#ROSBAG V2.0"):
            raise InputError(f"{p}: named .bag but not a ROS 1 bag (no #ROSBAG V2.0 header)")
        return p
    if not head:
        raise InputError(f"{p}: empty file, not {what}")
    _text_head(p, what, utf8=False, head=head)  # the reader reads ASCII, other bytes replaced
    return p



@contextmanager
def warnings_after_checks() -> Iterator[None]:
    """Hold the warnings raised in the block, a command's checks of its inputs before any work (a sensor
    or sweep file read in an old spelling), and say them as it ends; a user error in it is its one line
    alone, the warnings of the run it refused unsaid: `simulate --sensor OLD.yaml --rate-hz 1e9` said the
    old spelling's warning, then the rate's error (every user error is one line). Only the showing is
    held: the filters are left as they are (a user's cell module that silences its own warnings when a
    check imports it keeps them silenced; ``catch_warnings`` put the filters back as they were)."""
    if threading.current_thread() is not threading.main_thread():  # showwarning is the process's: a thread's
        yield  # swap could be undone out of order by another's, and every later warning held for ever
        return
    held: list[tuple[Any, ...]] = []
    say = warnings.showwarning

    def hold(*args: Any) -> None:  # noqa: ANN401 - showwarning's arguments, as the warnings module passes them
        held.append(args)

    warnings.showwarning = hold
    try:
        yield
    finally:
        warnings.showwarning = say
    for args in held:
        say(*args)


@contextmanager
def said_after_checks() -> Iterator[list[str]]:
    """:func:`warnings_after_checks`, and the lines a command's checks print on stderr (its notes and
    own warnings, appended to the list it yields) said after them once they pass: `slam LOG --odometry`
    on a log whose steps take no time said that warning, then the error that the log has no odometry."""
    lines: list[str] = []
    with warnings_after_checks():
        yield lines
    for line in lines:
        print(line, file=sys.stderr)


SIMULATE_OUTPUTS = (SIMULATE_LOG, *SIMULATE_OTHER_FILES)
#: The hidden file ``lmsbench simulate`` writes into its --out folder before any of its outputs and
#: removes once they are all whole (experiments.simulation.run_simulation): a run stopped or killed
#: while writing (Ctrl-C, SIGKILL, a crash, a power loss) leaves it, and the readers of the folder
#: refuse it (check_simulate_finished). A killed run left a cut scans.clf (or the earlier run's files
#: beside its new config.yaml) that slam, info, compare and sim2real read as a shorter run, exit 0.
#: A folder from before this file has none and reads as before. It holds the run's settings (a
#: simulate config under a comment), so ``simulate --config DIR/.simulate-unfinished --out DIR`` reruns it.
SIMULATE_UNFINISHED = ".simulate-unfinished"
SLAM_OUTPUTS = ("trajectory.tum", "keyframes.tum", "map.json", "metrics.json", "config.yaml", "slam.png")
COMPARE_OUTPUTS = ("compare.parquet", "compare.csv", "summary.csv", "summary.txt", "config.yaml")  # and a figure per log
COMPARE_FIGURES = ("realdata_*.png", "realdata_*.pdf", "realdata_*.csv")  # a log's figure and its rows (figures.realdata)
SIM2REAL_OUTPUTS = ("sim2real.csv", "scene.csv", "sim2real.md", "sim2real.png", "sensor.yaml", "config.yaml")
#: The hidden file ``lmsbench sim2real`` (and the demo, in its sim2real/) writes into its folder before
#: its outputs and removes once they are all whole (experiments.sim2real.write_outputs), as simulate's
#: SIMULATE_UNFINISHED: a run stopped while writing (Ctrl-C, SIGTERM at the figure) left its tables and
#: report without sim2real.png and sensor.yaml, or beside an earlier run's, with nothing to tell it. The
#: readers of its sensor.yaml (``--sensor``, a sweep's ``sensor_file``) refuse it
#: (check_sim2real_finished); the next run into the folder takes it. It holds the run's settings.
SIM2REAL_UNFINISHED = ".sim2real-unfinished"
BENCH_OUTPUTS = ("bench.csv", "versions.yaml")


@dataclass(frozen=True)
class OutTree:
    """What a command writes into a folder: files (names or shell patterns) and sub-folders, each an
    OutTree of its own. A file pattern matches files only, a sub-folder's name folders only."""

    files: tuple[str, ...] = ()
    folders: Mapping[str, "OutTree"] = field(default_factory=dict)

    def entries(self, folder: Path, prefix: str = "") -> list[tuple[str, bool]]:
        """The entries of ``folder`` (recursively, as ``sub/name``; a folder not of this tree as
        ``name/``), each with whether this tree writes it; hidden entries (a temporary file of an
        atomic write) are left out. One walk for :meth:`present` and :meth:`foreign`."""
        out: list[tuple[str, bool]] = []
        for e in sorted(folder.iterdir(), key=lambda e: e.name):
            if e.name.startswith("."):
                continue
            if e.name in self.folders and e.is_dir() and not e.is_symlink():
                out += self.folders[e.name].entries(e, f"{prefix}{e.name}/")
            elif e.is_dir():
                out.append((f"{prefix}{e.name}/", False))
            else:
                out.append((f"{prefix}{e.name}", any(fnmatch.fnmatchcase(e.name, pat) for pat in self.files)))
        return out

    def present(self, folder: Path) -> list[str]:
        """The files of ``folder`` (recursively, as ``sub/name``) of this tree's names."""
        return [name for name, ours in self.entries(folder) if ours]

    def foreign(self, folder: Path) -> list[str]:
        """The entries of ``folder`` (recursively, as ``sub/name``) this tree does not write; hidden
        entries (a temporary file of an atomic write) pass."""
        return [name for name, ours in self.entries(folder) if not ours]

    def named(self, prefix: str = "") -> set[str]:
        """The files this tree names exactly (``sub/name``), not by a pattern (``sweep_*``: a user's
        ``sweep_notes.csv`` matches it too)."""
        out = {f"{prefix}{name}" for name in self.files if not any(c in name for c in "*?[")}
        for sub, tree in self.folders.items():
            out |= tree.named(f"{prefix}{sub}/")
        return out


def _figure_files(stems: Sequence[str]) -> tuple[str, ...]:
    """The files of experiments.style.save_figure for each stem: STEM.png, STEM.pdf, STEM.csv, STEM_NAME.csv."""
    return tuple(f"{stem}{end}" for stem in stems for end in (".png", ".pdf", ".csv", "_*.csv"))


#: ``figures``: its record (figures.yaml), the paper's figures, a figure per sweep and metric, and
#: (unless --tables) the tables behind them (experiments.figures.make, figures.study.save_tables).
STUDY_TABLES = OutTree(("*.parquet", "study.yaml", "notes.txt"))
FIGURES_OUTPUTS = OutTree(("figures.yaml",) + _figure_files((
    "fig3_scan", "fig4_ad", "fig5_theta", "fig6_psi", "fig7_timing", "fig9_office", "fig9_intel", "fig10_slam",
    "accuracy_speed", "sweep_*")), {"tables": STUDY_TABLES})
#: The files behind FIGURES_OUTPUTS's patterns that a figures run writes by name (Owner.remove_earlier's ``also``:
#: a user's file matching a pattern is never removed): the tables save_figure writes beside Fig. 9 and Fig. 10
#: (experiments.figures.draw's ``data=`` names; a test checks them against a drawn folder).
FIGURE_PART_FILES = (tuple(f"fig9_{source}_{part}.csv" for source in ("office", "intel") for part in ("points", "lines", "corners"))
                     + ("fig10_slam_trajectory.csv", "fig10_slam_map.csv"))
#: A sweep folder (experiments.sweep.store).
SWEEP_OUTPUTS = OutTree(("sweep.yaml", "versions.yaml", "results.parquet", "results.csv"),
                        {"cells": OutTree(("*.parquet",))})
#: The demo's sweep (experiments.demo): window size k of the paper's extractor against range noise (a few seconds).
DEMO_SWEEP: dict[str, Any] = {
    "name": "demo_k_vs_noise",
    "kind": "extract",
    "description": "sensor-coordinate extractor: window k against range noise (demo size)",
    "fixed": {"method": "sensor", "world": "office", "duration": 3.0, "rate_hz": 4.0},
    # the extractor is told the sensor's range noise (sigma_r), as for a sensor of known noise
    "grid": {"sensor.noise_sigma,extractor.sigma_r": [[0.002, 0.002], [0.01, 0.01], [0.03, 0.03]],
             "extractor.k": [3, 5, 10]},
    "seeds": [0],
}
#: ``demo``: the report, its tables, figures, sim2real outputs and its one sweep (experiments.demo).
DEMO_OUTPUTS = OutTree(("report.md", "report.html"),
                       {"tables": STUDY_TABLES, "figures": OutTree(FIGURES_OUTPUTS.files),
                        "sim2real": OutTree(SIM2REAL_OUTPUTS), "sweeps": OutTree(folders={DEMO_SWEEP["name"]: SWEEP_OUTPUTS})})


def demo_sweep_files(out: Path) -> list[str]:
    """The files of the demo's sweep that an earlier demo into ``out`` wrote by names a pattern stands for
    (``sub/name``), named exactly: its cells, ``sweeps/NAME/cells/KEY.parquet`` for the key of each cell of
    DEMO_SWEEP (``sweep.cell_key``; the sweep reads no file), and its plots, ``figures/sweep_NAME_METRIC.*``
    for the metrics its table holds (``figures.make.sweep_stems``, as the demo drew them from it). The
    patterns ``figures/sweep_demo_k_vs_noise_*`` and ``cells/*.parquet`` removed a user's files of such
    names too, and the sweep's folder was removed whole before it ran. The demo removes them before it
    writes its own; ``figures --out DEMO/figures`` keeps the plots."""
    from experiments.figures.make import sweep_stems
    from experiments.sweep import SweepSpec, cell_key
    from lms200 import LmsbenchError

    spec = SweepSpec.from_dict(DEMO_SWEEP)
    folder = f"sweeps/{spec.name}"
    names = [f"{folder}/cells/{cell_key(spec.kind, params)}.parquet" for params in spec.cells()]
    try:  # a table the demo's sweep wrote: its plots are those of its metrics; none (or damaged): none drawn
        stems = sweep_stems(out / folder) if (out / folder / "results.parquet").is_file() else []
    except (LmsbenchError, OSError, ValueError):
        stems = []
    return names + [f"figures/{stem}{end}" for stem in stems for end in FIGURE_ENDS]


#: Largest record a command reads to tell an earlier run's folder (bytes): YAML (the largest, a sweep's
#: sweep.yaml of its most cells, is under 2 MB; PyYAML parses about a MiB in 4 s) and JSON (slam's
#: metrics.json and map.json). A larger file is no record of a run, unread: `simulate --out DIR` read a
#: 3 GB DIR/config.yaml whole (3.2 GB of memory, over 30 s) to find it was not its own (fuzzing).
MAX_RECORD_YAML_BYTES = 4 << 20
MAX_RECORD_JSON_BYTES = 64 << 20


def _small_file(path: Path, limit: int) -> bool:
    """Whether ``path`` is a regular file of at most ``limit`` bytes (a pipe waits for ever)."""
    try:
        st = path.stat()
    except OSError:
        return False
    return stat.S_ISREG(st.st_mode) and st.st_size <= limit


def _yaml_read(path: Path) -> tuple[dict | None, str | None]:
    """The mapping a YAML file holds and None, or None and what keeps it from being one (one line:
    unreadable, not UTF-8, empty, not YAML, not a mapping, larger than ``MAX_RECORD_YAML_BYTES``)."""
    try:
        st = path.stat()
    except OSError as exc:
        return None, f"it cannot be read ({exc.strerror or exc})"
    if not stat.S_ISREG(st.st_mode):
        return None, "it is not a regular file"
    if st.st_size > MAX_RECORD_YAML_BYTES:
        return None, f"it is larger than a record's {MAX_RECORD_YAML_BYTES} bytes"
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        return None, "it is not UTF-8 text"
    except OSError as exc:
        return None, f"it cannot be read ({exc.strerror or exc})"
    if not text.strip():
        return None, "it is empty"
    try:
        raw = load_yaml(text, words=True)  # an earlier version's record may hold a plain n
    except Exception as exc:  # noqa: BLE001 - whatever it is, it is not a record of a run
        return None, f"it does not parse as YAML ({' '.join(str(exc).split())[:160]})"
    if not isinstance(raw, dict):
        return None, f"it holds a {_kind_of(raw)}, not a mapping"
    return raw, None


def _kind_of(value: Any) -> str:
    """A YAML value's kind in a message: list, number, text, ..."""
    return {list: "list", str: "text", bool: "boolean", int: "number", float: "number",
            type(None): "null"}.get(type(value), type(value).__name__)


def _yaml_mapping(path: Path) -> dict | None:
    """The mapping a YAML file holds, or None (unreadable, not UTF-8, not YAML, not a mapping, larger
    than ``MAX_RECORD_YAML_BYTES``)."""
    return _yaml_read(path)[0]


@dataclass(frozen=True)
class _Recogniser:
    """A record's recogniser that can say why a file is not the record (``Owner.problem``): ``why``
    gives None for a record, else what is wrong with it, one line."""

    why: Callable[[Path], str | None]

    def __call__(self, path: Path) -> bool:
        return self.why(path) is None


def _json_object(path: Path) -> dict | None:
    """The object a JSON file holds, or None (also for a file larger than ``MAX_RECORD_JSON_BYTES``)."""
    import json

    if not _small_file(path, MAX_RECORD_JSON_BYTES):
        return None
    try:
        raw = json.loads(path.read_text(encoding="utf-8"))
    except Exception:  # noqa: BLE001
        return None
    return raw if isinstance(raw, dict) else None


def _csv_header(path: Path) -> list[str]:
    """The column names of a CSV file's first line ([] if unreadable)."""
    try:
        with open(path, encoding="utf-8") as fh:
            return fh.readline(1 << 16).rstrip("\r\n").split(",")
    except Exception:  # noqa: BLE001
        return []


def _yaml_has(*keys: str, dicts: Sequence[str] = (), exact: bool = False) -> Callable[[Path], bool]:
    """A recogniser: a YAML mapping with ``keys`` (``exact``: only those), ``dicts`` of them mappings."""
    def why(path: Path) -> str | None:
        raw, problem = _yaml_read(path)
        if raw is None:
            return problem
        missing = [k for k in keys if k not in raw]
        if missing:
            return "it has no " + ", ".join(f"{k}:" for k in missing)
        extra = sorted(str(k) for k in raw if k not in keys) if exact else []
        if extra:
            return f"it has {extra[0]}:, which such a record does not hold"
        flat = [k for k in dicts if not isinstance(raw[k], dict)]
        return f"its {flat[0]}: holds a {_kind_of(raw[flat[0]])}, not a mapping" if flat else None
    return _Recogniser(why)


def _yaml_says(**values: str) -> Callable[[Path], bool]:
    """A recogniser: a YAML mapping whose keys ``values`` hold those values."""
    def why(path: Path) -> str | None:
        raw, problem = _yaml_read(path)
        if raw is None:
            return problem
        for k, v in values.items():
            if raw.get(k) != v:
                return f"its {k}: is {repr(raw.get(k))[:80]}, not {v!r}" if k in raw else f"it has no {k}:"
        return None
    return _Recogniser(why)


def _json_has(**kinds: type) -> Callable[[Path], bool]:
    """A recogniser: a JSON object whose keys ``kinds`` hold values of those types."""
    names = {dict: "an object", list: "a list", str: "text", int: "a whole number"}

    def why(path: Path) -> str | None:
        raw = _json_object(path)
        if raw is None:
            return "it does not read as a JSON object"
        for k, t in kinds.items():
            if k not in raw:
                return f"it has no {k!r}"
            if not isinstance(raw[k], t) or (t is int and isinstance(raw[k], bool)):
                return f"its {k!r} is not {names.get(t, t.__name__)}"
        return None
    return _Recogniser(why)


def _csv_starts(*columns: str) -> Callable[[Path], bool]:
    """A recogniser: a CSV file whose header begins with ``columns``."""
    return lambda path: _csv_header(path)[:len(columns)] == list(columns)


def _parquet_has(*columns: str) -> Callable[[Path], bool]:
    """A recogniser: a Parquet file whose columns include ``columns`` (its footer's schema alone is read)."""
    def tells(path: Path) -> bool:
        try:
            import pyarrow.parquet as pq

            return set(columns) <= set(pq.read_schema(path).names)
        except Exception:  # noqa: BLE001
            return False
    return tells


def _first_line(start: str) -> Callable[[Path], bool]:
    """A recogniser: a text file whose first line begins with ``start``."""
    def tells(path: Path) -> bool:
        try:
            with open(path, encoding="utf-8") as fh:
                return fh.readline(1 << 12).startswith(start)
        except Exception:  # noqa: BLE001
            return False
    return tells


#: a slam run's config.yaml records beside input: and slam: (what ran, not settings: ``slam --config``
#: reads past them; experiments.slamrun.write_config writes them)
SLAM_RECORD_KEYS = ("extractor_config", "versions")


def _slam_config_problem(path: Path) -> str | None:
    """What keeps ``path`` from being config.yaml as lmsbench slam writes it (slamrun.write_config): input:
    and slam: mappings, the slam one with a preset, and nothing else but the records extractor_config: and
    versions: (mappings; an earlier version wrote neither); None when it is one."""
    raw, problem = _yaml_read(path)
    if raw is None:
        return problem
    missing = [k for k in ("input", "slam") if k not in raw]
    if missing:
        return "it has no " + ", ".join(f"{k}:" for k in missing)
    extra = sorted(str(k) for k in raw if k not in ("input", "slam", *SLAM_RECORD_KEYS))
    if extra:
        return f"it has {extra[0]}:, which such a record does not hold"
    flat = [k for k in ("input", "slam", *SLAM_RECORD_KEYS) if k in raw and not isinstance(raw[k], dict)]
    if flat:
        return f"its {flat[0]}: holds a {_kind_of(raw[flat[0]])}, not a mapping"
    return None if "preset" in raw["slam"] else "its slam: has no preset:"


_slam_config = _Recogniser(_slam_config_problem)


@dataclass(frozen=True)
class Owner:
    """How a command tells, from the content of what it left, that an earlier run of it wrote the
    files of its output names in a folder: ``records`` maps a file name to a recogniser of its
    content; every other output file (a TUM file, a figure, a table) counts as the earlier run's
    only when one of the records beside it (in the folder given as --out) is recognised. Each
    command writes one record first, whole (``experiments.provenance.write_record``), so a run
    stopped before its other outputs leaves a folder the next run recognises. ``within`` names
    the sub-folder (by name) that another command's folder gives this one: a demo's ``figures/``,
    which ``figures --tables DEMO/tables --out DEMO/figures`` redraws, is the figures' own
    wherever the demo's records tell DEMO as the demo's."""

    command: str
    records: Mapping[str, Callable[[Path], bool]]
    within: Mapping[str, "Owner"] = field(default_factory=dict)
    #: outputs that tell a folder of a run from before its records (not records: beside a record,
    #: one of them holding anything else is still the run's own, to replace)
    legacy: Mapping[str, Callable[[Path], bool]] = field(default_factory=dict)
    #: how the messages name the command where it is no lmsbench command (``python -m experiments.slameval``)
    program: str = ""

    @property
    def named(self) -> str:
        """The command as a user runs it: ``lmsbench COMMAND`` or ``program``."""
        return self.program or f"lmsbench {self.command}"

    def told(self, folder: Path) -> set[str]:
        """The records of ``folder`` (``sub/name`` in sub-folders) that an earlier run wrote."""
        return {n for n, tells in self.records.items() if (folder / n).is_file() and tells(folder / n)}

    def wrote_in(self, folder: Path) -> bool:
        """Whether an earlier run wrote into ``folder``: a record of it there, or ``folder`` is the
        sub-folder of ``within`` in a folder an earlier run of that owner wrote."""
        if self.told(folder) or any((folder / n).is_file() and tells(folder / n) for n, tells in self.legacy.items()):
            return True
        real = real_path(folder)
        return any(real.name == sub and owner.wrote_in(real.parent) for sub, owner in self.within.items())

    def earlier(self, folder: Path, writes: OutTree) -> set[str]:
        """The output files of ``folder`` (``sub/name`` in sub-folders) an earlier run wrote; a
        record whose content says otherwise is not one of them."""
        if not self.wrote_in(folder):
            return set()
        told = self.told(folder)
        return {n for n in writes.present(folder) if n in told or n not in self.records}

    def problem(self, folder: Path) -> tuple[str, str] | None:
        """The first record of ``folder`` present but not told as this command's, with what is wrong
        with it (one line), where no record there is told: a hand-damaged sweep.yaml (truncated,
        wrong types) beside a sweep's cells was refused as any user's folder, naming no record."""
        if self.told(folder):
            return None
        for name, tells in self.records.items():
            if (folder / name).is_file() and not tells(folder / name):
                why = tells.why(folder / name) if isinstance(tells, _Recogniser) else None
                return name, why or f"it is not the {name} such a run writes"
        return None

    def foreign(self, folder: Path, writes: OutTree) -> list[str]:
        """The output files of ``folder`` this run would replace that no earlier run wrote."""
        earlier = self.earlier(folder, writes)
        return [n for n in writes.present(folder) if n not in earlier]

    def remove_earlier(self, folder: Path, writes: OutTree, keep: Sequence[str] = (), also: Sequence[str] = ()) -> list[str]:
        """Remove the output files of ``folder`` (of ``writes``) an earlier run of the command wrote,
        but ``keep`` (the record this run writes first, whole, over the earlier one), before this run
        writes any: the others first, the records last, so that a stop between leaves either files told
        as the command's or none; the sub-folders of ``writes`` it empties go too. A run replaced only
        the files it wrote again, so the earlier run's others stayed beside its own as if they were
        its: ``figures --no-slam --out D`` over a run with SLAM left fig10_slam.png and
        tables/trajectory.parquet (which ``figures --tables D/tables`` drew as the new study's Fig. 10),
        and a run stopped while drawing left the earlier run's figures beside its first ones. Call it
        after :func:`check_out` (which refused a file of these names no earlier run wrote). Only the
        files ``writes`` names exactly go, and those ``also`` names exactly (``sub/name``: files the
        command writes by names a pattern of ``writes`` stands for, as the earlier run recorded them,
        :func:`recorded_names`, or as the command alone names them): a user's file that matches a
        pattern of an earlier run's folder (``sweep_notes.csv`` beside figures' ``sweep_*``, a
        ``realdata_notes.csv`` beside compare's ``realdata_*``) was removed with them (review of
        round 10; ``also`` took patterns until round 11). Returns the names removed (``sub/name`` in
        sub-folders)."""
        named = writes.named() | set(also)
        earlier = {n for n in (self.earlier(folder, writes) if folder.is_dir() else set()) if n in named}
        gone = sorted(n for n in earlier if n not in self.records) + sorted(n for n in earlier if n in self.records)
        gone = [n for n in gone if n not in keep]
        for name in gone:
            (folder / name).unlink(missing_ok=True)
        emptied = {str(Path(n).parent) for n in gone if "/" in n}
        for sub in sorted(emptied, key=lambda s: -s.count("/")):  # deepest first; one holding anything stays
            for parent in [Path(sub), *Path(sub).parents][:-1]:
                try:
                    (folder / parent).rmdir()
                except OSError:
                    break
        return gone


#: The files experiments.style.save_figure writes for a figure of one table: STEM.png, STEM.pdf, STEM.csv.
FIGURE_ENDS = (".png", ".pdf", ".csv")


def recorded_names(record: Path, key: str) -> tuple[str, ...]:
    """The output files an earlier run listed under ``key`` of its YAML record ``record`` (figures.yaml's
    ``sweep_plots``, compare's config.yaml ``figures``): what it wrote by names a pattern stands for,
    listed before it wrote them, so that the next run into the folder removes exactly those
    (:meth:`Owner.remove_earlier`) and no file of the user's that matches the pattern. () where the
    record lists none (a folder of a version before these lists: its files of those names stay)."""
    raw = _yaml_mapping(record) if record.is_file() else None
    names = raw.get(key) if raw is not None else None
    return tuple(n for n in names if isinstance(n, str)) if isinstance(names, list) else ()


#: What each command's earlier run left that says so (a user's summary.txt or config.yaml in a
#: folder of nothing else was written over: check_out allowed a folder by its file names alone).
SIMULATE_OWNER = Owner("simulate", {
    "config.yaml": _yaml_has("world", "seed", "duration", "sensor", dicts=("sensor",)),  # SimulationConfig.to_dict
    "world.json": _json_has(walls=list, corners=list, circles=list)})  # sim.World.to_json
SLAM_OWNER = Owner("slam", {
    "config.yaml": _slam_config,
    "metrics.json": _json_has(input=dict, n_scans=int, consistency=dict),  # every version's
    "map.json": _json_has(frame=str, lines=list, corners=list)})  # SlamResult.map_dict
COMPARE_OWNER = Owner("compare", {
    "config.yaml": _yaml_has("sources", "seeds", "methods", "scoring"),  # commands.compare: resolved
    "compare.csv": _csv_starts("source"),
    "summary.csv": _csv_starts("source", "method")})
SIM2REAL_OWNER = Owner("sim2real", {  # sim2real.write_outputs (also the demo's sim2real/)
    "config.yaml": _yaml_has("log", "world", "seeds", "probe_seeds", "robot", "checks", dicts=("robot",)),
    "sensor.yaml": _first_line("# sensor model used by lmsbench sim2real ")})
BENCH_OWNER = Owner("bench", {
    "versions.yaml": _yaml_has("benchmarks", "quick", "versions", exact=True),
    "bench.csv": _csv_starts("area")})  # commands.bench: {"area": name, **row}; the next column is the first area's own
SWEEP_OWNER = Owner("sweep", {"sweep.yaml": _yaml_has("name", "kind")})  # sweep.runner.spec_record
#: ``python -m experiments.slameval``: its slameval.yaml (written first, whole: the run's settings and versions)
#: A folder of a run from before its slameval.yaml is told by its sim.parquet's columns (a review found
#: such folders refused as "no earlier python -m experiments.slameval run wrote").
SLAMEVAL_OWNER = Owner("slameval", {"slameval.yaml": _yaml_says(command="python -m experiments.slameval")},
                       legacy={"sim.parquet": _parquet_has("seed", "rate_hz", "ate_rmse_m", "cpu_scans_per_s")},
                       program="python -m experiments.slameval")
#: The study's settings beside its tables (figures.study.save_tables, written first).
_STUDY_RECORD = _yaml_has("world", "seed", "duration", "resolved", dicts=("resolved",))
#: The demo: its report, the study's settings (figures.study.save_tables, written first), its
#: sim2real/ records and its sweep's sweep.yaml; its figures and tables count beside one of those.
DEMO_OWNER = Owner("demo", {
    "report.md": _first_line("# lmsbench demo"),
    "tables/study.yaml": _STUDY_RECORD,
    **{f"sim2real/{name}": tells for name, tells in SIM2REAL_OWNER.records.items()},
    "sweeps/demo_k_vs_noise/sweep.yaml": SWEEP_OWNER.records["sweep.yaml"]})
#: ``figures``: its figures.yaml (commands.figures, written first: the command, where the tables
#: came from, the versions), or, from a run before figures.yaml, the study's settings of its
#: tables/ (or of the tables folder itself, for ``figures --tables DIR --out DIR``); a demo's
#: figures/ folder (``figures --tables DEMO/tables --out DEMO/figures``) is its own too. A figure
#: or its CSV says nothing of lmsbench: by names alone a user's fig3_scan.png was written over.
#: A folder of ``figures --tables T --out DIR`` from before figures.yaml holds no table: its
#: fig4_ad.csv tells it (figures.tables.signals_table's columns and the reference line's; a review
#: found such folders refused as "no earlier lmsbench figures run wrote").
FIGURES_OWNER = Owner("figures", {"figures.yaml": _yaml_says(command="lmsbench figures"),
                                  "tables/study.yaml": _STUDY_RECORD, "study.yaml": _STUDY_RECORD},
                      within={"figures": DEMO_OWNER},
                      legacy={"fig4_ad.csv": _csv_starts("beam", "bearing_deg", "range_m", "ad", "ad_band",
                                                         "theta_deg", "psi_deg", "reference")})


def check_out(path: str | os.PathLike | None, writes: Sequence[str] | OutTree | None = None,
              patterns: Sequence[str] = (), owner: Owner | None = None,
              replaces: OutTree | None = None, default: str | None = None) -> Path | None:
    """An output folder: absent (created later) or a folder; its nearest existing parent writable.
    None (no --out: a new timestamped folder will be made) passes. With ``writes`` (the fixed file
    names a command writes: SIMULATE_OUTPUTS, SLAM_OUTPUTS, COMPARE_OUTPUTS, or an OutTree of
    files and sub-folders: FIGURES_OUTPUTS, DEMO_OUTPUTS) and ``patterns`` (shell patterns of the
    names it writes per input: COMPARE_FIGURES), an existing folder may hold only those (a run's
    own earlier outputs, which it replaces) and hidden files: ``slam run --out slam`` from the
    checkout wrote into the slam package, ``slam run --out run`` replaced the run's config.yaml,
    ``compare LOG --out FOLDER`` a config.yaml of the user's, ``demo --out FOLDER`` deleted a
    folder's sweeps/demo_k_vs_noise. With ``owner`` (how the command tells its own earlier outputs
    by their content) a file of its names is accepted only when an earlier run of it wrote it: by
    names alone a user's summary.txt or config.yaml in a folder of nothing else was written over.
    ``replaces``: the files of those the run writes (default: all; ``figures --tables DIR --out DIR``
    reads the tables beside its figures and writes only the figures). ``default``: where the command
    makes its run's folder without --out (``results/compare``), checked as --out's parent is: a
    read-only or full current folder failed ``bench`` and ``figures`` after all their work."""
    if path is None:
        if default is not None:
            _check_default_base(Path(default))
        return None
    p = Path(path)
    check_link(p)
    if p.exists() and not p.is_dir():
        raise InputError(f"--out {p}: exists and is not a folder")
    if p.is_dir():
        hold_output(p)  # first: what another run is writing there is no sign of what the folder holds
    if writes is not None and p.is_dir():
        tree = writes if isinstance(writes, OutTree) else OutTree(tuple(writes) + tuple(patterns))
        others = tree.foreign(p)
        if others:
            shown = ", ".join(others[:3]) + (f" and {len(others) - 3} more" if len(others) > 3 else "")
            raise InputError(f"--out {p}: holds {shown}, which this command does not write; give a new or empty "
                             "folder (a folder of this command's own earlier outputs is replaced)")
        if owner is not None:  # its own names, but not written by it: a user's summary.txt or config.yaml
            theirs = owner.foreign(p, tree if replaces is None else replaces)
            hidden = [n for n in theirs if not os.access(p / n, os.R_OK)]
            if hidden:  # said "holds config.yaml, which ... no earlier lmsbench compare run wrote" of an unreadable record
                raise InputError(f"--out {p}: {p / hidden[0]} cannot be read (permission denied), so this run cannot "
                                 f"tell whether an earlier {owner.named} run wrote it; make it readable, or "
                                 "give another folder")
            if theirs:
                shown = " and ".join(theirs) if len(theirs) <= 3 else ", ".join(theirs[:3]) + f" and {len(theirs) - 3} more"
                damaged = owner.problem(p) if any(n not in owner.records for n in theirs) else None
                said = (f" (its record {p / damaged[0]} is not one such a run leaves: {damaged[1]})"
                        if damaged is not None else "")
                raise InputError(f"--out {p}: holds {shown}, which this run would replace but no earlier "
                                 f"{owner.named} run wrote{said}; give a new or empty folder")
        _check_replaceable(p, tree if replaces is None else replaces, removed=patterns)
    parent = nearest_existing(p)
    if not _writable_folder(parent):
        raise InputError(f"--out {p}: {parent} is not a writable folder")
    hold_output(p, make=True)  # a new folder is made here to be locked (removed as the command ends if still empty)
    return p


#: a sub-folder of outputs not checked by :func:`_check_replaceable`: a sweep's finished cells
#: (experiments.sweep.store.CELLS_DIR), read and kept, written only when cells are left to compute
#: (the sweep checks that itself, experiments.sweep.runner)
KEPT_FOLDERS = ("cells",)


def _check_replaceable(p: Path, tree: OutTree, top: Path | None = None, removed: Sequence[str] = ()) -> None:
    """Refuse, before any work, a read-only file of ``--out p`` that the run would replace or may write
    (a pattern's: ``STEM_*.csv``, ``tables/*.parquet``, ``sweep_*``), or a sub-folder of its outputs it
    cannot write in: ``figures --out DIR`` over a read-only ``fig3_scan.png`` computed its whole study,
    then failed ``DIR/fig3_scan.png: permission denied`` (a permission fuzz round, run as a user without
    root's powers: as root everything is writable). Not the files of ``removed``, patterns of which the
    run removes an earlier run's files before writing its own (compare's ``realdata_*``), which a
    read-only file allows (a review)."""
    for name in tree.files:
        if name in removed:
            continue
        pattern = any(c in name for c in "*?[")
        for f in sorted(p.glob(name)) if pattern else [p / name]:
            if f.is_file() and not f.is_symlink() and not os.access(f, os.W_OK):
                raise InputError(f"--out {top or p}: {f} cannot be written (permission denied: read-only), and this run "
                                 f"{'may write' if pattern else 'would replace'} it; make it writable (chmod u+w), or "
                                 "give another folder")
    for sub, inner in tree.folders.items():
        folder = p / sub
        if sub in KEPT_FOLDERS or not folder.is_dir() or folder.is_symlink():
            continue
        if not os.access(folder, os.W_OK | os.X_OK):
            raise InputError(f"--out {top or p}: {folder} is not a writable folder, and this run writes its outputs there; "
                             "make it writable (chmod u+w), or give another folder")
        _check_replaceable(folder, inner, top or p, removed)


#: the outputs (``--out`` folders and files) the running command holds, per thread (two ``cli.main``
#: calls on threads released each other's): real path -> (the open locked descriptor, the lock file
#: to remove or None, the folders check_out made for it, deepest last). None outside a command
#: (:func:`holding_outputs`): the library's own calls lock nothing.
_HOLDING = threading.local()
#: A file output's lock: a hidden file beside it (``.NAME.lmsbench-lock``), removed as the command ends.
LOCK_SUFFIX = ".lmsbench-lock"


def lock_file(path: Path) -> Path:
    """The hidden lock file of the output file ``path`` (a real path): ``.NAME.lmsbench-lock`` beside
    it, or, where that name would pass the file system's longest name (NAME_MAX, 255 bytes on
    Linux's), ``.PREFIX.HASH.lmsbench-lock``: NAME's first bytes and 16 hex digits of its SHA-256
    (:func:`lms200.logs.hidden_stem`), so that every run of one output takes one lock (an output
    named near 255 bytes made a lock name no file system takes, and the run went on unguarded)."""
    from lms200.logs import hidden_stem

    return path.with_name(hidden_stem(path, len(os.fsencode(LOCK_SUFFIX))) + LOCK_SUFFIX)


def _held() -> dict[str, tuple[int, Path | None, list[Path]]] | None:
    return getattr(_HOLDING, "held", None)


def holding_outputs() -> None:
    """Start a command's holding of its outputs (``experiments.cli``, before the command runs):
    from here :func:`check_out` and :func:`check_out_file` take each output for this process until
    :func:`release_outputs`."""
    release_outputs()
    _HOLDING.held = {}


def release_outputs() -> None:
    """End the holding (the command ended; a killed process's locks end with it, by the kernel):
    a file output's lock file is removed, and so is a folder check_out made that is still empty
    (a command refused after check_out left no folder before the lock made it)."""
    for fd, lock, made in (_held() or {}).values():
        try:  # removed while held: a run that opened it meanwhile finds it gone once locked, and retries
            _remove_lock(lock, made)
        finally:
            os.close(fd)
    _HOLDING.held = None


def _remove_lock(lock: Path | None, made: list[Path]) -> None:
    """Remove a file output's lock file, and the folders check_out made that are still empty."""
    try:
        if lock is not None:
            lock.unlink(missing_ok=True)
        for folder in reversed(made):
            folder.rmdir()  # only an empty one: the first not empty ends it
    except OSError:
        pass


def _lock_holder(fd: int) -> str:
    """Who holds the lock of ``fd``: "pid N" from the kernel's table of locks (Linux's /proc/locks,
    which names the device and inode of each), or "" where that cannot be told."""
    info = os.fstat(fd)
    want = f"{os.major(info.st_dev):02x}:{os.minor(info.st_dev):02x}:{info.st_ino}"
    try:
        with open("/proc/locks", encoding="ascii", errors="replace") as table:
            for line in table:
                fields = line.split()
                if len(fields) >= 6 and fields[1] == "FLOCK" and fields[5] == want and fields[4].isdigit():
                    return f"pid {fields[4]}"
    except OSError:
        pass
    return ""


def hold_output(p: Path, flag: str = "--out", make: bool = False) -> None:
    """Take the output ``p`` (a folder or a file) for this command, or refuse it when another
    lmsbench command holds it: two runs into one --out interleaved their files, each removing the
    other's temporary files (``simulate --seed 1 --out D`` beside ``--seed 2 --out D``: one said
    "D/.scans.clf.N.tmp: no such file or directory", the other "simulated ... seed 1 into D" over
    a folder of seed 2's files, exit 0). An advisory lock (``fcntl.flock``) on the output folder
    itself (``make``: made first when absent, by :func:`check_out` once the path is checked), or for
    a file on a hidden lock file beside it (``.NAME.lmsbench-lock``, :func:`lock_file`, removed as the command ends; one
    a killed run left holds no lock and is taken). Nothing in the temporary folder: a lock file there
    depended on $TMPDIR (two runs of different TMPDIR both wrote one --out) and piled up. A lock
    ends with the command or with its process when it is killed (SIGKILL too). Any OSError while
    locking (a read-only or full file system, one without locks): the run goes on unguarded."""
    import fcntl

    held = _held()
    if held is None:
        return
    key = str(real_path(p))
    if key in held:
        return
    folder = make or p.is_dir()
    lock = None if folder else lock_file(Path(key))  # beside the real file
    for _ in range(100):  # removed by its holder's end between our open and our lock: again
        made: list[Path] = []
        try:
            if folder:
                for q in (p, *p.parents):
                    if q.exists():
                        break
                    made.insert(0, q)
                p.mkdir(parents=True, exist_ok=True)
                fd = os.open(p, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
            else:
                assert lock is not None
                fd = os.open(lock, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o600)
        except FileNotFoundError:
            continue
        except OSError:  # no lock to be had (a read-only or full file system): unguarded, rather than refusing
            return
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            same = os.path.samestat(os.fstat(fd), os.stat(lock or p, follow_symlinks=lock is None))
        except BlockingIOError:
            holder = _lock_holder(fd)
            os.close(fd)  # a folder made just now stays: its holder made it too, and removes it when empty
            raise InputError(f"{flag} {p}: another lmsbench command{f' ({holder})' if holder else ''} is writing "
                             "there; wait for it to end, or give another path") from None
        except FileNotFoundError:
            same = False
        except OSError:  # a file system without locks (EPERM, ENOLCK; NFS refuses a folder's): unguarded, and
            os.close(fd)  # nothing of the lock's left (no lock is held there: the file system takes none)
            _remove_lock(lock, made)
            return
        if same:
            held[key] = (fd, lock, made)
            return
        os.close(fd)


def check_link(p: Path, flag: str = "--out") -> None:
    """An output path that is a link to nothing or a loop of links: found only when the run wrote
    (after the work: "dang: file exists"), or by Path.resolve ("internal error: RuntimeError:
    Symlink loop"). The path's folders too (review: --out LOOP/sub, DANGLING/sub were the same)."""
    for q in (p, *p.parents):
        if q.is_symlink() and not q.exists():
            raise InputError(f"{flag} {p}: " + missing_message(q, "folder") if q != p else f"{flag} {missing_message(p, 'folder')}")


def check_out_spares(out: str | os.PathLike | None, writes: Sequence[str], reads: Sequence[str | os.PathLike]) -> None:
    """No file a run writes into ``out`` (the names ``writes``) is a file it reads (``reads``):
    ``compare SIMFOLDER --out SIMFOLDER`` replaced the simulate folder's config.yaml, the sensor
    model compare reads for it, with its own; nor is ``out`` a folder it reads (said so)."""
    if out is None:
        return
    check_link(Path(out))
    for f in reads:  # `slam RUN --out RUN` was refused as "holds groundtruth.tum ..., which this command does not write"
        if Path(f).is_dir() and real_path(f) == real_path(Path(out)):
            raise InputError(f"--out {out} is the input folder {f}, which the run reads; give another folder for "
                             "its outputs")
    targets = {real_path(Path(out) / name) for name in writes}
    for f in reads:
        if real_path(f) in targets:
            raise InputError(f"--out {out}: the run would write {Path(f).name} over {f}, which it reads; "
                             "give another folder")


def check_out_file(path: str | os.PathLike | None, flag: str = "--out") -> Path | None:
    """An output file: not a folder, in an existing writable folder (checked before any work)."""
    if path is None:
        return None
    p = Path(path)
    check_link(p, flag)
    if p.is_dir():
        raise InputError(f"{flag} {p} is a folder; give a file name")
    if p.exists() and not p.is_file():  # writing to a pipe with no reader hung the command after its work
        raise InputError(f"{flag} {p}: not a regular file (a pipe, a device or a socket); give a file name")
    hold_output(p, flag)
    parent = p.parent
    if not parent.exists():  # it said "nodir is not a folder", as of a file: the file's folder is not made
        raise InputError(f"{flag} {p}: no folder {parent}; make it first (a file's folder is not made for it)")
    if not parent.is_dir():
        raise InputError(f"{flag} {p}: {parent} is not a folder")
    if not _writable_folder(parent):
        raise InputError(f"{flag} {p}: {parent} is not a writable folder")
    return p


#: the line of a relative path met after the current folder was removed (the shell still in it)
CWD_GONE = "the current folder no longer exists (it was removed after the shell entered it); cd to one that does"


def _check_default_base(base: Path) -> None:
    """The folder ``base`` a command makes its run folder ``base/DATE_TIME`` in without --out: a
    folder, or absent beneath a writable one."""
    if not base.is_absolute():
        try:
            os.getcwd()
        except FileNotFoundError:  # said ". is not a writable folder, so a run without --out cannot be made ..."
            raise InputError(CWD_GONE) from None
    check_link(base)
    if base.exists() and not base.is_dir():
        raise InputError(f"{base} (where a run without --out goes) exists and is not a folder; give --out")
    parent = nearest_existing(base)
    if not _writable_folder(parent):
        what = "a writable folder" if parent.is_dir() else "a folder"
        raise InputError(f"{parent} is not {what}, so a run without --out cannot be made in {base}; give --out")


def nearest_existing(p: Path, links: bool = False) -> Path:
    """``p`` or its nearest parent that exists (where a folder to be made goes), the root at most.
    ``links``: a dangling symbolic link counts as existing and is where it stops (the sweep's folders,
    ``sweep.store``, say such a link is no folder to make one in); without, it is walked past to the
    folder that holds it (``check_out`` then checks that folder)."""
    while not (p.exists() or (links and p.is_symlink())) and p != p.parent:
        p = p.parent
    return p


def _writable_folder(folder: Path) -> bool:
    """Whether ``folder`` is a folder this process can make files and folders in."""
    return folder.is_dir() and os.access(folder, os.W_OK | os.X_OK) and _can_create_in(folder)


def _can_create_in(folder: Path) -> bool:
    """Whether a folder can be made in ``folder`` (made and removed at once): os.access says yes to
    root everywhere, also in /proc or on a read-only mount."""
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".lmsbench-probe-", dir=folder))
    except OSError:
        return False
    return True


def check_methods(methods: Sequence[str] | None) -> list[str]:
    """Known extractor names (all of them when None), given apart or comma-separated
    (``--methods sensor split_merge`` or ``--methods sensor,split_merge``)."""
    from features.registry import available_methods

    from experiments.user_methods import ensure_method, is_user_method

    known = available_methods()
    if not methods:
        return known
    methods = split_methods(methods)
    for m in methods:
        if is_user_method(m):
            ensure_method(m)  # raises naming what is wrong with MODULE:FUNCTION
    bad = [m for m in methods if m not in known and not is_user_method(m)]
    if bad:
        raise InputError(f"unknown method(s) {', '.join(bad)}; known: {', '.join(known)}, or MODULE:FUNCTION "
                         "(your own extractor)")
    if len(set(methods)) != len(methods):
        raise InputError(f"a method is named twice in {' '.join(methods)}")
    return list(methods)


def split_methods(methods: Sequence[str]) -> list[str]:
    """Method names given apart or separated by commas (no name holds one: neither a built-in
    name nor MODULE:FUNCTION). A comma at a word's end or start joins it to the next or last word
    (the shell splits ``--methods sensor, hough`` into ``sensor,`` and ``hough``); an empty name
    between two commas (``sensor,,hough``) or a word of commas alone is refused."""
    names = []
    for given in methods:
        parts = [part.strip() for part in given.split(",")] if "," in given else [given]
        if any(not part for part in parts[1:-1]) or not any(parts):
            raise InputError(f"method list {given!r}: an empty name between commas; give names such as "
                             "sensor,split_merge or sensor split_merge")
        names += [part for part in parts if part]
    return names


def _check_readable_folder(p: Path, flag: str, what: str) -> None:
    """Refuse a folder whose files cannot be listed or opened (no read or search permission): an
    error named a file in it (``t/study.yaml: permission denied``) or said it held none (``no
    study.yaml and tables``) where the folder itself could not be read."""
    if not os.access(p, os.R_OK | os.X_OK):
        raise InputError(f"{flag} {p}: folder cannot be read (permission denied), so {what} in it cannot be read; "
                         "make it readable (chmod u+rx)")


def check_study_tables(folder: str | os.PathLike) -> Path:
    """A folder of tables saved by an earlier ``lmsbench figures`` / ``demo`` (study.yaml and Parquet)."""
    p = Path(folder)
    if p.exists() and not p.is_dir():  # it said "no such folder" of a file
        raise InputError(f"--tables {p} is a file, not a folder of tables")
    if not p.is_dir():
        raise InputError(f"--tables {p}: no such folder")
    _check_readable_folder(p, "--tables", "the tables")
    if not (p / "study.yaml").is_file() or not any(p.glob("*.parquet")):
        raise InputError(f"--tables {p}: no study.yaml and tables (*.parquet) from an earlier "
                         "`lmsbench figures` or `lmsbench demo` (they are in its tables/ folder)")
    return p


class SweepResults(NamedTuple):
    """A ``figures --sweep`` folder as :func:`read_sweep_results` read it for its checks, to draw from."""

    folder: Path
    table: Any  # its results.parquet, a pandas DataFrame
    spec: dict  # its sweep.yaml


def read_sweep_results(folder: str | os.PathLike) -> SweepResults:
    """A sweep folder with results.parquet holding at least one successful cell, and that table (a
    pandas DataFrame) and its sweep.yaml as read for the checks: ``figures --sweep`` draws from them (it
    read the table and parsed the sweep.yaml again for its plots' names, its record and its drawing: four
    times a sweep)."""
    from experiments.provenance import read_parquet

    p = Path(folder)
    path = p / "results.parquet"
    if p.exists() and not p.is_dir():  # a sweep file given for its folder: it said "no results.parquet"
        raise InputError(f"--sweep {p} is a file, not a sweep folder (the folder `lmsbench sweep` wrote: --out, "
                         "default results/sweeps/NAME)")
    if p.is_dir():
        _check_readable_folder(p, "--sweep", "the sweep's results")
    if path.is_file() and not os.access(path, os.R_OK):  # it said "not a Parquet table (PermissionError)"
        raise InputError(f"--sweep {path}: cannot be read (permission denied)")
    if path.is_dir():  # it said "no results.parquet: the sweep did not finish"
        raise InputError(f"--sweep {path}: a folder where the sweep's table goes; it is the Parquet file `lmsbench sweep` "
                         "writes")
    if not path.is_file():
        if (p / "sweep.yaml").is_file():  # a sweep stopped or killed before its table
            raise InputError(f"--sweep {p}: no results.parquet: the sweep did not finish; finish it with lmsbench "
                             f"sweep {p / 'sweep.yaml'} --out {p}, then draw it")
        raise InputError(f"--sweep {p}: no results.parquet (run `lmsbench sweep` first)")
    try:
        table = read_parquet(path)
    except Exception as exc:  # noqa: BLE001 - pyarrow raises several types for a broken file
        raise InputError(f"--sweep {path}: not a Parquet table ({type(exc).__name__})") from None
    if "status" not in table or "cell" not in table:  # a figures table said "361 cells, all failed"
        raise InputError(f"--sweep {path}: not the table of `lmsbench sweep` (no {'status' if 'status' not in table else 'cell'} "
                         "column: one row per cell with its status; another program's table, or edited?)")
    if not len(table):  # it said "no successful cell to plot (0 cells, all failed; ...)"
        raise InputError(f"--sweep {path}: an empty table (no cell); run the sweep again into its folder to write it")
    if not (table["status"] == "ok").any():
        raise InputError(f"--sweep {p}: no successful cell to plot ({len(table)} cells, all failed; "
                         "their `error` column says why)")
    spec_path = check_yaml(p / "sweep.yaml", "the sweep.yaml `lmsbench sweep` writes beside its results", sized=False)
    try:  # read for the plots' axes after the study: a damaged one was an internal error after the work
        spec = load_yaml(spec_path.read_text(encoding="utf-8"))
    except yaml.YAMLError as exc:
        raise InputError(f"--sweep {spec_path}: not valid YAML ({exc})") from None
    if not isinstance(spec, dict) or not all(isinstance(spec.get(k) or {}, dict) for k in ("grid", "random")):
        raise InputError(f"--sweep {spec_path}: not the sweep.yaml of `lmsbench sweep` (a mapping whose grid: and "
                         "random: are mappings)")
    params = list(dict.fromkeys(n.strip() for key in (*(spec.get("grid") or {}), *(spec.get("random") or {}))
                                for n in str(key).split(",")))
    absent = [n for n in params if n not in table]
    if absent:  # another sweep's table or sweep.yaml: "holds 2 of the 3 cells ...: the sweep did not finish"
        raise InputError(f"--sweep {p}: its results.parquet has no column {absent[0]}, a parameter of its sweep.yaml "
                         f"({spec_path}): the table and the sweep.yaml are of different sweeps (one copied over "
                         "the other's?); run the sweep again into a new folder")
    from experiments.sweep.spec import cell_key

    drawn = _sweep_cells(spec)  # the sweep.yaml's cells, read once for the count and the rows' check
    cells = None if drawn is None else len({cell_key(drawn[0], cell) for cell in drawn[1]})
    held = int(table["cell"].nunique()) if "cell" in table else len(table)
    if cells is not None and held > cells:  # "holds 3 of the 2 cells ...: the sweep did not finish"
        raise InputError(f"--sweep {p}: its results.parquet holds {held} cells, more than the {cells} of its sweep.yaml "
                         f"({spec_path}): the table and the sweep.yaml are of different sweeps (one copied over the "
                         "other's?); run the sweep again into a new folder")
    if cells is not None and held != cells:  # a stopped sweep's table was drawn as the sweep's result, exit 0
        raise InputError(f"--sweep {p}: its results.parquet holds {held} of the {cells} cells of its sweep.yaml: the "
                         f"sweep did not finish (stopped, or cells not stored); finish it with lmsbench sweep "
                         f"{spec_path} --out {p}, then draw it")
    strange = None if drawn is None else _foreign_rows(table, drawn[1], params)
    if strange is not None:  # k 0..39999 beside a grid of k [3, 8], or each cell 50 times, was drawn, exit 0
        raise InputError(f"--sweep {p}: its results.parquet's row {strange}: the table and the sweep.yaml "
                         f"({spec_path}) are of different sweeps, or the table was edited; run the sweep again into a "
                         "new folder")
    return SweepResults(p, table, spec)


def _foreign_rows(table: Any, cells: list[dict], params: list[str]) -> str | None:
    """What is wrong with the first row of a sweep's table (a pandas DataFrame) that is no cell of its
    sweep.yaml (``cells``; its grid and random parameters and seed, compared as values: a linked grid
    key's values, a random draw's number), or that repeats a cell; None when the rows are cells of it,
    each at most as often as the sweep has it. Values are compared as the table stores them
    (:func:`_cell_value`): a column that mixed text with numbers holds them as text, a column of numbers
    holds a bool as 1 and a whole number beyond 2^53 rounded, so two cells may be one value there."""
    from collections import Counter

    if "seed" not in table:
        return None  # said by the caller's count of cells, or drawn as an older table
    names = [*params, "seed"]
    kinds = [_column_kind(table[n]) for n in names]
    expected = Counter(tuple(_cell_value(cell.get(n), k) for n, k in zip(names, kinds)) for cell in cells)
    for i, row in enumerate(zip(*(table[n] for n in names))):
        key = tuple(_cell_value(v, k) for v, k in zip(row, kinds))
        if not expected[key]:
            if key in expected:  # each of its cells already had its row
                return f"{i} repeats a cell of an earlier row"
            shown = ", ".join(f"{n}={v!r}"[:40] for n, v in zip(names, row))
            return f"{i} ({shown}) is no cell of its sweep.yaml"
        expected[key] -= 1
    return None


def _column_kind(column: Any) -> str:
    """How a sweep table's column (a pandas Series) holds its cells' values: "text" (a column that
    mixed text with numbers was stored as text, ``sweep.store._tidy``), "number" (a bool is 1 there,
    a whole number a float where the column has nulls), or "value" (as the sweep.yaml holds them)."""
    import pandas as pd

    if any(isinstance(v, str) for v in column):
        return "text"
    if pd.api.types.is_numeric_dtype(column) and not pd.api.types.is_bool_dtype(column):
        return "number"
    return "value"


def _cell_value(value: object, kind: str) -> object:
    """A sweep cell's parameter value, of the sweep.yaml or of a table row, as a column of ``kind``
    (:func:`_column_kind`) holds it, so that the two compare equal: numpy's as Python's, nan and None
    (a null parameter in a column of numbers) alike; a bool apart from the numbers where the column
    keeps it."""
    import numpy as np

    if isinstance(value, np.generic):
        value = value.item()
    if value is None or (isinstance(value, float) and value != value):
        return None
    if kind == "text":  # a null in a column stored as text may be 'nan' there (the string of a float nan)
        return None if value == "nan" else str(value)
    if kind == "number" and isinstance(value, (int, float)):
        return float(value)
    from experiments.sweep.spec import _value_key

    return _value_key(value)  # as the spec tells grid points apart: a bool apart from the numbers


def _sweep_cells(raw: dict) -> tuple[str, list[dict]] | None:
    """The kind and cells of a sweep.yaml's sweep, None when it does not read as a sweep (one of an
    older lmsbench: its table is drawn as it is)."""
    import warnings

    from lms200 import LmsbenchError

    from experiments.sweep.spec import SweepSpec

    try:
        with warnings.catch_warnings():  # an old spelling was said when the sweep ran
            warnings.simplefilter("ignore")
            spec = SweepSpec.from_dict(raw)
        return spec.kind, spec.cells()
    except (LmsbenchError, ValueError, TypeError):
        return None
