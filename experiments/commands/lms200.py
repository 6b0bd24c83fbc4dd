"""`lmsbench lms200 emulate|record`: a virtual LMS200 on a pseudo-terminal or TCP port, and a
recorder that logs a real (or virtual) LMS200 to a CARMEN log or a ROS bag."""

from __future__ import annotations

import argparse
import math
import signal
import sys
import time
from pathlib import Path
from typing import Iterable, Iterator

from lms200 import LmsbenchError, Record
from lms200.carmen import write_carmen
from lms200.driver import LMS200, MAX_TIMEOUT_S
from lms200.protocol import BAUD_MODES
from lms200.timing import MIN_DURATION_S
from lms200.virtual import MAX_TIME_SCALE, MIN_TIME_SCALE

from experiments.lms200_sources import log_scans, simulator_scans
from experiments.logargs import add_log_options, given_log_flags, read_log_options
from experiments.options import (WORLDS, PORT, SEED, InputError, check_link, check_log, check_out_file, count, mid_sentence, number, plain,
                                 path_arg, text, warnings_after_checks, world_name)


#: emulate / record --duration: at least lms200.timing.MIN_DURATION_S (1e-300 stopped at once: "0 scans sent" /
#: "recorded no scan", exit 0). Wall-clock seconds in both: emulate's --time-scale does not scale it (at 0.01 a
#: 0.1 s run holds hundreds of scans' line time; at 100 none, but serving stops there as asked). A recording
#: whose duration ends before its first scan (a telegram takes 0.19 s at 38400 baud) is an error (_no_scan_within).
STOP_AFTER = number(MIN_DURATION_S, unit="s")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("lms200", help="virtual LMS200 (emulate) and serial recorder (record)")
    # not required=True: argparse then said "the following arguments are required: ACTION"; without
    # an action, cli.main says "a command is required: emulate, record", as for `lmsbench` alone
    cmds = p.add_subparsers(dest="lms200_command", metavar="ACTION")

    e = cmds.add_parser("emulate", help="serve a virtual LMS200 on a pseudo-terminal (or TCP); prints its path / URL")
    e.add_argument("--world", type=world_name, help="simulator world to scan: " + WORLDS + " (default office)")
    e.add_argument("--seed", type=SEED, help="seed of the world and the sensor noise (default 0)")
    e.add_argument("--log", type=path_arg, help="replay this log (CARMEN, bag or lmsbench simulate folder) instead of the simulator, in a loop")
    e.add_argument("--tcp", type=PORT, metavar="PORT", help="serve on socket://127.0.0.1:PORT (or --host's address) instead of a pty (0 = any free port)")
    e.add_argument("--rfc2217", action="store_true", help="with --tcp: speak RFC 2217 (rfc2217://HOST:PORT), so the host sets the baud")
    e.add_argument("--host", type=text("an address, e.g. 127.0.0.1, 0.0.0.0 or ::1"), help="address to listen on with --tcp (default 127.0.0.1; ::1 for IPv6, its URL socket://[::1]:PORT)")
    e.add_argument("--units", choices=("cm", "mm"), default="cm", help="power-on unit mode (default cm, as the LMS200 ships)")
    e.add_argument("--time-scale", type=number(MIN_TIME_SCALE, MAX_TIME_SCALE), default=1.0,
                   help=f"multiplies every byte time and device delay (default 1, real time; 0.01 = 100x faster; "
                        f"{MIN_TIME_SCALE:g} to {MAX_TIME_SCALE:g}: faster than a millionth changes nothing a host sees)")
    e.add_argument("--duration", type=STOP_AFTER, help=f"stop after this many seconds of wall-clock time, whatever --time-scale "
                                                      f"(at least {MIN_DURATION_S:g}; default: until Ctrl-C)")
    add_log_options(e)  # with --log
    e.set_defaults(func=run_emulate)

    r = cmds.add_parser("record", help="record an LMS200 to a CARMEN log (.clf, .log, .gz) or a ROS bag (.bag)")
    r.add_argument("--port", required=True, type=text("a serial device or a pyserial URL"), help="serial device or pyserial URL (socket://host:port, rfc2217://, loop://)")
    r.add_argument("--out", type=path_arg, required=True, help="output: FILE.clf / .log / .gz (CARMEN) or FILE.bag (ROS 1)")
    r.add_argument("--baud", type=plain(integer=True), default=38400, choices=sorted(BAUD_MODES), help="line speed to switch to (default 38400)")
    r.add_argument("--units", choices=("mm", "cm"), default="mm", help="range unit: mm (8.18 m) or cm (81.8 m) (default mm)")
    r.add_argument("--fov-deg", "--fov", dest="fov_deg", type=plain(integer=True), default=180, choices=(180, 100),
                   help="field of view, deg (default 180; --fov is the old spelling)")
    r.add_argument("--resolution-deg", "--resolution", dest="resolution_deg", type=plain(), default=0.5,
                   choices=(1.0, 0.5, 0.25), help="angular resolution, deg (default 0.5; --resolution is the old spelling)")
    r.add_argument("--max-scans", type=count(1), help="stop after this many scans")
    r.add_argument("--duration", type=STOP_AFTER, help=f"stop after this many seconds (at least {MIN_DURATION_S:g}; one that ends before the first scan, "
                                                      "a 361-beam telegram taking 0.19 s at 38400 baud, is an error)")
    r.add_argument("--timeout", type=number(0.0, MAX_TIMEOUT_S, lo_open=True, unit="s"), default=0.5,
                   help=f"seconds to wait for a reply, on top of the line time (default 0.5, at most {MAX_TIMEOUT_S:g})")
    r.add_argument("--mode-timeout", type=number(0.0, MAX_TIMEOUT_S, lo_open=True, unit="s"), default=3.5,
                   help="seconds to wait for the reply to a mode change (start or stop of continuous output, "
                        f"installation mode) and for the first scan after it (default 3.5: the LMS200 takes up to 3 s; "
                        f"at most {MAX_TIMEOUT_S:g})")
    r.set_defaults(func=run_record)


# -- emulate ------------------------------------------------------------------------------------
def run_emulate(args: argparse.Namespace) -> int:
    from lms200.adapters import PtyAdapter, TcpServer
    from lms200.virtual import VirtualLMS200

    if args.rfc2217 and args.tcp is None:
        raise InputError("--rfc2217 needs --tcp PORT")
    if args.host is not None and args.tcp is None:  # it was ignored: a pseudo-terminal has no address
        raise InputError("--host needs --tcp PORT (without it the device is a pseudo-terminal)")
    simulated = [flag for flag, value in (("--world", args.world), ("--seed", args.seed)) if value is not None]
    if args.log and simulated:  # they were ignored: the log's scans were replayed
        raise InputError(f"{', '.join(simulated)} set the simulated scans; --log replays the log's own")
    unread = given_log_flags(args)
    if not args.log and unread:  # they were ignored: the simulator's scans were served
        raise InputError(f"{', '.join(unread)} {'say' if len(unread) > 1 else 'says'} how to read the --log to replay; "
                         "without --log the device serves simulated scans (give --log LOG, or leave them out)")
    args.world, args.seed = args.world or "office", 0 if args.seed is None else args.seed
    args.host = args.host or "127.0.0.1"
    # the log's warnings (ranges in millimetres) are said once it is read whole and the port is open: a refused
    # run (a malformed line after scan 50, --tcp PORT in use) is its error alone (it said the warning, then the error)
    with warnings_after_checks():
        if args.log:
            args.log = check_log(args.log)  # a simulate folder: its scans.clf
            scans = log_scans(args.log, read_options=read_log_options(args))
            what = f"scans of {args.log} in a loop"
        else:
            scans = simulator_scans(args.world, args.seed)
            what = f"simulated scans of world {args.world} (seed {args.seed}) along its route graph"
        device = VirtualLMS200(scans, time_scale=args.time_scale, units=args.units)
        try:
            adapter = TcpServer(device, args.host, args.tcp, rfc2217=args.rfc2217) if args.tcp is not None else PtyAdapter(device)
        except OSError as exc:  # said "[Errno 98] Address already in use (while attempting to bind on address (...))"
            if args.tcp is None:
                raise
            import errno
            import socket

            why = str(exc.strerror or exc).split(" (while attempting", 1)[0]
            if isinstance(exc, socket.gaierror) or (exc.errno or 0) < 0 or exc.errno == errno.EADDRNOTAVAIL:  # < 0: getaddrinfo
                raise InputError(f"--host {args.host}: cannot listen there ({why}); give an address of this machine "
                                 "(127.0.0.1, or 0.0.0.0 for all of them)") from None
            bare = args.host.strip("[]")
            raise InputError(f"--tcp {args.tcp}: cannot listen on {f'[{bare}]' if ':' in bare else bare}:{args.tcp} ({why}); "
                             "give a free port (--tcp 0 picks one)") from None
    where = adapter.url if args.tcp is not None else adapter.path
    print(where, flush=True)
    print(f"virtual LMS200 at {where}: {what}, 9600 baud at power-on, "
          f"time scale {args.time_scale:g}; Ctrl-C stops", file=sys.stderr, flush=True)
    stop = {"now": False}
    previous = {sig: signal.signal(sig, lambda *_: stop.update(now=True)) for sig in (signal.SIGINT, signal.SIGTERM)}
    start = time.monotonic()
    try:
        # adapter.error: its thread stopped (the log moved or changed while replayed: each pass reads it again);
        # the device had gone silent and the error was said only when emulate was stopped
        while not stop["now"] and adapter.error is None and (args.duration is None or time.monotonic() - start < args.duration):
            time.sleep(0.05)
    finally:
        adapter.close()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    busy = f", {device.requests_dropped} dropped unanswered while busy" if device.requests_dropped else ""
    print(f"virtual LMS200 stopped: {device.scans_sent} scans sent, {device.requests} requests{busy}", file=sys.stderr)
    return 0


# -- record -------------------------------------------------------------------------------------
class _Progress:
    """One status line on stderr, redrawn at most 4 times a second on a terminal; to a file or a
    pipe, where the redraws' carriage returns were clutter (a line every 0.25 s of a recording),
    one line every HEARTBEAT_S, as sim2real and calibrate do there, and the final count."""

    HEARTBEAT_S = 4.0  # s between lines when stderr is no terminal

    def __init__(self, dev: LMS200, tty: bool | None = None) -> None:
        self.dev, self.start, self.shown, self.count = dev, time.monotonic(), 0.0, 0
        self.tty = sys.stderr.isatty() if tty is None else tty
        if not self.tty:  # the first line after HEARTBEAT_S, not at the first scan
            self.shown = self.start

    def update(self, final: bool = False) -> None:
        now = time.monotonic()
        if not final and now - self.shown < (0.25 if self.tty else self.HEARTBEAT_S):
            return
        self.shown = now
        elapsed = max(now - self.start, 1e-9)
        stats = self.dev.stats
        text = (f"{self.count} scans  {self.count / elapsed:5.1f} scans/s  {stats.dropped_frames} dropped frames  "
                f"{elapsed:6.1f} s")
        if self.tty:
            print(f"\r{text}", end="\n" if final else "", file=sys.stderr, flush=True)
        else:
            print(text, file=sys.stderr, flush=True)


#: s: while the device sends nothing, the records give a None this often, so that the bag writer
#: writes out the scans it holds on time (``write_bag(flush_s=...)``), not at the next scan
IDLE_TICK_S = 0.1


def _records(dev: LMS200, progress: _Progress, stop: dict, max_scans: int | None,
             duration: float | None) -> Iterator[Record | None]:
    """Records from the device until Ctrl-C, the scan limit or the duration, and a None every
    IDLE_TICK_S while none comes (see ``write_bag``). A device error (a
    timeout, a lost connection) ends the records as a stop does, so the file is closed with every
    scan before it (a bag that an exception leaves open is not indexed, and unreadable), and is
    kept in ``stop["error"]`` for the caller to report."""
    def done() -> bool:
        return stop["now"] or (duration is not None and time.monotonic() - progress.start >= duration)

    if max_scans is not None and max_scans <= 0:
        return
    try:
        for scan in dev.scans(stop=done, idle_s=IDLE_TICK_S):
            if scan is None:
                yield None
                progress.update()
                continue
            progress.count += 1
            yield Record(scan)
            progress.update()
            if max_scans is not None and progress.count >= max_scans:
                return
    except LmsbenchError as exc:
        stop["error"] = exc


def _write(out: Path, records: Iterable[Record | None]) -> int:
    if out.suffix == ".bag":
        from lms200.bag import RECORD_FLUSH_S, write_bag

        # a killed recording keeps all but its last second, its first scan and the scans before a stall too
        return write_bag(out, records, flush_s=RECORD_FLUSH_S)
    return write_carmen(out, (rec for rec in records if rec is not None), flush=True)  # every line flushed


class _Counted:
    """The records handed to a writer, counted, so that a writer that fails says how many it had
    written: it takes a record only after the one before is in the file (CARMEN flushed, the bag
    closed with its index on the error), so all but the last one taken, or all once it asked for
    more and there were none."""

    def __init__(self, records: Iterable[Record | None]) -> None:
        self.records, self.taken, self.done = records, 0, False

    def __iter__(self) -> Iterator[Record | None]:
        for rec in self.records:
            self.taken += rec is not None  # a None is a tick, no record
            yield rec
        self.done = True

    @property
    def written(self) -> int:
        return self.taken if self.done else max(self.taken - 1, 0)


RECORD_SUFFIXES = (".clf", ".log", ".gz", ".bag")


def _drop_empty(out: Path) -> None:
    """Remove a recording of no scan (the file run_record made: --out did not exist): a log of
    headers alone, which no command reads and which a second run refused to write over."""
    try:
        if out.is_dir():
            import shutil

            shutil.rmtree(out)
        else:
            out.unlink(missing_ok=True)
    except OSError:
        pass  # the error being reported is the one to see


def _record_failed(out: Path, written: int, error: BaseException | None, closing: BaseException | None = None) -> str:
    """The one line of a recording that ended on a device error (``error``; ``closing``: the error
    of returning the device to on-request mode, which came after it, if any), saying what was kept.
    A recording of no scan is removed: "the 0 scans before it are saved in OUT" left a file of
    headers alone, and the next run into OUT was refused ("exists")."""
    what = "; ".join(str(e) for e in (error, closing) if e is not None)
    if written == 0:
        _drop_empty(out)
        return f"{what}; no scan was recorded, so {out} was not written"
    return f"{what}; the {written} scans before it are saved in {out}"


def _no_scan_within(duration: float, baud: int, variant: tuple[int, int], out: Path) -> str:
    """The one line of a recording whose --duration ran out before its first scan: what one scan's
    telegram takes at the baud used, and the duration that holds one (the stream may start mid-telegram:
    the first whole one ends within two telegrams' time)."""
    from lms200.protocol import scan_telegram_seconds

    fov, res_cdeg = variant
    beams = round(fov * 100 / res_cdeg) + 1
    telegram = scan_telegram_seconds(beams, baud)
    need = math.ceil(2 * telegram * 10) / 10
    if duration >= need:  # time enough for a scan: the device sent none
        return (f"--duration {duration:g} s ended with no scan from the device ({out} not written), though one "
                f"{beams}-beam scan telegram takes {telegram:.2f} s at {baud} baud")
    return (f"--duration {duration:g} s ended before the first scan came ({out} not written): one {beams}-beam scan "
            f"telegram takes {telegram:.2f} s at {baud} baud, and the first whole one can take twice that; give "
            f"--duration {need:g} or more (or a higher --baud)")


class _StoppedOpening(KeyboardInterrupt):
    """Ctrl-C or SIGTERM while ``lms200 record`` opens and sets up the device, before any scan."""


def run_record(args: argparse.Namespace) -> int:
    if args.out.is_dir():  # was "unknown kind '(no suffix)'"
        raise InputError(f"--out {args.out} is a folder; give a file name (.clf, .log, .gz or .bag)")
    if args.out.suffix not in RECORD_SUFFIXES:
        raise InputError(f"--out {args.out}: unknown kind {args.out.suffix or '(no suffix)'!r}; "
                         f"write a CARMEN log (.clf, .log, .gz) or a ROS 1 bag (.bag)")
    check_link(args.out)  # a link to nothing was said to exist, as a file a recording is not written over
    if args.out.exists() or args.out.is_symlink():  # a CARMEN recording replaced an earlier one silently
        raise InputError(f"--out {args.out} exists; a recording is not written over a file (give a new name)")
    check_out_file(args.out)
    stop: dict = {"now": False}
    written, set_up = 0, False

    def on_stop(*_: object) -> None:
        stop["now"] = True
        if not set_up:  # the driver's requests while it opens the device do not look at `stop`
            raise _StoppedOpening

    # Ctrl-C and SIGTERM (a batch system's limit) end the recording as asked: the file closed and
    # readable (SIGTERM went to the CLI's interrupt: a bag cut in its index, "Bag is not indexed");
    # while the device is still being opened (the baud probe: up to 8 requests of --timeout each) they
    # end the opening at once (they were held until it gave up: "no LMS200 answered", 40 s at --timeout 5)
    status = ""
    previous = {sig: signal.signal(sig, on_stop) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        # a status the next line overwrites, on a terminal only (like the progress bars), so that
        # a port that cannot be opened leaves the error as stderr's one line
        status = f"opening {args.port} ..." if sys.stderr.isatty() else ""
        print(status, end="\r" if status else "", file=sys.stderr, flush=True)
        with LMS200(args.port, baud=args.baud, fov_deg=args.fov_deg, resolution_deg=args.resolution_deg,
                    units=args.units, timeout=args.timeout, mode_timeout=args.mode_timeout) as dev:
            set_up = True
            opened = (f"{dev.type_string.strip()} at {dev.baud} baud, {args.units}; recording to {args.out} "
                      f"(Ctrl-C stops)")
            print(f"{opened:<{len(status)}}", file=sys.stderr, flush=True)
            line = (dev.baud, dev.variant)
            progress = _Progress(dev)
            counted = _Counted(_records(dev, progress, stop, args.max_scans, args.duration))
            try:
                written = _write(args.out, counted)
            except LmsbenchError as exc:  # the writer refused a scan (units changed): the ones before it are kept
                # (was caught below as the port's closing error with 0 written: the file of 3 flushed
                # scans was deleted, "no scan was recorded"; found by the session's review)
                written, stop["error"] = counted.written, exc
            except OSError as exc:  # the file could not be written on (a full disk): the scans before it are
                # kept, said as such (it said "[Errno 28] No space left on device" and left a bag of 0 bytes)
                reason = exc.strerror or str(exc)
                written = counted.written
                stop["error"] = LmsbenchError(f"cannot write {args.out}: {mid_sentence(reason)}")
            finally:
                progress.update(final=True)
            stats = dev.stats
    except _StoppedOpening:  # the port is closed (the driver closes it when its opening fails)
        print(f"{' ' * len(status)}\r" if status else "", end="", file=sys.stderr, flush=True)
        print(f"stopped while opening {args.port}: recorded no scan; {args.out} not written")
        return 0
    except LmsbenchError as exc:  # the device did not return to on-request mode as the port closed
        if not set_up:  # the port did not open, or the device was not set up: no file was made, said as it was
            raise
        raise LmsbenchError(_record_failed(args.out, written, stop.get("error"), exc)) from exc
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    if stop.get("error") is not None:
        raise LmsbenchError(_record_failed(args.out, written, stop["error"]))
    if written == 0:
        _drop_empty(args.out)
        if args.duration is not None and not stop["now"]:  # --duration ran out first: it said "recorded no scan", exit 0
            raise LmsbenchError(_no_scan_within(args.duration, *line, args.out))
        print(f"recorded no scan; {args.out} not written; device back in on-request mode at 9600 baud")
        return 0
    flagged = f", {stats.flagged} of them flagged by the device's status byte" if stats.flagged else ""
    print(f"recorded {written} scans to {args.out} ({stats.dropped_frames} frames dropped, "
          f"{stats.decode_errors} undecodable{flagged}); device back in on-request mode at 9600 baud")
    return 0
