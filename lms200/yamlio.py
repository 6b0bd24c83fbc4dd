"""YAML read the way numbers are written: PyYAML follows YAML 1.1, in which ``1e9``, ``5e-3`` or
``1E6`` (no dot, or no sign in the exponent) are strings, so a config value ``noise_sigma: 5e-3``
reached the code as text. :func:`load` reads them as floats, as YAML 1.2 and Python do.

More departures from PyYAML's safe loader, all refusals of what it took silently or crashed
on: a key given twice in one mapping (PyYAML kept the last, so ``noise_sigma: 0.005`` followed
further down by ``noise_sigma: 0.5`` simulated the second without a word; YAML 1.2 forbids it),
nesting too deep for Python's recursion limit (a RecursionError, not a YAML error), and aliases
that expand a document to billions of values or into itself (a "billion laughs": fine to
PyYAML, which shares the objects, but endless to the ``repr`` of an error message), and a
scalar its tag cannot make (an impossible date, ``seed: 2025-02-30``, or ``!!float abc``: Python's
ValueError, without the file or line), and a number that YAML 1.1 reads otherwise than YAML 1.2,
Python and the command line (``k: 1_0`` read as 10, ``duration: 1:30`` as 90, ``seed: 010`` as 8;
quoted, each is text for the field's own check), a float written nonzero that float64 reads as 0
(``noise_sigma: 1e-400``: a noise-free run), and a value written as one of YAML 1.1's boolean
words other than true / false (``yes``, ``no``, ``on``, ``off``, ``y``, ``n``, any case, unquoted:
``deskew: no`` was False, ``y`` text; a key such as ``on:`` reads as before). Hexadecimal (``0x10``), binary (``0b101``),
``.inf`` and ``.nan`` read as before. All
raise ``yaml.YAMLError`` with the line, as any malformed YAML does; PyYAML's own errors are
re-raised as :class:`Malformed`, one line that starts with the place ("line 2, column 1: ...")."""

from __future__ import annotations

import re
import sys
from typing import Any

import yaml

from .finite import digit_limit_problem, underflow_problem


class Loader(yaml.SafeLoader):
    """The safe loader with YAML 1.2 floats (``1e9``, ``5e-3``)."""

    #: a plain YAML 1.1 boolean word (``yes``, ``no``, ``on``, ``off``, ``y``, ``n``) as a value is
    #: refused (``yaml11_bool``); :class:`WordsLoader` reads them as PyYAML does
    refuse_words = True


class WordsLoader(Loader):
    """:class:`Loader` that reads YAML 1.1's boolean words as PyYAML does (``no`` False, ``n``
    text), for YAML that lmsbench's users do not write for it: a ROS 2 bag's metadata.yaml (rosbag2
    writes it) and the records of runs an earlier version wrote with ``yaml.safe_dump`` (``n`` and
    ``y`` plain), which :func:`load` would refuse."""

    refuse_words = False


Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
                   |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
                   |[-+]?\.[0-9_]+(?:[eE][-+]?[0-9]+)?)$""", re.X),
    list("-+0123456789."),
)


_INT_TAG, _FLOAT_TAG = "tag:yaml.org,2002:int", "tag:yaml.org,2002:float"
_OCTAL = re.compile(r"[-+]?0[0-9]+")  # YAML 1.1's octal (010 is 8); a lone 0 is not one


def yaml11_number(loader: Loader, node: yaml.Node) -> str | None:
    """Why ``node``, a scalar that YAML 1.1 (PyYAML) reads as a number, reads as another number
    than YAML 1.2, Python and the command line (``experiments.options.plain_number``) would, or
    None: underscores dropped (``1_0`` is 10), base 60 (``1:30`` is 90, ``12:30:00`` 45000), a
    leading 0 read as octal (``010`` is 8). Each ran, silently, as that other number."""
    if not isinstance(node, yaml.ScalarNode) or node.tag not in (_INT_TAG, _FLOAT_TAG):
        return None
    text = node.value
    if ":" in text:
        why = "YAML 1.1 reads digits between colons in base 60 (a time or an angle)"
    elif "_" in text:
        why = "YAML 1.1 drops a number's underscores (the command line refuses them)"
    elif node.tag == _INT_TAG and _OCTAL.fullmatch(text):
        why = "YAML 1.1 reads a whole number with a leading 0 in octal"
    else:
        return None
    value = yaml.SafeLoader.construct_object(loader, node)
    return f"{text} is read as {value!r}: {why}; write the number as a plain decimal, or quote it ('{text}') for text"


_BOOL_WORD = re.compile(r"^(?:yes|no|on|off|y|n)$", re.I)  # YAML 1.1's booleans besides true / false (any case here)


def yaml11_bool(loader: Loader, node: yaml.Node) -> str | None:
    """Why ``node``, a value written as a plain (unquoted, untagged) YAML 1.1 boolean word other
    than true / false (``yes``, ``no``, ``on``, ``off``, ``y``, ``n``, any case), is refused, or
    None: PyYAML reads ``yes`` / ``no`` / ``on`` / ``off`` as True / False (``units: no`` became
    False, a sweep's ``mode: [on, off]`` [True, False]) where YAML 1.2, Python and the command line
    read text, and ``y`` / ``n`` as text where YAML 1.1 reads a boolean: what was meant cannot be
    told. ``true`` / ``false`` and a quoted word read as before; so does a key (``on:``)."""
    if not isinstance(node, yaml.ScalarNode) or node.style is not None or not _BOOL_WORD.fullmatch(node.value):
        return None
    mark, end = node.start_mark, node.end_mark
    if mark.buffer is not None and "!" in mark.buffer[mark.pointer:end.pointer - len(node.value)]:
        return None  # an explicit tag (!!str yes, !!bool yes) says what it is
    text, truth = node.value, node.value.lower() in ("yes", "on", "y")
    if node.tag == "tag:yaml.org,2002:bool":
        read = f"is read as {str(truth).lower()} (YAML 1.1), but as text by YAML 1.2"
    else:
        read = f"is read as text here, but is YAML 1.1's boolean word for {str(truth).lower()}"
    return f"{text} {read}; write true or false, or quote it ('{text}') for text"


def float_underflow(node: yaml.Node) -> str | None:
    """Why ``node``, a float scalar written nonzero that reads as 0.0 (``noise_sigma: 1e-400``: below
    float64's smallest nonzero number), is refused, or None (``lms200.finite.underflow_problem``): the
    run took it for 0 without a word (a noise-free run)."""
    if not isinstance(node, yaml.ScalarNode) or node.tag != _FLOAT_TAG:
        return None
    try:
        value = float(node.value)
    except ValueError:  # .inf, 1:30, !!float abc: the constructor reads or refuses them
        return None
    return underflow_problem(node.value, value)


def _refuse_yaml11_number(loader: Loader, node: yaml.Node, where: str = "", key: bool = False) -> None:
    """Raise a YAML error at ``node`` (``where``: "key 'k': " before the problem) if
    ``yaml11_number`` finds it reads as another number, ``float_underflow`` that it reads as 0
    though written nonzero, or, unless it is a mapping's ``key``, ``yaml11_bool`` finds it a
    YAML 1.1 boolean word."""
    problem = yaml11_number(loader, node) or float_underflow(node) \
        or (None if key or not loader.refuse_words else yaml11_bool(loader, node))
    if problem:
        raise yaml.constructor.ConstructorError(None, None, where + problem, node.start_mark)


def _construct_object(loader: Loader, node: yaml.Node, deep: bool = False) -> Any:
    """SafeLoader's construction, with a scalar that its tag cannot make a YAML error at its line
    and column: an impossible date (``seed: 2025-02-30``, "day is out of range for month") or an
    explicit tag's bad value (``!!float abc``) was Python's ValueError, an internal error without
    the file, line or field; an int of more than 4300 digits says so, and so does one beyond float64's
    range (``duration: 1000...0`` of 401 digits was an internal OverflowError where it was cast to float). A
    number that YAML 1.1 reads otherwise than YAML 1.2 and the command line (``yaml11_number``) is refused at
    its place, and so is a YAML 1.1 boolean word that is no mapping's key (``yaml11_bool``)."""
    _refuse_yaml11_number(loader, node, key=id(node) in getattr(loader, "_key_nodes", ()))
    try:
        value = yaml.SafeLoader.construct_object(loader, node, deep=deep)
        if type(value) is int and not -sys.float_info.max <= value <= sys.float_info.max:
            raise OverflowError("beyond float64's range, +-1.8e308: no setting takes it")
        return value
    except (ValueError, TypeError, AttributeError, OverflowError) as exc:
        if not isinstance(node, yaml.ScalarNode):
            raise
        kind = str(node.tag).rsplit(":", 1)[-1]
        shown = node.value if len(node.value) <= 40 else f"{node.value[:30]}...({len(node.value)} characters)"
        if isinstance(exc, OverflowError) and kind == "int":  # a 401-digit number: an internal OverflowError where
            raise yaml.constructor.ConstructorError(  # a setting was cast to float (simulate's duration, a sweep's grid)
                None, None, f"a whole number of {len(node.value)} characters, {exc}", node.start_mark) from None
        problem = digit_limit_problem(exc)  # int("9" * 5000): Python's limit
        if problem is None:
            why = f" ({' '.join(str(exc).split())})" if isinstance(exc, (ValueError, OverflowError)) else ""
            problem = f"{shown!r} is not a valid {'date or time' if kind == 'timestamp' else kind}{why}"
        raise yaml.constructor.ConstructorError(None, None, problem, node.start_mark) from None


Loader.construct_object = _construct_object  # type: ignore[method-assign,assignment]


class DuplicateKey(yaml.YAMLError):
    """A mapping that gives one key twice (PyYAML keeps the last silently)."""


def _construct_mapping(loader: Loader, node: yaml.MappingNode, deep: bool = False) -> Any:
    """SafeLoader's mapping, refusing a key written twice (merge keys ``<<`` may be overridden)."""
    if isinstance(node, yaml.MappingNode):
        seen: set[Any] = set()
        keys = loader.__dict__.setdefault("_key_nodes", set())  # a key may be a boolean word (``on:``)
        keys.update(id(key_node) for key_node, _ in node.value)
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":
                continue
            key = loader.construct_object(key_node, deep=True)
            try:
                duplicate = key in seen
                seen.add(key)
            except TypeError:  # an unhashable key: the base constructor says so
                continue
            if duplicate:
                raise DuplicateKey(f"key {key!r} given twice (again at line {key_node.start_mark.line + 1})")
        for key_node, value_node in node.value:  # a number read otherwise or a boolean word, named by its key
            # (the place alone below)
            items = value_node.value if isinstance(value_node, yaml.SequenceNode) else [value_node]
            for i, item in enumerate(items):
                shown = key_node.value if isinstance(key_node, yaml.ScalarNode) else "?"
                item_of = f", item {i + 1}" if isinstance(value_node, yaml.SequenceNode) else ""
                _refuse_yaml11_number(loader, item, f"key {shown!r}{item_of}: ")
    return yaml.SafeLoader.construct_mapping(loader, node, deep=deep)


Loader.construct_mapping = _construct_mapping  # type: ignore[method-assign,assignment]


def _flatten_mapping(loader: Loader, node: yaml.MappingNode) -> None:
    """SafeLoader's merge (``<<``), the keys it brings in from the merged mappings marked as keys
    too (``yaml11_bool`` passes a key such as ``on:`` over: one merged in was refused)."""
    yaml.SafeLoader.flatten_mapping(loader, node)
    loader.__dict__.setdefault("_key_nodes", set()).update(id(key_node) for key_node, _ in node.value)


Loader.flatten_mapping = _flatten_mapping  # type: ignore[method-assign,assignment]


class Dumper(yaml.SafeDumper):
    """The safe dumper, quoting text that :class:`Loader` refuses written plain: the boolean words
    ``y`` and ``n`` (any case) and ``yes`` / ``no`` / ``on`` / ``off`` in a case PyYAML reads as text
    (``yEs``). ``yaml.safe_dump`` wrote them plain (PyYAML reads them as text), so a config.yaml or
    sweep.yaml lmsbench wrote with such a value (a grid's ``['y', 'n']``) was refused when read back."""


Dumper.add_implicit_resolver("tag:yaml.org,2002:bool", _BOOL_WORD, list("yYnNoO"))


def dump(data: Any, **kwargs: Any) -> str:  # noqa: ANN401 - any YAML data
    """``yaml.safe_dump(data, **kwargs)`` with :class:`Dumper`: text :func:`load` reads back as written."""
    return yaml.dump(data, Dumper=Dumper, **kwargs)


class TooDeep(yaml.YAMLError):
    """YAML nested deeper than the parser's recursion allows."""


class AliasBomb(yaml.YAMLError):
    """A document whose aliases (``*name``) expand it far beyond its own text ("billion laughs"):
    nine lines of ``&a [*b, *b, ...]`` are 10^9 values to anything that walks them (a message's
    ``repr``, a dataclass's ``asdict``): ``simulate --sensor`` hung, eating memory, on one."""


class SelfReference(yaml.YAMLError):
    """A value that holds itself through an alias (``&a [*a]``): endless to anything that walks it."""


#: Largest YAML file read as a config or sweep (bytes), checked before it is parsed: PyYAML's
#: pure-Python parser takes about 4 s a MiB, and a 1.5 MB sweep file took 81 s to be refused.
#: The configs and sweeps of this project are a few KB; a grid of the most cells a sweep may have
#: (100,000 values of one parameter) is 0.7 MB written as a list, ``k: [3, 4, ...]``.
MAX_YAML_BYTES = 1 << 20


#: what a sweep file's size refusal adds: how a sweep file of the most cells stays small
SWEEP_SIZE_HINT = "sweep files are a few KB: a sweep's grid lists the values of each parameter, not every cell"


def size_problem(size: int, what: str = "a config file", hint: str = "they are a few KB") -> str | None:
    """Why a YAML file of ``size`` bytes is not read as ``what`` (a config file, a sweep file, a simulate
    folder's config.yaml, ...; None: it may be), ``hint`` saying how large one is. The message spoke of "a
    config or sweep file" and "a sweep's grid" for every file, a simulate folder's config.yaml too."""
    if size <= MAX_YAML_BYTES:
        return None
    return f"{size:,} bytes, more than the {MAX_YAML_BYTES:,} {what} may hold (refused unread; {hint})"


#: Values a document may expand to through its aliases beyond the size of its text (each value
#: written out takes at least a character, so a document without aliases never reaches it).
MAX_EXPANDED_VALUES = 1_000_000


def _check_expansion(doc: Any, text: str) -> None:
    """Raise AliasBomb / SelfReference for a document too big or endless once its aliases are
    expanded. Walks each distinct list and mapping once (iteratively: no recursion limit)."""
    limit = max(MAX_EXPANDED_VALUES, len(text))
    size: dict[int, int] = {}  # expanded values under each finished list / mapping, by id
    active: set[int] = set()  # the lists and mappings being walked: the current one's ancestors
    stack: list[tuple[Any, bool]] = [(doc, False)]
    while stack:
        obj, finished = stack.pop()
        if not isinstance(obj, (list, dict, set)):
            continue
        key = id(obj)
        items = list(obj.values()) + list(obj) if isinstance(obj, dict) else list(obj)
        if finished:
            active.discard(key)
            size[key] = 1 + sum(size.get(id(v), 1) for v in items)
            if size[key] > limit:
                raise AliasBomb(f"its aliases (*name) expand it to more than {limit:,} values (a 'billion laughs'); "
                                "write the values out")
            continue
        if key in size:
            continue
        if key in active:
            raise SelfReference("a value holds itself through an alias (&name ... *name inside it)")
        active.add(key)
        stack.append((obj, True))
        stack.extend((v, False) for v in items)


class Malformed(yaml.YAMLError):
    """PyYAML's error in one line, with its place (``line``, ``column``: 1-based, 0 where unknown):
    "line 2, column 1: expected ',' or ']', but got '<stream end>' (while parsing a flow sequence
    at line 1, column 4)". PyYAML's own spans lines, quotes the text under a caret, and names the
    source "<unicode string>", which read as the file's name after the real one."""

    def __init__(self, message: str, line: int = 0, column: int = 0) -> None:
        super().__init__(message)
        self.line, self.column = line, column


def _malformed(exc: yaml.YAMLError, text: str) -> Malformed:
    """``exc`` as a :class:`Malformed` (a duplicate key keeps its own message, prefixed the same way)."""
    if isinstance(exc, yaml.reader.ReaderError):  # a character YAML forbids: a position, not a line
        pos = max(0, min(int(exc.position), len(text)))
        line, column = text.count("\n", 0, pos) + 1, pos - (text.rfind("\n", 0, pos) + 1) + 1
        char = f"#x{exc.character:04x}" if isinstance(exc.character, int) else repr(exc.character)
        return Malformed(f"line {line}, column {column}: unacceptable character {char}: {exc.reason}", line, column)
    if isinstance(exc, yaml.MarkedYAMLError):
        mark = exc.problem_mark or exc.context_mark
        problem = exc.problem or exc.context or type(exc).__name__
        if exc.problem and exc.context:
            at = (f" at line {exc.context_mark.line + 1}, column {exc.context_mark.column + 1}"
                  if exc.context_mark is not None and exc.context_mark is not mark else "")
            problem += f" ({exc.context}{at})"
        if mark is None:
            return Malformed(problem)
        return Malformed(f"line {mark.line + 1}, column {mark.column + 1}: {problem}", mark.line + 1, mark.column + 1)
    return Malformed(" ".join(str(exc).split()))


def load(text: str, *, words: bool = False) -> Any:
    """Parse YAML text with :class:`Loader` (``words``: with :class:`WordsLoader`, YAML 1.1's
    boolean words read as PyYAML reads them, for YAML not written for lmsbench by its users).

    Raises:
        yaml.YAMLError: as ``yaml.safe_load`` does but in one line that starts with the place
            (:class:`Malformed`, "line L, column C: ..."), and for a duplicate key
            (:class:`DuplicateKey`), nesting too deep to parse (:class:`TooDeep`), aliases that
            expand the document beyond MAX_EXPANDED_VALUES and its length (:class:`AliasBomb`) or
            a value that holds itself (:class:`SelfReference`).
    """
    try:
        doc = yaml.load(text, Loader=WordsLoader if words else Loader)  # noqa: S506 - both are SafeLoaders
    except RecursionError:
        raise TooDeep("nested too deeply to parse") from None
    except (DuplicateKey, TooDeep):
        raise
    except yaml.YAMLError as exc:
        raise _malformed(exc, text) from None
    except ValueError as exc:  # a scalar's is a YAML error at its place (_construct_object); any other, without one
        raise Malformed(" ".join(str(exc).split())) from None
    _check_expansion(doc, text)
    return doc
