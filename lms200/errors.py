"""The project's base exception: every known error a user can fix derives from it.

The command line turns these into one-line messages (exit status 2) instead of tracebacks.
"""

import os
import re
from typing import TypeVar

_E = TypeVar("_E", bound=BaseException)


def in_chain(exc: BaseException, kind: type[_E]) -> _E | None:
    """The first exception of ``kind`` among ``exc`` and its causes and contexts (``__cause__``, else
    ``__context__``), or None: what an error raised while handling another hides (the command line's
    Ctrl-C under a worker's error, a full disk under matplotlib's clean-up error)."""
    seen: set[int] = set()
    cur: BaseException | None = exc
    while cur is not None and id(cur) not in seen:
        if isinstance(cur, kind):
            return cur
        seen.add(id(cur))
        cur = cur.__cause__ or cur.__context__
    return None


#: a line break with the blanks around it (LmsbenchError's messages are one line)
_LINE_BREAK = re.compile(r"[ \t]*[\r\n]+\s*")


def one_line(text: str) -> str:
    """``text`` with each line break (``\\n``, ``\\r``, and the blanks around it: the indent under
    PyYAML's caret) one space, and no blanks at its ends when it had a break; other whitespace kept
    (a path with two spaces stays itself). Text without a line break is returned as it is."""
    return _LINE_BREAK.sub(" ", text).strip() if "\n" in text or "\r" in text else text


class LmsbenchError(Exception):
    """A known error whose message says what went wrong and what to do about it, on one line: a
    message's line breaks (and the spaces around them) become one space (:func:`one_line`), so a
    value quoted by its repr, a 2-D array's spanning lines, does not break it (``Scan(ranges,
    angle_min=np.ones((2, 3)), ...)``, ``extract(scan, method=array)``, ``read_log(path,
    topic=array)``: the API raised multi-line errors from the ~90 messages that quote a value with
    ``!r``; fuzz round 7). A subclass that sets its ``args`` again later passes them through
    :func:`one_line` too. Keyword arguments go to the other base (``ImportError``'s ``name``,
    ``path``)."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        if len(args) == 1 and isinstance(args[0], str):
            args = (one_line(args[0]),)
        super().__init__(*args, **kwargs)


class NumbaUnavailableError(LmsbenchError, ImportError):
    """numba, which compiles the extractors, the simulator's ray caster and the ICP, is not
    installed or cannot be loaded."""


class LogFormatError(LmsbenchError, ValueError):
    """A log file that cannot be read: the message names the file and the line number, or the file
    alone (``line_no`` None) for a problem of the whole file (no laser line in it, not a CARMEN log,
    an archive): those said ``FILE:1:``, pointing at a line that was not at fault."""

    def __init__(self, path: str | os.PathLike[str], line_no: int | None, reason: str) -> None:
        self.path = str(path)
        self.line_no = line_no
        self.reason = reason
        super().__init__(f"{self.path}: {reason}" if line_no is None else f"{self.path}:{line_no}: {reason}")


class ScanError(LmsbenchError, ValueError):
    """A Scan whose fields cannot make one: the message starts with the field's name."""


class InputError(LmsbenchError, ValueError):
    """An argument of a public call that cannot work: the message starts with the argument's name."""


class LogNotFoundError(LmsbenchError, FileNotFoundError):
    """A log path that does not exist, or is a folder that is not a ROS 2 bag, or a device or pipe."""


class LmsDeviceError(LmsbenchError):
    """A problem talking to an LMS200 (real or virtual): the message says what was asked and what came back."""


class LmsTimeoutError(LmsDeviceError, TimeoutError):
    """The device did not answer a request in time (after the retries). From the driver's request
    loop: ``budget_s``, the seconds each attempt waited, and ``attempts``, what each attempt saw
    (as its message lists them), for a caller that words its own message (the baud change)."""

    budget_s: float | None = None
    attempts: tuple[str, ...] = ()


class LmsNakError(LmsDeviceError):
    """The device answered a request with NAK (0x15): it received the telegram with a bad CRC."""


class LmsModeRefusedError(LmsDeviceError):
    """The device refused a mode, baud, variant or configuration change."""


class LmsLinkError(LmsDeviceError, ConnectionError):
    """The port or connection failed mid-use (a USB adapter unplugged, a TCP link dropped): the
    message names the port, the baud and what was being done."""


class LmsProtocolError(LmsDeviceError, ValueError):
    """A telegram that does not make sense: wrong reply code, bad length, unknown variant, ..."""


class LmsStatusError(LmsProtocolError):
    """A scan telegram whose STATUS byte says its values are not to be used: an error or a fatal
    error (bits 0-2 of 3 or more) or implausible values (bit 6): ``lms200.protocol.status_problem``."""


class LmsbenchWarning(UserWarning):
    """Something read that still works but should be written differently (an old spelling of a
    config field): the message names the file where known and says what to write instead. The
    command line prints it as one line, ``lmsbench CMD: warning: ...``."""
