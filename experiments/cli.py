"""The ``lmsbench`` command line. Each subcommand lives in its own module under
``experiments/commands/`` and exposes ``register(subparsers)``; this module finds them all.

Known errors (``lms200.LmsbenchError``, any ``OSError``: missing files, bad paths, unreachable
schedulers or devices) and bad options become one-line messages ``lmsbench CMD: error: ...`` with
exit status 2; Ctrl-C exits with 130 and one line, within INTERRUPT_GRACE_S even when a cleanup
(closing a Dask cluster whose workers are in the middle of cells) would take longer; SIGTERM (``kill``,
a batch system's time limit) stops the same way, with 143 and "terminated"; either after the command
ended, while the interpreter exits, leaves the command's own status, with no line. An exception raised by the user's own code that a
command runs (a ``--methods MODULE:FUNCTION`` extractor: ``experiments.user_methods.UserMethodFailed``)
is a user error too, named as such (exit 2; ``LMSBENCH_TRACEBACK=1`` shows its traceback). Anything
else is a bug: one line saying so, exit status 1 (``LMSBENCH_TRACEBACK=1`` shows the traceback).
"""

from __future__ import annotations

import argparse
import atexit
import errno
import functools
import importlib
import io
import logging
import os
import pkgutil
import tempfile
import _thread
import signal
import sys
import threading
import time
import traceback
import warnings
from pathlib import Path
from typing import Any, Sequence



def _command_words(argv: Sequence[str]) -> str:
    """The command ``argv`` names, as its messages do (``sweep``, ``lms200 record``), read before
    the parser exists: the words before the first option."""
    words = []
    for word in argv:
        if word.startswith("-") or len(words) == (2 if words[:1] == ["lms200"] else 1):
            break
        words.append(word)
    return " ".join(words)


#: The signals that stop a command in order, with the word said and the exit status (128 + signal).
STOP_SIGNALS = {signal.SIGINT: ("interrupted", 130), signal.SIGTERM: ("terminated", 143)}
#: the stop signal that came before the command's own handler was in place (see _stopped_while_starting)
_EARLY_STOP: list[int] = []


def _stop_while_starting(signum: int, frame: Any) -> None:
    """SIGTERM before the command's own handler is in place: stop as Ctrl-C does there."""
    _EARLY_STOP.append(signum)
    raise KeyboardInterrupt


def _stopped_while_starting(argv: Sequence[str]) -> int:
    """Ctrl-C before the command's own handler is in place (lmsbench's imports, ~0.5-1 s, and
    the reading of its options): the one line and 130. It was Python's traceback of the import it
    cut (`lmsbench sweep S.yaml` stopped 0.5 s in) and exit status -2. SIGTERM there: "terminated"
    and 143 (it killed the process: exit -15, no line)."""
    name = _command_words(argv)
    word, status = STOP_SIGNALS[signal.Signals(_EARLY_STOP[-1])] if _EARLY_STOP else STOP_SIGNALS[signal.SIGINT]
    try:
        sys.stderr.write(f"lmsbench{' ' + name if name else ''}: {word}\n")
        sys.stderr.flush()
    except (OSError, ValueError):
        pass
    return status


def _as_the_command() -> bool:
    """Whether this module is imported by the ``lmsbench`` command (its script, ``python -m
    experiments.cli``), not by a program of the user's, whose signals are its own."""
    return __name__ == "__main__" or Path(sys.argv[0]).name == "lmsbench"


def _a_worker_process() -> bool:
    """Whether this is a child process of multiprocessing (a local cluster's Dask worker, given
    lmsbench's ``sys.argv``): its SIGTERM, from a ``kill`` of the whole process group, is left
    as it was (with the handler above, workers that were importing printed 75 lines of traceback)."""
    if "--multiprocessing-fork" in getattr(sys, "orig_argv", ()):  # a spawned child, given the script's argv
        return True
    mp = sys.modules.get("multiprocessing")  # not yet imported here in lmsbench itself
    if mp is None:
        return False
    # a forkserver's child runs the script again with the parent's argv and no parent_process() yet: it is
    # "inheriting" while it prepares (review: its SIGTERM was caught for its whole life)
    return mp.parent_process() is not None or bool(getattr(mp.process.current_process(), "_inheriting", False))


if (_as_the_command() and not _a_worker_process() and threading.current_thread() is threading.main_thread()
        and signal.getsignal(signal.SIGTERM) == signal.SIG_DFL):
    signal.signal(signal.SIGTERM, _stop_while_starting)

try:  # lmsbench's packages: most of its start-up time
    from features.batch import default_threads
    from lms200 import LmsbenchError, LogFormatError
    from lms200.errors import LmsbenchWarning

    from . import commands
    from .options import OneLineParser, mid_sentence, shorten_quoted
except KeyboardInterrupt:
    if not _as_the_command():  # imported by a program: its own Ctrl-C
        raise
    raise SystemExit(_stopped_while_starting(sys.argv[1:])) from None


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog="lmsbench",
        description="Fast feature extraction from 2-D laser rangefinders: a research testbed.",
    )
    parser.add_argument("--version", action=_Version, help="print lmsbench's version (and git commit, run from a checkout) and exit")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for info in sorted(pkgutil.iter_modules(commands.__path__), key=lambda m: m.name):
        module = importlib.import_module(f"{commands.__name__}.{info.name}")
        if hasattr(module, "register"):
            module.register(sub)
    parser.set_root()  # an option given to the wrong command names the commands that take it
    return parser


class _Version(argparse.Action):
    """``lmsbench --version``: the installed package's version and, run from a git checkout, its
    commit (experiments.provenance.version_text), worked out only when asked."""

    def __init__(self, option_strings: Sequence[str], dest: str = argparse.SUPPRESS, help: str | None = None) -> None:
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, help=help)

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: Any,
                 option_string: str | None = None) -> None:
        from .provenance import version_text

        try:
            sys.stdout.write(version_text() + "\n")
            sys.stdout.flush()
        except BrokenPipeError:  # a reader that went away (`--version | head -0`), as argparse's --help: nothing to say it to
            _stdout_to_devnull()
        except OSError as exc:  # `--version > /dev/full`: it exited 0, nothing written
            parser.exit(_stdout_failed("", exc))
        parser.exit()


REDELIVER_S = 0.05  # s after a swallowed stop (see _Interrupt.swallowed) before it is raised again
REDELIVER_MAX = 10  # tries of REDELIVER_S (0.5 s) to raise a stop outside numba's code; then it is raised anyway
INTERRUPT_GRACE_S = 15.0  # s after Ctrl-C for cleanup; then child processes are killed and the process exits 130

#: the command was stopped by a signal (its line written): the stop signals are ignored at the exit's end
_STOPPED = threading.Event()
#: the command ended, not stopped (the process's own main()): the same (see _Interrupt.after_the_end)
_ENDED = threading.Event()


@atexit.register  # at this module's import: it runs after the exit handlers of libraries imported later (Dask's)
def _ignore_stop_signals_at_the_end() -> None:
    """Once a command stopped by Ctrl-C or SIGTERM has run the exit handlers (Dask closing its
    cluster, where a second Ctrl-C still ends it at once), the stop signals are ignored: Python's
    finalization then sets a handled signal back to its default, and one more Ctrl-C there (a
    user's, or a test's repeated SIGINT) killed the process after its line: exit -2, not 130. The
    same after a command that returned (its status stands: _Interrupt.after_the_end): the
    modules' teardown that follows took ~0.7 s after ``simulate``, and a SIGTERM there was exit 143
    with no line."""
    if (_STOPPED.is_set() or _ENDED.is_set()) and threading.current_thread() is threading.main_thread():
        for sig in STOP_SIGNALS:
            signal.signal(sig, signal.SIG_IGN)


class _Interrupt:
    """Ctrl-C or SIGTERM: raise KeyboardInterrupt for an orderly stop, and start a timer that ends
    the process (children killed, exit 130 / 143, the one line) if that stop has not finished in
    INTERRUPT_GRACE_S (a Dask cluster waiting for its workers' running cells, an exit handler).
    SIGTERM killed the process at once: no line, exit -15, a multi-line warning of leaked
    semaphores from multiprocessing, and a local cluster's workers left to notice on their own."""

    def __init__(self, name: str) -> None:
        self.name, self.reported = name, False
        self.ended = False  # the command returned or failed, in the process's own main(): see after_the_end
        self.status: int | None = None  # its exit status, once main() has it
        self.late: threading.Timer | None = None  # a stop signal came after the end: see after_the_end
        self.lock = threading.Lock()  # the one line: written once, whoever comes first (see report)
        self.timer: threading.Timer | None = None
        self.signum: int = signal.SIGINT
        self.redeliver = False  # the stop's KeyboardInterrupt was swallowed: raise it again
        self.retry_due = False  # the next signal is _raise_again's own (interrupt_main), not a user's
        self.retries = 0  # of the stop held back (see handler)
        self.in_jit = False  # the stop is pending in features.jit (see handler)
        self.in_numba = False  # the stop was held back in numba's code (else in sys.unraisablehook: swallowed)
        self.retry_timer: threading.Timer | None = None  # _raise_again's
        self.in_hook = False  # sys.unraisablehook is running
        self.running = False  # the command is running (a swallowed stop is raised again only then)

    @property
    def word_and_status(self) -> tuple[str, int]:
        return STOP_SIGNALS.get(signal.Signals(self.signum), STOP_SIGNALS[signal.SIGINT])

    def handler(self, signum: int, frame: Any) -> None:
        retry, self.retry_due = self.retry_due, False
        if retry and not self.redeliver:  # _raise_again's own, for a stop raised meanwhile (features.jit)
            return
        if retry:  # the first stop again (see swallowed, _raise_again), not a second Ctrl-C
            if not self.running:  # the command returned meanwhile: nothing to stop (raised during the
                self._drop_held_stop()  # exit, it cut an atexit callback short, silently: a review)
                return
            if self.in_jit and not _jit_stop_pending():  # features.jit raised it as its compiled call returned
                self._drop_held_stop()
                return
            self.retries += 1
            if (self.in_hook or _in_numba(frame)) and self.retries < REDELIVER_MAX:
                self._raise_again()  # not inside the hook itself, where it would be swallowed again, nor
                return  # inside a compiled call (see _in_numba); after REDELIVER_MAX tries, raised anyway
            self._drop_held_stop()  # (back-to-back compiled calls: each try landed in one, and the command
            raise KeyboardInterrupt  # went on until the grace timer killed it, or ended 0, the stop lost)
        if self.ended:  # the command is over: the signal meets the interpreter's exit, nothing to stop
            self.after_the_end(signum)
            return
        if self.timer is not None:  # a second Ctrl-C while the first one's stop runs: stop now, as said
            self.hard_stop()  # (it raised KeyboardInterrupt inside the cleanup: a traceback, exit -2)
        self.signum = signum
        self.timer = threading.Timer(INTERRUPT_GRACE_S, self.hard_stop)
        self.timer.daemon = True
        self.timer.start()
        if _in_numba(frame):  # raised there, it broke the compiled call (a SystemError, or the process crashed)
            self.redeliver, self.retries, self.in_numba = True, 0, True
            self.in_jit = _set_jit_stop(True)  # raised as an extractor's compiled call returns (features.jit)
            self._raise_again()  # else (another compiled call) tried again REDELIVER_S later
            return
        raise KeyboardInterrupt

    def _drop_held_stop(self) -> None:
        """The stop held back (see handler) is raised, or not to be: no retry, nothing pending in features.jit."""
        self.redeliver = self.in_jit = False
        _set_jit_stop(False)
        if self.retry_timer is not None:  # a retry left for it would stop the next command in this process
            self.retry_timer.cancel()

    def swallowed(self, unraisable: Any) -> bool:
        """Whether ``unraisable`` (what ``sys.unraisablehook`` is given) is this stop's
        KeyboardInterrupt raised where Python ignores exceptions (a garbage-collection callback,
        as Dask's, a ``__del__``, a weakref callback); if so it is raised again in the main thread
        at once. It printed "Exception ignored in: <function ...>" and a traceback above the one
        line, and the command went on until a second Ctrl-C or the grace timer stopped it."""
        if not isinstance(unraisable.exc_value, KeyboardInterrupt) or self.timer is None or not self.running:
            return False
        self.in_hook, self.redeliver, self.retries, self.in_numba = True, True, 0, False
        try:
            self._raise_again()
        finally:
            self.in_hook = False
        return True

    def _raise_again(self) -> None:
        """The handler run again in the main thread REDELIVER_S from now, from another thread: by
        then the hook and the collection have returned (a signal tripped at once is handled inside
        the hook itself, where its exception is swallowed too)."""
        timer = self.retry_timer = threading.Timer(REDELIVER_S, self._retry)
        timer.daemon = True
        timer.start()

    def _retry(self) -> None:
        """The timer's signal to the main thread: marked as its own, so that a user's second Ctrl-C
        meanwhile stops at once (it was taken as the retry)."""
        if self.redeliver:  # not raised meanwhile (features.jit, the command's end)
            self.retry_due = True
            _thread.interrupt_main(self.signum)

    def report(self) -> None:
        """Write the stop's one line unless it is out already: the main thread's orderly stop, the
        grace timer's hard stop and a second Ctrl-C each ask, and exactly one line is written
        (the flag was set before the line: a hard stop between exited with no line, and one that
        had read the flag before wrote a second). In the main thread the stop signals wait until
        the line is out (a second Ctrl-C's hard stop is run after it, not inside the lock)."""
        main = threading.current_thread() is threading.main_thread() and hasattr(signal, "pthread_sigmask")
        blocked = signal.pthread_sigmask(signal.SIG_BLOCK, set(STOP_SIGNALS)) if main else None
        try:
            if not self.lock.acquire(timeout=2.0):  # a line stuck in a full pipe: exit without one
                return
            try:
                if not self.reported:
                    word, _ = self.word_and_status
                    sys.stderr.write(f"lmsbench {self.name}: {word}\n")
                    sys.stderr.flush()
                    self.reported = True
            finally:
                self.lock.release()
        except (OSError, ValueError):  # stderr closed: nothing to say it on
            pass
        finally:
            if blocked is not None:
                signal.pthread_sigmask(signal.SIG_SETMASK, blocked)

    def after_the_end(self, signum: int) -> None:
        """A stop signal after the command ended (returned, its outputs and last line written, or
        failed, its error said next), while the interpreter exits (~0.7 s after ``simulate``: the
        exit handlers, then the modules' teardown): the command's own status stands, with no line.
        The exit goes on as it would (every exit handler run: matplotlib's temporary folder
        removed, a cluster closed), ended with that status if it is not over in INTERRUPT_GRACE_S;
        a second signal ends it at once (children killed). It was killed by the signal: exit 143
        (SIGTERM) with no "terminated" line, or Ctrl-C's KeyboardInterrupt from where it landed."""
        if self.late is None:
            self.signum = signum
            self.late = threading.Timer(INTERRUPT_GRACE_S, self.end_with_status)
            self.late.daemon = True
            self.late.start()
        else:
            self.end_with_status()

    def end_with_status(self) -> None:
        """Exit at once with the command's status, its children killed (stdout was flushed when
        main() got the status). Before main() has it (the command's last writes stuck on a full
        pipe), a stop as any other: the one line and 130 / 143."""
        if self.status is None:
            self.hard_stop()
            return
        _kill_children()
        os._exit(self.status)

    def hard_stop(self) -> None:
        _kill_children()
        _, status = self.word_and_status
        self.report()
        os._exit(status)


def _in_numba(frame: Any) -> bool:
    """Whether the signal handler runs in numba's own Python code (``_numba_unpickle``, which every compiled
    extraction, scan match and ray cast calls, 4-6 times, to box its results): a KeyboardInterrupt raised
    there left the compiled call with "SystemError: ... returned a result with an exception set" or, when
    it cut the unpickling short, crashed the process (a segmentation fault: no line, exit -11; 1 in 18 Ctrl-Cs
    during extract_many, probe 14). The stop is held back (_Interrupt.handler): raised as an extractor's compiled
    call returns (features.jit.stop_pending), else tried again every REDELIVER_S, REDELIVER_MAX times at most."""
    name = getattr(frame, "f_globals", {}).get("__name__", "") if frame is not None else ""
    return isinstance(name, str) and name.startswith("numba.")


def _set_jit_stop(pending: bool) -> bool:
    """Set features.jit's ``stop_pending`` (see _Interrupt.handler) if that module is loaded; whether it is."""
    jit = sys.modules.get("features.jit")
    if jit is None:
        return False
    jit.stop_pending = pending
    return True


def _jit_stop_pending() -> bool:
    jit = sys.modules.get("features.jit")
    return bool(getattr(jit, "stop_pending", False))


def _kill_children() -> None:
    """Kill this process's child processes (after Ctrl-C: Dask workers a cluster's close left
    behind would keep running their cells, and keep the terminal's pipes open)."""
    try:
        import psutil  # a dependency of dask.distributed

        for child in psutil.Process().children(recursive=True):
            child.kill()
    except Exception:  # noqa: BLE001 - exiting anyway
        pass


class _ClosedStdout(io.TextIOBase):
    """sys.stdout when the caller closed its descriptor (``lmsbench info LOG >&-``): Python leaves
    it None, and the first print was "internal error: AttributeError: 'NoneType' object has no
    attribute 'write'" with a traceback, exit 1. A write fails as one to ``/dev/full`` does (the
    one line "cannot write the standard output: ...", exit 2); a command that prints nothing is
    not stopped by it."""

    def writable(self) -> bool:
        return True

    def write(self, text: str) -> int:
        if not text:
            return 0
        raise OSError(errno.EBADF, "bad file descriptor (it was closed)")

    def flush(self) -> None:
        pass

    def isatty(self) -> bool:
        return False


def _standard_streams() -> None:
    """A standard descriptor the caller closed (``>&-``, ``2>&-``, ``<&-``) is pointed at /dev/null
    before any work: else the next file opened takes its number, and what a library or a child
    process writes to "its" stderr lands in it. A closed stderr becomes a text stream on that
    /dev/null (Python left it None: a print to it went to stdout, ``sim``'s import failed and the
    command with it, exit 1), a closed stdout one whose writes fail (_ClosedStdout)."""
    for fd in (0, 1, 2):
        try:
            os.fstat(fd)
            continue
        except OSError:
            pass
        try:
            devnull = os.open(os.devnull, os.O_RDONLY if fd == 0 else os.O_WRONLY)
        except OSError:
            continue
        if devnull != fd:
            os.dup2(devnull, fd)  # inheritable, as dup2 makes it
            os.close(devnull)
        else:  # os.open's descriptor is not inherited (PEP 446): a child process (a Dask worker) found it
            os.set_inheritable(fd, True)  # closed, its sys.stderr None, and its cells failed to import sim
    if sys.stderr is None:
        try:
            sys.stderr = open(2, "w", encoding="utf-8", errors="backslashreplace", buffering=1, closefd=False)
        except OSError:
            pass
    if sys.stdout is None:
        sys.stdout = _ClosedStdout()


class _NoConfigFolderWarning(logging.Filter):
    """Drops matplotlib's warnings where the config folder it chose itself (MPLCONFIGDIR unset) cannot be
    made or written (HOME read-only, missing or a file: a container run as a user without a home has
    HOME=/, a cluster's compute nodes a read-only one): "mkdir -p failed for path ...", "... is not a
    writable directory" (a read-only home that has ~/.config/matplotlib) and "Matplotlib created a
    temporary cache directory at ... because there was an issue with the default path (...)", lines on
    stderr of every command that draws (simulate, slam, compare, ...), above their own. matplotlib then
    uses a temporary folder, removed at exit: nothing for the user to do. A folder the user named
    (MPLCONFIGDIR) that cannot be used is still said: that is theirs to mend."""

    def filter(self, record: logging.LogRecord) -> bool:
        text = record.getMessage()
        if "created a temporary cache directory" in text:  # said after matplotlib set MPLCONFIGDIR to it
            return not ("an issue with the default path" in text or "an issue with resolving the home" in text)
        if text.startswith("mkdir -p failed for path") or text.endswith(" is not a writable directory"):
            return bool(os.environ.get("MPLCONFIGDIR"))  # said before matplotlib sets it: the user's, or unset
        return True


#: one filter for every main() (tests call it many times): added again, the same one is not doubled
_NO_CONFIG_FOLDER_WARNING = _NoConfigFolderWarning()


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command ``argv`` names (None: ``sys.argv[1:]``) and return its exit status. Run so, as
    the process itself (the ``lmsbench`` script, ``python -m experiments.cli``), its handler of
    Ctrl-C and SIGTERM stays in place after the command returns, until the process exits: a stop
    signal then ends nothing and the command's status stands (_Interrupt.after_the_end). Called
    with ``argv`` (a test, a script of the user's), the handlers before it are put back."""
    _standard_streams()
    logging.getLogger("matplotlib").addFilter(_NO_CONFIG_FOLDER_WARNING)  # before matplotlib is imported
    ended: list[_Interrupt] | None = [] if argv is None else None  # the process's own: its handler kept
    try:
        status = _flushed(_main(argv, ended))
    except KeyboardInterrupt:  # before the command's handler is in place: its options being read
        return _flushed(_stopped_while_starting(sys.argv[1:] if argv is None else argv))
    finally:
        _end_start_handler()
    for interrupt in ended or ():
        interrupt.status = status
    return status


def _end_start_handler() -> None:
    """SIGTERM back to its default where the start-up handler (``_stop_while_starting``) is still in
    place once the command returned (``--help``, a usage error, an error before the command's own
    handler): a SIGTERM at the exit then raised KeyboardInterrupt in an exit handler ("Exception
    ignored in atexit callback"), or added "terminated" and 143 after a usage error's line (review)."""
    if (threading.current_thread() is threading.main_thread()
            and signal.getsignal(signal.SIGTERM) is _stop_while_starting):
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _flushed(status: int) -> int:
    """``status`` after stdout is flushed here, not at the interpreter's exit, where a reader that
    went away after a Ctrl-C, an error or ``--help`` turned it into 120 with Python's 'Exception
    ignored ... BrokenPipeError' (that status is kept, what is left goes to /dev/null). Output that
    cannot be written (a full disk under ``> FILE``) is an error line, and 2 where it was 0."""
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        _stdout_to_devnull()
    except OSError as exc:
        return _stdout_failed("", exc, status)
    except ValueError:  # stdout closed by the caller: nothing left to write
        pass
    return status


def _main(argv: Sequence[str] | None, ended: list[_Interrupt] | None = None) -> int:
    """main()'s work; ``ended``, a list where the process's own main() runs it, is given the
    command's stop handler, which then stays in place after the command (main() sets its status)."""
    parser = build_parser()
    argv = sys.argv[1:] if argv is None else list(argv)
    try:
        _options_before_commands(parser, argv)
        args, extra = parser.parse_known_args(argv)
        if extra:  # said by the command's own parser: "lmsbench compare: error: ...", not "lmsbench: error:"
            _command_parser(parser, args).error(f"unrecognized arguments: {' '.join(extra)}")
    except SystemExit as exc:  # --help (0) or a bad option, already printed in one line (2)
        return int(exc.code or 0)
    except OSError as exc:  # --help to a standard output that cannot be written (options.OneLineParser._print_message)
        return _stdout_failed(_command_words(argv), exc)
    if not getattr(args, "func", None):  # "lmsbench" or "lmsbench lms200" alone: a usage error, one line, 2
        sub = _command_parser(parser, args)
        try:
            sub.error("a command is required: " + ", ".join(_commands(sub)))
        except SystemExit as exc:
            return int(exc.code or 0)
    name = " ".join(filter(None, (args.command, getattr(args, "lms200_command", None))))
    interrupt = _Interrupt(name)
    main_thread = threading.current_thread() is threading.main_thread()
    previous = {sig: signal.signal(sig, interrupt.handler) for sig in STOP_SIGNALS} if main_thread else {}
    keep = ended is not None and main_thread  # the handler stays after the command (see main)
    if keep and ended is not None:
        ended.append(interrupt)
    previous_hook = sys.unraisablehook
    if main_thread:
        sys.unraisablehook = lambda u: interrupt.swallowed(u) or previous_hook(u)
    previous_show = warnings.showwarning
    warnings.showwarning = functools.partial(_show_warning, name, previous_show)
    done = False  # whether the command's work ended (a reader of stdout that went away then is no loss)
    started_ns = time.time_ns()  # files in --out modified since were written by this run (_stdout_gone)
    watched = _WatchedStdout(sys.stdout)
    try:
        default_threads()  # a bad $LMSBENCH_THREADS is refused before any work, by every command
        from .options import holding_outputs

        holding_outputs()  # the command's --out is its own until it ends (options.hold_output)
        interrupt.running = True
        sys.stdout = watched  # type: ignore[assignment]
        try:
            status = int(args.func(args) or 0)
            if interrupt.redeliver and interrupt.in_numba:  # a stop held back in numba's code as the command
                interrupt._drop_held_stop()  # returned (see _Interrupt.handler): it ended 0 as if not stopped
                raise KeyboardInterrupt
            done = True
            sys.stdout.flush()  # here, not at exit: a reader that went away (`| head`) is said below
        finally:
            interrupt.running = False
            # returned, or failed (its error said next): a stop signal from here on leaves its status as
            # it is (after_the_end). In release_outputs below, SIGTERM after simulate's last line was
            # "interrupted", 130 (a KeyboardInterrupt out of this function); after it, exit 143, no line
            interrupt.ended = keep and interrupt.timer is None
            if sys.stdout is watched:
                sys.stdout = watched.stream
        return status
    except (LmsbenchError, OSError) as exc:  # OSError: missing files, bad paths, unreachable hosts, timeouts
        if interrupt.timer is not None or _from_interrupt(exc):  # what Ctrl-C broke: not the input's error
            return _interrupted(interrupt)
        if isinstance(exc, BrokenPipeError) and _stdout_closed():
            stopped = not done and _writes_outputs(args) and not getattr(args, "outputs_complete", False)
            return _stdout_gone(name, stopped, getattr(args, "out", None), started_ns)
        if isinstance(exc, OSError) and exc is watched.failed:
            _end_progress_bars()  # `lmsbench info LOG > /dev/full`: it said "error: [Errno 28] No space left on device"
            return _stdout_failed(name, exc)
        _end_progress_bars()
        if _users_code(exc) and os.environ.get("LMSBENCH_TRACEBACK"):
            traceback.print_exception(exc)  # the user's exception first, then where lmsbench called it
        text = _full_disk(exc, getattr(args, "out", None)) or _cwd_gone(exc) or _one_line(exc)
        _say(f"lmsbench {name}: error: {text}{_skip_hint(exc, args)}{_traceback_hint(exc)}")
        return 2
    except KeyboardInterrupt:
        return _interrupted(interrupt)
    except SystemExit as exc:  # no command exits so: code it ran called sys.exit() (a user's sweep cell kind)
        if interrupt.timer is not None:  # it ended the command silently with that status (0: as if finished)
            return _interrupted(interrupt)
        if os.environ.get("LMSBENCH_TRACEBACK"):
            traceback.print_exception(exc)
        _end_progress_bars()
        _say(f"lmsbench {name}: error: code the command ran called sys.exit({exc.code!r}), which stopped it "
             "before it finished (a user's extractor or sweep cell kind?"
             f"{'' if os.environ.get('LMSBENCH_TRACEBACK') else '; LMSBENCH_TRACEBACK=1 shows where'})")
        return 2
    except BaseException as exc:  # a bug, not a user error: say so in one line (GeneratorExit: a traceback)
        if interrupt.timer is not None or _from_interrupt(exc):
            # Ctrl-C inside a compiled (numba) call: the KeyboardInterrupt comes out as a SystemError
            # ("<function _numba_unpickle> returned a result with an exception set"), not a bug
            return _interrupted(interrupt)
        if os.environ.get("LMSBENCH_TRACEBACK"):
            raise
        _end_progress_bars()
        _say(f"lmsbench {name}: internal error: {type(exc).__name__}: {_one_line(exc)} "
             "(a bug in lmsbench; LMSBENCH_TRACEBACK=1 shows where)")
        return 1
    finally:
        from .options import release_outputs

        release_outputs()
        interrupt._drop_held_stop()  # a stop pending in features.jit ends with its command, not in the next
        if interrupt.timer is None:  # stopped by a signal: the handler stays for the exit's own cleanup
            if interrupt.ended:  # (atexit: Dask closing clusters), where a second Ctrl-C printed a traceback;
                _ENDED.set()  # it now ends the process at once. A command that ended: kept till the exit
            else:
                for sig, handler in previous.items():
                    signal.signal(sig, handler)
            if main_thread:
                sys.unraisablehook = previous_hook
            warnings.showwarning = previous_show


PIPE_CLOSED_STATUS = 141  # 128 + SIGPIPE: what a shell reports for a command whose reader went away


def _stdout_closed() -> bool:
    """Whether stdout is a pipe whose reader has gone (`lmsbench info LOG | head -1`)."""
    try:
        import select

        poller = select.poll()
        poller.register(sys.stdout.fileno(), select.POLLOUT)
        return any(events & (select.POLLERR | select.POLLHUP) for _, events in poller.poll(0))
    except (OSError, ValueError, AttributeError):  # no file descriptor (a test's capture), no poll
        return False


def _stdout_gone(name: str, stopped: bool, out: object, started_ns: int = 0) -> int:
    """A reader of stdout that went away (`lmsbench info LOG | head -4`): no error message (it was
    'error: [Errno 32] Broken pipe', exit 2, or with buffered output Python's 'Exception ignored ...
    BrokenPipeError' at exit, status 120), the status a shell gives for SIGPIPE. A command that
    writes outputs (an --out option: ``out``, None while its default folder is not made) and was
    ``stopped`` in its work by it (`lmsbench demo | head -1`) says so in one line on stderr, with
    what it left: nothing, or how many files it wrote in ``out`` since ``started_ns`` (time.time_ns):
    `figures --out DIR | head -1`, stopped before DIR was made, said "DIR is incomplete". What is
    left in stdout's buffer goes to /dev/null, so the interpreter's last flush does not fail again."""
    _stdout_to_devnull()
    if stopped:
        _end_progress_bars()
        from .options import release_outputs

        release_outputs()  # first: an --out folder made to be locked and still empty is removed (nothing was written)
        written = _files_written(Path(out), started_ns) if isinstance(out, (str, os.PathLike)) else 0
        if not written:
            left = f"nothing was written{f' in {out}' if out is not None and Path(out).is_dir() else ''}"
        elif Path(out).is_dir():
            left = f"{out} is incomplete: this run wrote {written} file{'s' if written > 1 else ''} there before it stopped"
        else:
            left = f"{out} is incomplete"
        _say(f"lmsbench {name}: stopped: the reader of its standard output went away; {left}")
    return PIPE_CLOSED_STATUS


MTIME_SLACK_NS = 10_000_000  # a file's mtime comes from the kernel's coarse clock, a few ms behind time.time_ns


def _files_written(out: Path, since_ns: int) -> int:
    """How many files ``out`` (a folder, searched through; or a file) holds that were modified at
    or after ``since_ns`` (time.time_ns): the ones this run wrote."""
    def fresh(path: str | os.PathLike) -> bool:
        try:
            return os.stat(path).st_mtime_ns >= since_ns - MTIME_SLACK_NS
        except OSError:
            return False

    if not out.is_dir():
        return int(out.is_file() and fresh(out))
    return sum(fresh(os.path.join(top, f)) for top, _, files in os.walk(out) for f in files if not f.startswith("."))


def _writes_outputs(args: argparse.Namespace) -> bool:
    """Whether the command writes files: it has an --out option, and is not one whose output without
    it is stdout alone (``calibrate LOG | head -5`` said its output folder was incomplete: there is
    none). A command sets ``args.outputs_complete`` once they are all written, before it prints its
    summary: ``compare ... | head -3`` said the folder it had just finished was incomplete."""
    return hasattr(args, "out") and not (args.out is None and getattr(args, "prints_without_out", False))


def _stdout_failed(name: str, exc: OSError, status: int = 0) -> int:
    """A standard output that cannot be written (``> /dev/full``, a full disk under ``> FILE``): one
    line on stderr, and ``status``, or 2 where it was 0 (the run wrote nothing, or not all, of what it
    was asked to print: a user-side error, as every other). What is left in stdout's buffer goes to
    /dev/null, so the interpreter's last flush does not fail again."""
    _stdout_to_devnull()
    reason = exc.strerror or str(exc) or type(exc).__name__
    try:
        print(f"lmsbench{' ' + name if name else ''}: error: cannot write the standard output: "
              f"{mid_sentence(reason)}", file=sys.stderr)
    except (OSError, ValueError):
        pass
    return status or 2


class _WatchedStdout:
    """sys.stdout while a command runs: the stream itself, except that the OSError a write or flush
    of it raises is kept (``failed``), so that the error it ends the command with is said as the
    standard output's, not as "[Errno 28] No space left on device" of nothing named."""

    def __init__(self, stream: Any) -> None:  # noqa: ANN401 - any text stream (a test's capture too)
        self.stream = stream
        self.failed: OSError | None = None

    def write(self, text: str) -> int:
        try:
            try:
                return self.stream.write(text)
            except UnicodeEncodeError:  # a name that is not UTF-8 (os.fsdecode's lone surrogates) on a stream
                # that takes only its encoding (stdout is strict under en_US.UTF-8): written with escapes,
                # as stderr writes them (a TextIOWrapper encodes the whole text before it writes any)
                encoding = getattr(self.stream, "encoding", None) or "utf-8"
                return self.stream.write(text.encode(encoding, "backslashreplace").decode(encoding))
        except BrokenPipeError:
            raise
        except OSError as exc:
            self.failed = exc
            raise

    def flush(self) -> None:
        try:
            self.stream.flush()
        except BrokenPipeError:
            raise
        except OSError as exc:
            self.failed = exc
            raise

    def __getattr__(self, name: str) -> Any:  # noqa: ANN401
        return getattr(self.stream, name)


def _stdout_to_devnull() -> None:
    """stdout's file descriptor pointed at /dev/null (its reader went away)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
    except OSError:
        return
    try:
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # no descriptor (a StringIO): nothing to point
        pass
    finally:
        os.close(devnull)  # it leaked when fileno() raised


def _interrupted(interrupt: _Interrupt) -> int:
    """Ctrl-C's one line and exit status 130 (SIGTERM's: "terminated", 143), the children killed."""
    _end_progress_bars()
    _kill_children()
    interrupt.report()
    _STOPPED.set()
    return interrupt.word_and_status[1]


def _from_interrupt(exc: BaseException) -> bool:
    """Whether a KeyboardInterrupt is among the causes of ``exc``."""
    from lms200.errors import in_chain

    return in_chain(exc, KeyboardInterrupt) is not None


def _subparsers(parser: argparse.ArgumentParser) -> argparse._SubParsersAction | None:
    return next((a for a in parser._actions if isinstance(a, argparse._SubParsersAction)), None)


def _options_before_commands(parser: argparse.ArgumentParser, argv: list[str]) -> None:
    """An unknown option before a (sub)command word is the error of the parser it was given to:
    ``lmsbench --bogus compare office`` was said by compare's parser ("lmsbench compare: error:
    unrecognized arguments: --bogus"), or, without SOURCES, as compare's missing argument. The
    parsers above the commands take no option with a value (only -h), so every word before the
    command is an option of theirs or an error."""
    for word in argv:
        sub = _subparsers(parser)
        if sub is None or word == "--":
            return
        if word.startswith("-") and len(word) > 1:
            if word.split("=", 1)[0] not in parser._option_string_actions:
                parser.error(f"unrecognized arguments: {word}")
            continue
        if word not in sub.choices:
            return  # argparse says "invalid choice", naming the known commands
        parser = sub.choices[word]


def _commands(parser: argparse.ArgumentParser) -> list[str]:
    """The names of ``parser``'s (sub)commands."""
    sub = _subparsers(parser)
    return list(sub.choices) if sub else []


def _command_parser(parser: argparse.ArgumentParser, args: argparse.Namespace) -> argparse.ArgumentParser:
    """The innermost (sub)command's parser that ``args`` came through (``lmsbench lms200 record``'s)."""
    while True:
        sub = _subparsers(parser)
        name = getattr(args, sub.dest, None) if sub else None
        if sub is None or name is None or name not in sub.choices:
            return parser
        parser = sub.choices[name]


def _show_warning(name: str, previous: Any, message: Warning | str, category: type[Warning], filename: str,
                  lineno: int, file: Any = None, line: str | None = None) -> None:
    """An ``LmsbenchWarning`` (an old spelling read, converted: a sensor file's ``resolution_deg``)
    as one line, ``lmsbench CMD: warning: ...``, above any progress bar; other warnings as Python
    shows them (``previous``). Python's own form is two lines, the second the source line that warned."""
    if not issubclass(category, LmsbenchWarning):
        previous(message, category, filename, lineno, file, line)
        return
    text = f"lmsbench {name}: warning: {_one_line(Exception(str(message)))}"
    try:
        if "tqdm" in sys.modules:
            from tqdm import tqdm

            tqdm.write(text, file=sys.stderr)
        else:
            print(text, file=sys.stderr)
    except (OSError, ValueError):  # stderr closed: nothing to say it on
        pass


def _say(line: str) -> None:
    """``line`` on stderr. Where stderr cannot be written (``2>/dev/full``, closed) the line is lost and
    the command's exit status stands: the OSError of the error's own line came out of its handler, and a
    user error exited 1 (Python's uncaught exception), not 2."""
    try:
        print(line, file=sys.stderr, flush=True)
    except (OSError, ValueError):  # nothing to say it on
        pass


def _end_progress_bars() -> None:
    """Close the progress bars an error left open, so that the error starts a line of its own."""
    if "tqdm" not in sys.modules:
        return
    from tqdm import tqdm

    for bar in list(getattr(tqdm, "_instances", ())):
        bar.leave = False  # clear the bar's line: the error replaces it
        bar.close()


def _skip_hint(exc: BaseException, args: argparse.Namespace) -> str:
    """How to read on past a malformed line or a truncated end of a log, where the command takes
    --skip-bad-lines and it was not given (a recording cut short ends mid-line; a download cut
    short is a truncated .gz)."""
    if not isinstance(exc, LogFormatError) or getattr(args, "skip_bad_lines", True):
        return ""
    from lms200.laser_geometry import MISFIT_WORDS

    if MISFIT_WORDS in exc.reason and any(
            getattr(args, flag, None) is not None for flag in ("laser_fov_deg", "laser_resolution_deg")):
        return ""  # the flags' geometry misfits every line of that beam count: skipping them skips the log
    if exc.reason.startswith("malformed"):
        return " (--skip-bad-lines skips malformed lines, each reported)"
    if exc.reason.startswith("cannot read on"):
        return " (--skip-bad-lines keeps the scans before the damage)"
    return ""


def _users_code(exc: BaseException) -> bool:
    """Whether ``exc`` is an exception raised by the user's own code that lmsbench ran (a
    ``--methods MODULE:FUNCTION`` extractor): a user error, said in one line with exit status 2 (it
    was "internal error: ... (a bug in lmsbench ...)", exit 1), its traceback under LMSBENCH_TRACEBACK=1."""
    from experiments.user_methods import UserMethodFailed

    return isinstance(exc, UserMethodFailed) and exc.raised


def _traceback_hint(exc: BaseException) -> str:
    """Where the traceback of the user's own code's exception is to be had."""
    return " (LMSBENCH_TRACEBACK=1 shows its traceback)" if _users_code(exc) and not os.environ.get("LMSBENCH_TRACEBACK") else ""


#: the errors of a write that found no room: a file's write or close raises them without its name
FULL_DISK_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG})


def _full_disk(exc: BaseException, out: object) -> str:
    """The message of a write that found no room and names no file (a full disk: a file's write or
    close raises ENOSPC without its name, and the command said only "[Errno 28] No space left on
    device"), naming where a command writes: ``out`` (its --out) and the temporary folder; else ""."""
    if not isinstance(exc, OSError) or exc.errno not in FULL_DISK_ERRNOS or exc.filename is not None:
        return ""
    reason = os.strerror(exc.errno)  # not pyarrow's "error writing bytes to file. Detail: [errno 28] ..."
    where = f"--out {out}" if out is not None else "the outputs"
    return (f"cannot write: {mid_sentence(reason)} (on the disk of {where} or of the temporary "
            f"folder {tempfile.gettempdir()})")


def _cwd_gone(exc: BaseException) -> str:
    """The message of a relative path that could not be made absolute because the current folder
    was removed after the shell entered it (os.getcwd's FileNotFoundError names no file: "error:
    [Errno 2] No such file or directory"), else ""."""
    if not isinstance(exc, FileNotFoundError) or exc.filename is not None:
        return ""
    try:
        os.getcwd()
    except FileNotFoundError:
        from experiments.options import CWD_GONE

        return CWD_GONE
    return ""


def _one_line(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.filename is not None and exc.strerror:  # not "[Errno 13] Permission denied: 'x'"
        text = f"{exc.filename}: {mid_sentence(exc.strerror)}"
        if exc.filename2 is not None:
            text += f" ({exc.filename2})"
        return text
    text = shorten_quoted(" ".join(str(exc).split())) or type(exc).__name__
    return text if len(text) <= 600 else text[:597] + "..."


if __name__ == "__main__":
    sys.exit(main())
