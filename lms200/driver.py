"""Serial driver for a SICK LMS200 (a real unit or :mod:`lms200.virtual`) over pyserial.

::

    with LMS200("/dev/ttyUSB0", baud=38400) as dev:   # or socket://host:port, rfc2217://, loop://
        for scan in dev.scans():                      # lms200.Scan, stamped with host time (s)
            ...

Opening talks at the power-on 9600 baud (probing 19200, 38400 and 500000 when nothing answers),
stops continuous output, sets the variant, the units (through the configuration telegrams, only
when they differ) and the baud; ``scans()`` starts continuous output (0x20 0x24). ``close()``
returns the device to on-request mode and 9600 baud. Every request is retried (the device can
miss one during a mirror turn); failures raise :class:`LmsTimeoutError`, :class:`LmsNakError`,
:class:`LmsModeRefusedError` or :class:`LmsProtocolError`, naming what was asked and what came back;
a port or link that fails mid-use raises :class:`LmsLinkError` (pyserial's own exceptions do not escape).
"""

from __future__ import annotations

import math
import numbers
import os
import time
from collections import deque
from dataclasses import dataclass
from typing import Callable, Iterator, overload

import serial

from .codes import Units, check_units
from .errors import InputError, LmsDeviceError, LmsLinkError, LmsModeRefusedError, LmsNakError, LmsProtocolError, LmsStatusError, LmsTimeoutError
from .finite import check_number, float_of, shown
from .framing import Frame, FrameParser
from .protocol import (
    ACK,
    BAUD_MODES,
    CMD_MEASURE,
    CMD_SET_CONFIG,
    MAX_LEN,
    MODE_CONTINUOUS,
    MODE_INSTALLATION,
    MODE_ON_REQUEST,
    NAK,
    OVERHEAD_BYTES,
    PASSWORD,
    POWER_ON_BAUD,
    REPLY_BAD_COMMAND,
    REPLY_FLAG,
    REPLY_MEASURE,
    VARIANTS,
    baud_request,
    build_frame,
    decode_scan,
    frame_seconds,
    get_config_request,
    mode_request,
    reply_code,
    set_config_request,
    type_request,
    units_of_config,
    variant_request,
    with_units,
)
from .scan import Scan

PROBE_BAUDS = (9600, 19200, 38400, 500000)
MAX_TIMEOUT_S = 60.0  # longest wait for a reply (s): a device takes 3 s at most (mode changes); 1e9 waited for ever
MAX_STALL_TIMEOUT_S = 3600.0  # longest wait for the next scan in continuous mode (s): nan waited for ever
_READ_POLL_S = 0.01  # longest blocking read (s)
MIRROR_PERIOD_S = 1.0 / 75.0  # one mirror turn: a scan every 13.3 ms at 1 deg (2 turns at 0.5, 4 at 0.25)
_SHORT_REPLY_BYTES = 64  # every reply but 0xB0 fits (the 0xF7 configuration reply is 41 bytes)
MAX_ADDRESS = 0x7F  # the reply address is device address + 0x80, one byte
_READ_CHUNK = 4096  # bytes asked for when the port cannot tell how many are waiting
_DRAIN_READS = 16  # more reads after one while bytes are still waiting (a backlog read as one)
_READS_KEPT = 256  # reads remembered to stamp frames (a frame held behind a false start may span many)
_FALSE_START_GAP_S = 0.1  # quiet line after which a false start hiding a good frame is dropped


def _variant_names() -> str:
    return ", ".join(f"{fov} deg at {res / 100:g} deg" for fov, res in VARIANTS)


def _check_arguments(baud: object, fov_deg: object, resolution_deg: object, units: object, address: object,
                     timeout: object, mode_timeout: object, retries: object) -> tuple[int, int]:
    """The constructor's arguments, checked before the port is opened: an :class:`InputError`
    naming the argument and what it may be (a str resolution was a TypeError about ``__round__``,
    fov 180 at 0.25 deg a plain ValueError the command line called a bug). Returns the variant
    as (fov deg, resolution 1/100 deg)."""

    def real(name: str, value: object) -> float:
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise InputError(f"{name}: must be a number, got {type(value).__name__} {shown(value)}")
        return float_of(value, name, InputError)  # 10**400: OverflowError from float()

    def integer(name: str, value: object) -> int:
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            raise InputError(f"{name}: must be an integer, got {type(value).__name__} {shown(value)}")
        return int(value)

    # An int first: a list was a TypeError (unhashable), 9600.0 passed
    if isinstance(baud, bool) or not isinstance(baud, numbers.Integral) or int(baud) not in BAUD_MODES:
        raise InputError(f"baud: the LMS200 supports {sorted(BAUD_MODES)}, got {shown(baud)}")
    fov, res = real("fov_deg", fov_deg), real("resolution_deg", resolution_deg)
    ok = math.isfinite(fov) and math.isfinite(res * 100)  # 1e307 * 100 is inf: round() overflowed
    variant = (int(fov), int(round(res * 100))) if ok else None
    if variant not in VARIANTS or fov != variant[0] or not math.isclose(res * 100, variant[1], abs_tol=1e-6):
        raise InputError(f"fov_deg, resolution_deg: ({shown(fov_deg)} deg, {shown(resolution_deg)} deg) is not an LMS200 "
                         f"variant; the variants are {_variant_names()} (0.25 deg only with 100 deg)")
    check_units(units)  # an array was numpy's ValueError (ambiguous truth)
    if not 0 <= integer("address", address) <= MAX_ADDRESS:
        raise InputError(f"address: must be in 0..{MAX_ADDRESS} (replies come from address + 0x80), got {shown(address)}")
    if integer("retries", retries) < 1:
        raise InputError(f"retries: must be >= 1, got {shown(retries)}")
    for name, value in (("timeout", timeout), ("mode_timeout", mode_timeout)):
        if not 0 < real(name, value) <= MAX_TIMEOUT_S:  # also nan
            raise InputError(f"{name}: must be in (0, {MAX_TIMEOUT_S:g}] s, got {shown(value)}")
    return variant


@dataclass
class DriverStats:
    """Counters of one connection: scans yielded, frames dropped by the parser, undecodable scans
    (``flagged``: those of them the device's STATUS byte marked as not to be used), attempts resent (``retries``) and attempts that waited out their whole wait without a reply or
    a NAK (``timeouts``: a NAK is resent at once, without one)."""

    scans: int
    dropped_frames: int
    skipped_bytes: int
    decode_errors: int
    retries: int
    timeouts: int = 0
    flagged: int = 0  # scans dropped for their STATUS byte (an error, implausible values: protocol.status_problem)



def _bracketed_ipv6(url: str) -> str | None:
    """``url`` with its host in brackets when it is a ``socket://`` or ``rfc2217://`` URL whose
    host is a bare IPv6 address (``socket://::1:2111`` -> ``socket://[::1]:2111``), else None."""
    scheme, sep, rest = url.partition("://")
    if not sep or scheme.lower() not in ("socket", "rfc2217"):
        return None
    end = min((i for i in (rest.find("/"), rest.find("?")) if i >= 0), default=len(rest))
    netloc, tail = rest[:end], rest[end:]  # socket://HOST:PORT?logging=debug
    if netloc.startswith("[") or netloc.count(":") < 2:
        return None
    host, _, port = netloc.rpartition(":")
    return f"{scheme}://[{host}]:{port}{tail}"

def _url_port_problem(url: str) -> str | None:
    """What is wrong with the port of a ``socket://`` or ``rfc2217://`` URL (none, not a number,
    outside 1..65535), or None: pyserial's own messages for them were "'debug|info|warning|error'"
    and "'<=' not supported between instances of 'int' and 'NoneType'"."""
    scheme, sep, rest = url.partition("://")
    if not sep or scheme.lower() not in ("socket", "rfc2217"):
        return None
    end = min((i for i in (rest.find("/"), rest.find("?")) if i >= 0), default=len(rest))
    netloc = rest[:end]
    host, colon, port = netloc.rpartition(":") if not netloc.endswith("]") else (netloc, "", "")
    if not colon:  # (an empty host, socket://:2111, is this machine's, as pyserial takes it)
        return f"a {scheme.lower()}:// URL needs a port after its host, {scheme.lower()}://HOST:PORT"
    if not (port.isascii() and port.isdigit() and 1 <= int(port) <= 65535):
        return f"its port must be a number from 1 to 65535, got {port!r}"
    return None


class LMS200:
    """A connection to one LMS200.

    Args:
        port_or_url: serial device (``/dev/ttyUSB0``) or pyserial URL (``socket://``, ``rfc2217://``,
            ``loop://``).
        baud: line speed to switch to (9600, 19200, 38400 or 500000).
        fov_deg, resolution_deg: variant (180 or 100 deg; 1, 0.5 or 0.25 deg, 0.25 only with 100).
        units: 'mm' (8.18 m, 1 mm) or 'cm' (81.8 m, 1 cm).
        address: device address (0 for a single unit).
        timeout: seconds to wait for the ACK and reply of a request, on top of the line time of
            the reply (and of a scan telegram in flight while streaming); the listing promises
            60 ms, USB adapters and TCP need more. A frame cut off by a line gone quiet is given
            up after ``timeout`` plus the line time of the longest telegram (818 bytes).
        mode_timeout: the same for mode changes and configuration writes (up to 3 s).
        retries: attempts per request.
        probe: when 9600 baud gets no answer, try 19200, 38400 and 500000.
        password: installation-mode password (needed to change the units).

    Raises:
        LmsDeviceError: the port cannot be opened, or a subclass when the device does not cooperate.
    """

    def __init__(
        self,
        port_or_url: str,
        baud: int = 38400,
        *,
        fov_deg: int = 180,
        resolution_deg: float = 0.5,
        units: Units = "mm",
        address: int = 0,
        timeout: float = 0.5,
        mode_timeout: float = 3.5,
        retries: int = 3,
        probe: bool = True,
        password: bytes = PASSWORD,
    ) -> None:
        if isinstance(port_or_url, os.PathLike):
            port_or_url = os.fspath(port_or_url)  # type: ignore[assignment]
        if not isinstance(port_or_url, str) or not port_or_url:  # None was an AttributeError ('partition')
            raise InputError(f"port_or_url: must be a serial device (/dev/ttyUSB0) or a pyserial URL "
                             f"(socket://HOST:PORT, rfc2217://HOST:PORT), got {shown(port_or_url)}")
        self.variant = _check_arguments(baud, fov_deg, resolution_deg, units, address, timeout, mode_timeout, retries)
        baud = int(baud)  # numpy's int64 too
        self.port = port_or_url
        self.target_baud = baud
        self.units: Units = units
        self.address = address
        self.timeout = timeout
        self.mode_timeout = mode_timeout
        self.retries = retries
        self.password = password
        self.type_string = ""
        self.baud = POWER_ON_BAUD
        self.streaming = False
        self.parser = FrameParser(REPLY_FLAG | address)
        self.parser.awaiting_reply = False  # True while a request waits for its handshake (see _request)
        self._scans = 0
        self._decode_errors = 0
        self._flagged = 0
        self._retries = 0
        self._timeouts = 0
        self._last_rx = time.monotonic()
        self._unanswered = 0  # attempts written whose answer (NAK, or the reply) was not read: see _no_answer_due
        self._last_write = -math.inf
        self._backlog: list = []  # events read past a reply, handed out by the next _pump
        # (stream offset after a read, host time when the read returned), the newest reads
        self._reads: deque[tuple[int, float]] = deque(maxlen=_READS_KEPT)
        self._last_end = -math.inf  # when the last scan telegram stamped ended (host time)
        # Host time = time.monotonic() + this offset, taken once: a wall-clock step (NTP) while
        # a backlog waits does not bend the stamps of the scans in it.
        self._clock_offset = time.time() - time.monotonic()
        self._doing = "opening the port"  # for the message of a link that fails mid-use
        self._lost = False  # the port failed: close() only closes it
        bracketed = _bracketed_ipv6(port_or_url)
        if bracketed is not None:  # pyserial said "Could not open port ...: 'debug|info|warning|error'"
            raise LmsDeviceError(f"cannot open {port_or_url}: an IPv6 address in a URL goes in brackets: {bracketed}")
        problem = _url_port_problem(port_or_url)
        if problem is not None:
            raise LmsDeviceError(f"cannot open {port_or_url}: {problem}")
        try:
            self._ser = serial.serial_for_url(port_or_url, baudrate=POWER_ON_BAUD, timeout=_READ_POLL_S)
        except (serial.SerialException, ValueError, OSError) as exc:
            raise LmsDeviceError(f"cannot open {port_or_url}: {_open_failure(exc)}") from None
        try:
            self._connect(probe)
            self._set_mode(MODE_ON_REQUEST, "stop continuous output (0x20 0x25)")
            self._set_variant()
            self._set_units()
            self._switch_baud(baud)
        except BaseException:
            try:
                self._ser.close()
            except (serial.SerialException, OSError):
                pass  # the error that ended the opening is the one to report
            raise

    # -- context manager -----------------------------------------------------------------------
    def __enter__(self) -> "LMS200":
        return self

    def __exit__(self, exc_type: object, exc: object, tb: object) -> None:
        try:
            self.close()
        except LmsDeviceError:
            if exc_type is None:
                raise

    @property
    def stats(self) -> DriverStats:
        p = self.parser.stats
        return DriverStats(self._scans, p.dropped_frames, p.skipped_bytes, self._decode_errors, self._retries, self._timeouts,
                           self._flagged)

    # -- low level -----------------------------------------------------------------------------
    def _idle_gap(self, hides_frame: bool) -> float:
        """How long the line must be quiet before held-back bytes are given up (``parser.idle()``).

        The LMS200 sends a telegram without gaps (byte after byte at the baud; the listing's own
        limit between the bytes of a telegram is 6 ms), so a pause inside a frame is the link's: a
        USB adapter's latency timer (16 ms) or a TCP retransmission (200 ms and more). A partial
        frame that is still consistent is therefore kept until the line has been quiet for as
        long as a reply may take (``timeout`` plus the line time of the longest telegram: 0.71 s
        at 38400 baud with the default timeout); one proven false by a good frame complete behind
        it is dropped after 0.1 s (or the line time of 20 bytes, if longer)."""
        if hides_frame:
            return max(_FALSE_START_GAP_S, frame_seconds(20, self.baud))
        return self.timeout + frame_seconds(MAX_LEN + OVERHEAD_BYTES, self.baud)

    def _no_answer_due(self) -> bool:
        """Whether, in on-request mode, no telegram of the device can be on its way: every request
        written was answered (a NAK, or its reply), none was written for longer than the longest
        answer may take (``mode_timeout`` plus the line time of the longest telegram), or nothing
        has arrived for 0.1 s (a device sends a telegram without gaps; as ``_idle_gap(True)``). The
        device sends nothing unasked, so bytes held back then are garbage, and the first byte of
        the answer to the next request is its handshake."""
        now = time.monotonic()
        longest = self.mode_timeout + frame_seconds(MAX_LEN + OVERHEAD_BYTES, self.baud)
        return self._unanswered == 0 or now - self._last_write > longest or now - self._last_rx > self._idle_gap(True)

    def _link_lost(self, exc: BaseException) -> LmsLinkError:
        """The error for a port that failed mid-use (pyserial's SerialException / OSError escaped
        before): it names the port, the baud and what was being done. The link is marked lost so
        that :meth:`close` only closes the port."""
        self._lost = True
        return LmsLinkError(f"the link to {self.port} at {self.baud} baud failed while {self._doing}: "
                            f"{exc or type(exc).__name__}")

    def _pump(self) -> list:
        """Events left over from the last read, else read what has arrived (blocking at most
        10 ms) and parse it into events."""
        if self._backlog:
            events, self._backlog = self._backlog, []
            return events
        try:
            waiting = self._ser.in_waiting  # exact on serial ports; only 0 / 1 on socket:// and loop://
            data = self._ser.read(waiting if waiting > 1 else _READ_CHUNK)
            # A backlog larger than one read (a pty hands out 4095 bytes at a time) is read whole,
            # so that its telegrams are stamped together (see _stamps); a few reads at most.
            piece = data
            for _ in range(_DRAIN_READS):
                if not piece:
                    break
                waiting = self._ser.in_waiting
                if not waiting and len(piece) >= _READ_CHUNK - 1:  # a full read: the kernel may be
                    time.sleep(0.002)  # moving the rest of the backlog into the port's buffer
                    waiting = self._ser.in_waiting
                if not waiting:
                    break
                piece = self._ser.read(waiting if waiting > 1 else _READ_CHUNK)
                data += piece
        except (serial.SerialException, OSError) as exc:
            raise self._link_lost(exc) from None
        now = time.monotonic()
        if data:
            self._last_rx = now
            self._reads.append((self.parser.received + len(data), now + self._clock_offset))
            return self.parser.feed(data)
        if self.parser.pending:
            quiet = now - self._last_rx
            if quiet > self._idle_gap(False) or (quiet > self._idle_gap(True) and self.parser.hides_frame()):
                return self.parser.idle()
        return []

    def _stamps(self, frames: list[Frame]) -> list[float]:
        """Host time (``time.time()`` at open plus ``time.monotonic()`` since) when each of
        ``frames`` (0xB0 telegrams in stream order) began to arrive.

        A frame's last byte arrived before the read that brought it returned, earlier by at least
        the line time of the bytes after it in that read; and telegrams in continuous mode are at
        least one line time and one scan period apart (one telegram per scan: 26.7 ms at 0.5 deg).
        Each frame's end is the latest time that fits those bounds, and no earlier than the
        previous frame's end plus that spacing; its stamp is that end less its own line time. So
        scans read together (a backlog left while the consumer was busy) keep their spacing
        instead of sharing the time they were processed at. What the host cannot see is how long
        a backlog waited in the port's buffer: its newest scans are stamped by the read.

        Telegrams can come faster than that spacing (a virtual device at ``time_scale`` < 1): where
        it would put a frame past its read, the frame is put instead at an equal share of the time
        between the previous frame's end and its read, one share per frame still to place, so
        stamps stay strictly increasing and never later than their read (every frame of such a
        read was pinned to the read's time: 359 of 399 stamp differences were exactly 0)."""
        byte_s = frame_seconds(1, self.baud)
        period = MIRROR_PERIOD_S * {100: 1, 50: 2, 25: 4}[self.variant[1]]
        ends, caps = [], []
        for frame in frames:
            found = None
            for end, t in reversed(self._reads):  # the oldest read that reaches the frame's end
                if end < frame.end:
                    break
                found = (end, t)
            end, t = found if found is not None else (frame.end, time.monotonic() + self._clock_offset)
            ends.append(t - (end - frame.end) * byte_s)
            caps.append(t)
        gaps = [max(len(f) * byte_s, period) for f in frames]
        for i in range(len(frames) - 2, -1, -1):  # the frames after one took their time to arrive
            ends[i] = min(ends[i], ends[i + 1] - gaps[i + 1])
        for i in range(len(frames)):
            last = self._last_end
            at = max(ends[i], last + gaps[i])
            if at > caps[i] > last:  # closer than the spacing assumed: share the time up to the read
                at = max(ends[i], last + (caps[i] - last) / (len(frames) - i))
            ends[i] = self._last_end = at if at > last else math.nextafter(last, math.inf)
        return [e - len(f) * byte_s for e, f in zip(ends, frames)]

    def _request(self, payload: bytes, what: str, timeout: float | None = None, retries: int | None = None,
                 budget: float | None = None, proof: int | None = None) -> Frame:
        """Send a request and return its reply frame, retrying on silence and NAK.

        Each attempt waits ``timeout`` plus the line time of the reply (and of a scan telegram
        that may be in flight in continuous mode), or ``budget`` seconds when given. ``proof``: a
        reply code that shows the request took effect when its reply is lost (0xB0 for the
        request to start continuous output); such a frame is returned instead and kept for
        :meth:`scans`.
        """
        expected = reply_code(payload[0])
        telegram = build_frame(payload, self.address)
        if budget is None:
            reply_bytes = MAX_LEN + OVERHEAD_BYTES if payload[0] == CMD_MEASURE else _SHORT_REPLY_BYTES
            in_flight = MAX_LEN + OVERHEAD_BYTES if self.streaming else 0
            budget = (self.timeout if timeout is None else timeout) + frame_seconds(reply_bytes + in_flight + 1, self.baud)
        attempts = self.retries if retries is None else retries
        try:
            return self._attempts(what, telegram, expected, budget, attempts, proof)
        finally:
            self.parser.awaiting_reply = False

    def _attempts(self, what: str, telegram: bytes, expected: int, budget: float, attempts: int,
                  proof: int | None = None) -> Frame:
        """The attempts of :meth:`_request`."""
        seen: list[str] = []
        for attempt in range(attempts):
            if attempt:
                self._retries += 1
            self._doing = f"{what}: sending {telegram.hex(' ')}"
            # A reply byte (ACK / NAK) counts only after the request: handshakes read before it
            # are dropped, and with nothing unread the answer starts in step (see
            # FrameParser.request_sent: in on-request mode bytes held back are stale; while
            # streaming only a few stray bytes since the last good frame are passed over).
            self._backlog = [ev for ev in self._backlog if isinstance(ev, Frame)]
            self.parser.awaiting_reply = True  # until the first handshake: the answer's
            try:
                if not self._ser.in_waiting:
                    if not self.streaming and self.parser.pending and self._no_answer_due():
                        # On-request mode, every request answered (or nothing sent for 0.1 s): the
                        # bytes held back are no telegram on its way but garbage, which held the NAK
                        # to this request back (behind a stray 02 80 until the line had been quiet
                        # for timeout + a telegram's line time; behind > 3 stray bytes for good).
                        self._backlog += [ev for ev in self.parser.idle() if isinstance(ev, Frame)]
                    self.parser.request_sent(streaming=self.streaming)
                self._ser.write(telegram)
                self._ser.flush()
            except (serial.SerialException, OSError) as exc:
                raise self._link_lost(exc) from None
            self._unanswered += 1
            self._last_write = time.monotonic()
            self._doing = f"{what}: waiting for the reply"
            deadline = time.monotonic() + budget
            acked = naked = False
            others = 0
            while not naked:
                # The deadline is read before the port: a host kept from running past it (a loaded
                # machine) still reads what came in time, once, before it gives up the attempt.
                expired = time.monotonic() >= deadline
                read = not self._backlog  # this _pump reads the port
                events = self._pump()
                for i, ev in enumerate(events):
                    if ev == ACK:
                        acked = True
                    elif ev == NAK and not acked:
                        naked = True
                        self._unanswered = max(0, self._unanswered - 1)
                    elif isinstance(ev, Frame):
                        if ev.code == expected:
                            self._backlog = events[i + 1 :] + self._backlog
                            self._unanswered = max(0, self._unanswered - 1)
                            return ev
                        if ev.code == proof:
                            self._backlog = events[i:] + self._backlog  # the frame too, for scans()
                            self._unanswered = max(0, self._unanswered - 1)
                            return ev
                        if ev.code == REPLY_BAD_COMMAND:
                            raise LmsProtocolError(f"{what}: the device answered 0x92 (incorrect command) to {telegram.hex(' ')}")
                        others += 1
                if expired and read:
                    break
            if not naked:
                self._timeouts += 1
            seen.append("NAK" if naked else ("ACK, then no reply" if acked else "nothing") +
                        (f" ({others} other frames)" if others else ""))
        raise self._gave_up(what, telegram, expected, budget, seen)

    def _gave_up(self, what: str, telegram: bytes, expected: int, budget: float,
                 seen: list[str]) -> LmsNakError | LmsTimeoutError:
        """The error for a request given up after the attempts ``seen`` (what each saw, as
        listed in the message): a NAK to the last, or no ``expected`` reply within ``budget`` s."""
        summary = "; ".join(f"attempt {i + 1}: {s}" for i, s in enumerate(seen))
        if seen and seen[-1] == "NAK":
            return LmsNakError(f"{what}: sent {telegram.hex(' ')} on {self.port} at {self.baud} baud; {summary}")
        timeout = LmsTimeoutError(
            f"{what}: no 0x{expected:02X} reply within {budget:.2f} s on {self.port} at {self.baud} baud; {summary}"
        )
        timeout.budget_s, timeout.attempts = budget, tuple(seen)
        return timeout

    def _set_mode(self, sub_command: int, what: str) -> None:
        # A scan telegram after the request to start continuous output shows that it took (the
        # device sends none in on-request mode, and the driver asks for no single scan): its 0xA0
        # reply lost, the driver waited out mode_timeout and sent the request again.
        proof = REPLY_MEASURE if sub_command == MODE_CONTINUOUS else None
        reply = self._request(mode_request(sub_command, self.password), what, timeout=self.mode_timeout, proof=proof)
        if reply.code == REPLY_MEASURE:
            self.streaming = True
            return
        if len(reply.payload) < 2 or reply.payload[1] != 0:
            raise LmsModeRefusedError(f"{what}: the device refused (0xA0 reply {reply.payload.hex(' ')})")
        if sub_command in (MODE_CONTINUOUS, MODE_ON_REQUEST):
            self.streaming = sub_command == MODE_CONTINUOUS

    # -- setup ---------------------------------------------------------------------------------
    def _connect(self, probe: bool) -> None:
        bauds = PROBE_BAUDS if probe else (POWER_ON_BAUD,)
        for baud in bauds:
            self._use_baud(baud)
            what = f"request the type (0x3A) at {baud} baud"
            frames_before = self.parser.stats.frames
            try:  # a short wait first: at a wrong baud nothing sensible comes back
                reply = self._request(type_request(), what, retries=2, budget=self.timeout + frame_seconds(64, baud))
            except (LmsTimeoutError, LmsNakError):
                if self.parser.stats.frames == frames_before:
                    continue
                # Good frames at this baud (a device in continuous mode): the baud is right.
                self.streaming = True
                reply = self._request(type_request(), what)
            self.type_string = reply.payload[1:-1].decode("ascii", errors="replace")
            return
        raise LmsTimeoutError(f"no LMS200 answered the type request (0x3A) on {self.port} at {list(bauds)} baud")

    def _use_baud(self, baud: int) -> None:
        try:
            self._ser.baudrate = baud
            self.baud = baud
            self._ser.reset_input_buffer()
        except (serial.SerialException, OSError) as exc:
            self._doing = f"setting the port to {baud} baud"
            raise self._link_lost(exc) from None
        self.parser.reset()
        self._backlog = []

    def _set_variant(self) -> None:
        fov, res = self.variant
        what = f"set the variant {fov} deg at {res / 100} deg (0x3B)"
        reply = self._request(variant_request(fov, res), what)
        if len(reply.payload) < 2 or reply.payload[1] != 1:
            raise LmsModeRefusedError(f"{what}: the device refused (0xBB reply {reply.payload.hex(' ')})")

    def _set_units(self) -> None:
        config = self._request(get_config_request(), "read the configuration (0x74)").payload[1:-1]
        if units_of_config(config) == self.units:
            return  # a configuration write goes to EEPROM: skip it when nothing changes
        self._set_mode(MODE_INSTALLATION, "enter installation mode (0x20 0x00)")
        what = f"set the units to {self.units} (0x77)"
        reply = self._request(set_config_request(with_units(config, self.units)), what, timeout=self.mode_timeout)
        if reply.code != reply_code(CMD_SET_CONFIG) or len(reply.payload) < 2 or reply.payload[1] != 1:
            raise LmsModeRefusedError(f"{what}: the device refused (0xF7 reply {reply.payload[:2].hex(' ')})")
        self._set_mode(MODE_ON_REQUEST, "leave installation mode (0x20 0x25)")

    def _switch_baud(self, baud: int) -> None:
        """Switch the device and then the host to ``baud``, attempt by attempt (``retries``).

        The device answers a baud change at the old baud and then switches, so when its 0xA0 reply
        is lost it is at the new baud already, and a request sent again at the old baud can only
        time out (garbled): each such attempt cost ``mode_timeout`` (two of them, 7 s, before the
        new baud was checked). So after an attempt without a reply the new baud is checked at once
        (a type request; a NAK read there counts too: from a device at another baud a NAK arrives
        garbled), and the switch is sent again at the old baud only when nothing answers there."""
        if baud == self.baud:
            return
        what = f"switch from {self.baud} to {baud} baud (0x20 0x{BAUD_MODES[baud]:02X})"
        old = self.baud
        seen: list[str] = []
        budget = 0.0
        for attempt in range(self.retries):
            if attempt:
                self._retries += 1
            try:
                reply = self._request(baud_request(baud), what, timeout=self.mode_timeout, retries=1)
            except LmsNakError:
                seen.append("NAK")
                continue
            except LmsTimeoutError as exc:
                budget = exc.budget_s or 0.0
                self._use_baud(baud)
                if self._answers(f"{what}: check at {baud} baud"):
                    return
                self._use_baud(old)
                seen.append(f"{exc.attempts[-1]}, and nothing at {baud} baud")
                continue
            if len(reply.payload) < 2 or reply.payload[1] != 0:
                raise LmsModeRefusedError(f"{what}: the device refused (0xA0 reply {reply.payload.hex(' ')})")
            self._use_baud(baud)
            return
        raise self._gave_up(what, build_frame(baud_request(baud), self.address), reply_code(baud_request(baud)[0]),
                            budget, seen)

    def _answers(self, what: str) -> bool:
        """Whether the device answers a type request at the current baud (a reply or a NAK)."""
        try:
            self._request(type_request(), what, retries=1)
        except LmsNakError:
            return True
        except LmsTimeoutError:
            return False
        return True

    # -- data ----------------------------------------------------------------------------------
    @overload
    def scans(self, stall_timeout: float | None = None, stop: Callable[[], bool] | None = None,
              idle_s: None = None) -> Iterator[Scan]: ...

    @overload
    def scans(self, stall_timeout: float | None = None, stop: Callable[[], bool] | None = None, *,
              idle_s: float) -> Iterator[Scan | None]: ...

    def scans(self, stall_timeout: float | None = None, stop: Callable[[], bool] | None = None,
              idle_s: float | None = None) -> Iterator[Scan] | Iterator[Scan | None]:
        """Start continuous output and yield every scan the device sends, as it sends them.

        ``scan.stamp`` is the host's clock (``time.time()``, s) when the telegram began to arrive,
        from the time of the read that brought it (see :meth:`_stamps`): scans read together
        keep their spacing.
        Frames with a bad CRC are dropped and counted in :attr:`stats`.

        ``stop``: checked between reads (at least every 10 ms); the generator ends when it
        returns True (e.g. a flag set by a Ctrl-C handler). The device keeps streaming until
        :meth:`close`.

        ``idle_s``: when given, the generator also yields None once no scan has come for this many
        seconds, and again every ``idle_s`` while none comes, so that its consumer can do timed work
        while the device is silent (``lmsbench lms200 record`` writes the scans it holds to its bag:
        they waited in memory for the next scan, and a recording killed in a stall lost them).

        Raises:
            LmsTimeoutError: when no scan arrives for ``stall_timeout`` seconds (default: the
                request timeout plus the line time of two telegrams). The first scan after
                continuous output was started gets ``mode_timeout`` on top (a mode change takes
                up to 3 s, and a virtual device's source may take a second for its first scan).
            LmsDeviceError: when, for that long, every scan the device sent was flagged by its
                STATUS byte as not to be used (``protocol.status_problem``), naming the last flag.
        """
        # checked when called, not at the first next(): a nan stall_timeout never timed out (a device
        # gone silent hung the loop for ever), text was a TypeError once the first scan was yielded,
        # and a stop that is no function a TypeError at the first read
        if stop is not None and not callable(stop):
            raise InputError(f"stop: must be None or a function returning True to stop, got {shown(stop)}")
        limit = (check_number(stall_timeout, "stall_timeout", 0.0, MAX_STALL_TIMEOUT_S, lo_open=True, unit="s")
                 if stall_timeout is not None else self.timeout + 2 * frame_seconds(MAX_LEN + OVERHEAD_BYTES, self.baud))
        idle = (check_number(idle_s, "idle_s", 0.0, MAX_STALL_TIMEOUT_S, lo_open=True, unit="s")
                if idle_s is not None else None)
        return self._stream(limit, stop, idle)

    def _stream(self, limit: float, stop: Callable[[], bool] | None, idle_s: float | None) -> Iterator[Scan | None]:
        """The generator of :meth:`scans`, its arguments checked."""
        allowed = limit
        if not self.streaming:
            self._set_mode(MODE_CONTINUOUS, "start continuous output (0x20 0x24)")
            allowed = limit + self.mode_timeout
        self._doing = "reading scans in continuous mode"
        last = time.monotonic()
        idle_at = last if idle_s is None else last + idle_s  # when to yield None next (idle_s given)
        refused, why = 0, ""  # scans the STATUS byte refused since the last usable one, and the last one's reason
        strays, stray_why = 0, ""  # the same for scans of another variant or unit than the one set
        while stop is None or not stop():
            events = self._pump()
            now = time.monotonic()
            frames = [ev for ev in events if isinstance(ev, Frame) and ev.code == REPLY_MEASURE]
            for ev, stamp in zip(frames, self._stamps(frames)):
                try:
                    scan = decode_scan(ev.payload, stamp)
                except LmsProtocolError as exc:  # a scan flagged by its STATUS byte too: its values were yielded
                    self._decode_errors += 1
                    if isinstance(exc, LmsStatusError):
                        self._flagged += 1
                        refused, why = refused + 1, str(exc)
                    continue
                other = self._other_setting(ev.payload)
                if other:  # a 181-beam scan amid 361-beam ones was yielded, and recorded, as one
                    self._decode_errors += 1
                    strays, stray_why = strays + 1, other
                    continue
                self._scans += 1
                last, allowed, refused, strays = now, limit, 0, 0
                if idle_s is not None:
                    idle_at = now + idle_s
                yield scan
            if now - last > allowed and refused:  # the device sends, but says its values are not to be used
                raise LmsDeviceError(
                    f"no usable scan from {self.port} for {now - last:.2f} s: the device sent {refused} scans, each "
                    f"flagged by its STATUS byte as not to be used (the last: {why}); see the device")
            if now - last > allowed and strays:
                raise LmsProtocolError(
                    f"no usable scan from {self.port} for {now - last:.2f} s: the device sent {strays} scans "
                    f"of another variant or unit than the one set (the last: {stray_why}); see the device")
            if now - last > allowed:  # said "no scan ... (0 frames dropped)" of a device flagging every scan
                raise LmsTimeoutError(
                    f"no scan from {self.port} for {now - last:.2f} s in continuous mode at {self.baud} baud "
                    f"({self.parser.stats.dropped_frames} frames dropped so far)"
                )
            if idle_s is not None and now >= idle_at:
                idle_at = now + idle_s
                yield None

    def _other_setting(self, payload: bytes) -> str | None:
        """What differs between a decoded 0xB0 ``payload`` and the variant and units the device was
        set to (:meth:`_set_variant`, :meth:`_set_units`), or None. Such a telegram, its CRC good,
        is no scan of this connection: a corrupted count word or a unit set by another host. It was
        yielded as one, so a recording mixed 181-, 361- and 401-beam scans, or mm and cm."""
        count = payload[1] | (payload[2] << 8)
        beams, units = count & 0x3FF, "mm" if count >> 14 == 1 else "cm"
        want = VARIANTS[self.variant]
        if beams == want and units == self.units:
            return None
        fov, res = self.variant
        return (f"a scan of {beams} values in {units}, not the {want} values in {self.units} of "
                f"{fov} deg at {res / 100:g} deg set")

    def close(self) -> None:
        """Return the device to on-request mode and 9600 baud, then close the port.

        The port is closed even when the device does not answer; the error is raised afterwards.
        After the link failed (an :class:`LmsLinkError` was raised already) the port is only
        closed: the device cannot be reached, and the error is not raised a second time.
        """
        ser = getattr(self, "_ser", None)
        if ser is None or not ser.is_open:
            return
        try:
            if not self._lost:
                self._set_mode(MODE_ON_REQUEST, "stop continuous output (0x20 0x25)")
                self._switch_baud(POWER_ON_BAUD)
        finally:
            try:
                ser.close()
            except (serial.SerialException, OSError):
                pass  # a port that failed may fail to close too; it is closed as far as it can be

    def __repr__(self) -> str:
        return f"LMS200({self.port!r}, baud={self.baud}, type={self.type_string!r})"


__all__ = ["LMS200", "DriverStats", "PROBE_BAUDS"]


def _open_failure(exc: BaseException) -> str:
    """The reason a port did not open: the operating system's own words where pyserial wraps an
    OSError ("[Errno 21] could not open port /tmp: [Errno 21] Is a directory: '/tmp'" said the
    cause twice around the port's name), else pyserial's message."""
    cause = exc if isinstance(exc, OSError) and not isinstance(exc, serial.SerialException) else exc.__context__
    if isinstance(cause, OSError) and cause.strerror:
        return cause.strerror
    return str(exc)
