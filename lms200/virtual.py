"""A virtual LMS200: the device's serial behaviour as a state machine, bytes in and bytes out.

The device knows nothing of ports or threads: an adapter (:mod:`lms200.adapters`) passes it the
host's bytes with ``receive(data, now)`` and asks ``transmit(now)`` for the bytes whose last bit has
left the line by ``now`` (seconds on any monotonic clock). Every byte takes 10 bits at the current
baud (8N1), times ``time_scale``; so does every device delay (ACK, reply, mode change, mirror
period), so tests can run a faithful device 100 times faster than real time.

Behaviour (SICK LMS2xx telegram listing; README section ``lms200``): ACK before every reply, NAK for a telegram with a bad CRC,
silence for another address, a host telegram with a gap of more than 6 ms between bytes is dropped;
commands 0x10, 0x20 (installation mode with password, continuous 0x24, on-request 0x25, bauds
0x40/0x41/0x42/0x48; the 0xA0 reply to a baud change still goes out at the old baud), 0x30 01,
0x31, 0x3A, 0x3B, and the configuration telegrams 0x74 / 0x77 (units); anything else gets 0x92.
In continuous mode one 0xB0 frame follows another as fast as the baud allows, each carrying the
newest complete scan (a 0.5 deg scan completes every 26.7 ms). Each scan sent is the source's next
scan, so a replayed log comes out in order and complete. Like a real unit, whose mirror always has
a scan, the device holds the source's first scan from construction on, so the first telegram of
continuous output follows the 0xA0 reply at once (a simulator's first scan takes 0.5-0.85 s to
build; built after the reply, it arrived that much late).
"""

from __future__ import annotations

import difflib
import math
import numbers
import struct
from collections import deque
from dataclasses import dataclass, fields
from typing import Callable, Iterable, Iterator

import numpy as np

from .codes import Units, check_units, ranges_to_codes, real_numbers
from .errors import InputError
from .finite import check_instance, check_integer, check_number, check_seed, is_integer, shown, whole_number
from .protocol import (
    ACK,
    BAUD_MODES,
    CMD_GET_CONFIG,
    CMD_MEASURE,
    CMD_MODE,
    CMD_RESET,
    CMD_SET_CONFIG,
    CMD_STATUS,
    CMD_TYPE,
    CMD_VARIANT,
    CONFIG_BYTES,
    CONFIG_UNITS_OFFSET,
    MAX_LEN,
    MODE_BAUDS,
    MODE_CONTINUOUS,
    MODE_INSTALLATION,
    MODE_ON_REQUEST,
    NAK,
    OVERHEAD_BYTES,
    PASSWORD,
    POWER_ON_BAUD,
    REPLY_BAD_COMMAND,
    REPLY_FLAG,
    REPLY_POWER_ON,
    REPLY_RESET,
    STATUS_OK,
    STX,
    UNITS_CODES,
    VARIANTS,
    build_frame,
    byte_string,
    crc16,
    encode_measurement,
    reply_code,
)
from .records import Record
from .scan import Scan

MAX_TIME_SCALE = 100.0  # slowest emulation: 100x slower than the device (1e9 took days a telegram)
#: fastest emulation: a million times the device's speed, a scan period of 27 ns and a 732-byte telegram's line
#: time of 0.19 us at 38400 baud, far below what a host resolves or the emulator's own loop takes a scan (tens of
#: us: 0.01, 1e-4 and 1e-6 all served 200-270 scans/s to a recorder), so a smaller scale changes nothing but the
#: clock arithmetic: 1e-310 (any scale under about 1e-302) overflowed it (the bytes due, clock / byte time:
#: "internal error: OverflowError: cannot convert float infinity to integer" once a host asked for scans)
MIN_TIME_SCALE = 1e-6
MAX_CLOCK_S = 1e12  # |now| a device takes (s, any monotonic clock; 1e308 overflowed a byte count: int(inf))
MAX_DELAY_S = 3600.0  # longest device delay a DeviceTiming takes (the listing's longest is 3 s)
MIRROR_PERIOD_S = 1.0 / 75.0  # one mirror turn: a 1 deg scan every 13.3 ms
#: telegrams and handshakes waiting for the device's line: a host telegram received while this many wait is dropped
#: unanswered (the device busy), counted in ``requests_dropped``. A host that wrote requests without reading the
#: answers (1 MB of scan requests, or of telegrams with a bad CRC, each NAKed) queued every reply: memory and a
#: simulated scan each without bound (5 ms and 1.8 KB a scan request). A driver waits for each answer: 2 at most.
MAX_QUEUED = 16
TYPE_STRING = b"LMS200;301063;V02.10 "
SOURCE_GRID_DEG = (-90.0, 0.5, 361)  # every scan source is resampled onto the 0.5 deg frame
# Power-on configuration block: blanking 0, sensitivity 0, availability 0, 8 m / 80 m mode, cm.
POWER_ON_CONFIG = bytes([0, 0, 0, 0, 0x0D, UNITS_CODES["cm"]]) + bytes(CONFIG_BYTES - 6)


def checked_field(record: object, base: type, name: str) -> bool:
    """Whether ``name`` is a field of ``base`` that ``record`` (a ``base`` or a subclass) checks when
    set: a subclass's own fields and private names (``_note``) are set unchecked, as before; any
    other name is an InputError naming the closest field (a misspelt field was a new attribute
    nothing read)."""
    if name in _FIELD_NAMES[base]:
        return True
    names = [f.name for f in fields(record)]  # type: ignore[arg-type]
    if name.startswith("_") or name in names:
        return False
    close = difflib.get_close_matches(name, names, n=1)
    hint = f" (did you mean {close[0]}?)" if close else f"; its fields are {', '.join(names)}"
    raise InputError(f"{type(record).__name__} has no field {name!r}{hint}")


def refuse_field_deletion(record: object, name: str) -> None:
    """``del record.FIELD`` left the device to fail at its next read; InputError instead."""
    if name in {f.name for f in fields(record)}:  # type: ignore[arg-type]
        raise InputError(f"{type(record).__name__}.{name} cannot be deleted; set it to another value")
    object.__delattr__(record, name)


@dataclass
class DeviceTiming:
    """Device delays in seconds at time_scale 1 (the listing's typical and worst values); each a
    finite number in [0, MAX_DELAY_S] s (InputError naming the field: None or text was a TypeError
    at the first transmit, 10**400 an OverflowError)."""

    ack_s: float = 0.002  # ACK within 60 ms
    reply_s: float = 0.010  # reply after the ACK
    mode_change_s: float = 0.050  # on-request / continuous / baud switches
    installation_s: float = 3.0  # installation mode and a configuration write ("up to 3 s")
    reset_s: float = 1.0  # from the 0x91 reply to the 0x90 power-on string
    rx_gap_s: float = 0.006  # largest gap between bytes of one host telegram (never scaled)

    def __setattr__(self, name: str, value: object) -> None:
        """Each field checked when it is set, at construction or later (``dev.timing.ack_s = -1``
        was taken and broke the device's clock at the next request); a name that is no field is
        an InputError too (a misspelt field was a new attribute the device never read)."""
        if checked_field(self, DeviceTiming, name):
            check_number(value, name, 0.0, MAX_DELAY_S, unit="s")
        object.__setattr__(self, name, value)

    def __delattr__(self, name: str) -> None:
        refuse_field_deletion(self, name)


@dataclass
class Faults:
    """Fault injection; change the fields at any time (the device reads them on every call).

    Attributes:
        corrupt_prob: probability that a byte sent is corrupted (XOR with a random nonzero mask).
        drop_prob: probability that a byte sent is lost.
        miss_prob: probability that a correct request is ignored (as during a mirror turn).
        rx_corrupt_prob: probability that a host telegram arrives with a bit error (-> NAK).
        mute: the device stops answering and sending altogether.
        seed: seed of the fault generator (read when the device is built).
    """

    corrupt_prob: float = 0.0
    drop_prob: float = 0.0
    miss_prob: float = 0.0
    rx_corrupt_prob: float = 0.0
    mute: bool = False
    seed: int = 0

    def __setattr__(self, name: str, value: object) -> None:
        """Each field checked when it is set, at construction or later, as the fields are meant to
        be changed on a running device: probabilities in [0, 1], ``mute`` a bool, a seed >= 0;
        InputError naming the field (a text probability was numpy's UFuncTypeError at the first
        transmit, 10**400 an OverflowError; set later, ``corrupt_prob = 2`` corrupted every byte
        and ``mute = "no"`` muted the device, silently; a misspelt field was a new attribute the
        device never read)."""
        if not checked_field(self, Faults, name):
            pass
        elif name == "mute":  # None, 0 and 0.0 meant not muted before the check, and still do
            if value is not None and not isinstance(value, (bool, np.bool_)) and whole_number(value) not in (0, 1):
                raise InputError(f"mute: must be True or False, got {shown(value)}")
        elif name == "seed":
            check_seed(value)
        else:
            check_number(value, name, 0.0, 1.0)
        object.__setattr__(self, name, value)

    def __delattr__(self, name: str) -> None:
        refuse_field_deletion(self, name)


_FIELD_NAMES: dict[type, frozenset[str]] = {cls: frozenset(f.name for f in fields(cls)) for cls in (DeviceTiming, Faults)}


def resample_to_grid(scan: Scan) -> np.ndarray:
    """A scan's ranges on the LMS200's 361-beam 0.5 deg frame (nearest beam, bearings compared
    modulo a full turn; nan where uncovered);
    InputError for a ``scan`` that is no lms200.Scan (None, a number or an array were a TypeError or
    an AttributeError, found by fuzzing)."""
    if not isinstance(scan, Scan):
        raise InputError(f"scan: must be an lms200.Scan, got {type(scan).__name__}")
    start, step, n = SOURCE_GRID_DEG
    target = np.deg2rad(start + step * np.arange(n))
    if len(scan) == n and math.isclose(scan.angle_min, target[0], abs_tol=1e-9) and math.isclose(
        scan.angle_increment, target[1] - target[0], rel_tol=1e-9
    ):
        return np.array(scan.ranges)
    # modulo a full turn: a 360 deg scan from 0 to 2 pi covers -90 deg as +270 deg (its bearings were
    # taken as they were, and half of the frame came out nan)
    idx = scan.beam_of(target)
    covered = (idx >= 0) & (idx < len(scan))
    out = np.full(n, np.nan)
    out[covered] = scan.ranges[idx[covered]]
    return out


def variant_codes(ranges361: np.ndarray, variant: tuple[int, int], units: Units) -> np.ndarray:
    """Distance codes a variant reports from 0.5 deg ranges: 1 deg takes every other beam, 100 deg
    the beams from -50 to +50 deg, 0.25 deg adds midpoints: the mean of the two neighbours, so nan
    (8191, not valid) next to a nan, else +inf (8183, above the maximum) next to a +inf; -inf (too close)
    is not valid, as nan is (its midpoint with +inf too: it warned "invalid value encountered in add").

    Raises:
        InputError: ``ranges361`` that are not 361 real numbers (text was numpy's ValueError; other
            lengths were cut silently), a ``variant`` that is no LMS200 variant (a number was a
            TypeError), an unknown unit.
    """
    fov, res = check_variant(variant)
    r = np.asarray(real_numbers(ranges361), dtype=np.float64)
    shape = r.shape
    if r.size != SOURCE_GRID_DEG[2] or max(shape, default=0) != r.size:  # one axis of 361, others of 1
        raise InputError(f"ranges: must be the {SOURCE_GRID_DEG[2]} ranges of the 0.5 deg frame, got shape {r.shape}")
    r = r.reshape(-1)
    if fov == 100:
        r = r[80:281]
    if res == 100:
        r = r[::2]
    elif res == 25:
        with np.errstate(invalid="ignore"):  # -inf + inf: nan, not valid as -inf's code is, without numpy's warning
            mid = 0.5 * (r[:-1] + r[1:])  # inf + x = inf, nan propagates
        fine = np.empty(2 * r.size - 1)
        fine[0::2], fine[1::2] = r, mid
        r = fine
    axis = shape.index(SOURCE_GRID_DEG[2])  # the codes in the ranges' shape: (1, 361) ranges, (1, n) codes
    return ranges_to_codes(r, units).reshape(shape[:axis] + (r.size,) + shape[axis + 1:])


def _is_real(value: object) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def check_variant(variant: object) -> tuple[int, int]:
    """``variant`` (a tuple or a list: ``variant_codes(r, [180, 50], 'cm')`` worked before this
    check) as (fov deg, resolution 1/100 deg), two ints of an LMS200 variant; InputError otherwise
    (([180], 50) was a TypeError, unhashable; (180.0, 50) passed the device's check of the time
    and a refused 0x3B later raised struct.error in receive(); a number was "cannot unpack" in
    variant_codes)."""
    items = tuple(variant) if isinstance(variant, (tuple, list)) else ()
    pair = tuple(int(v) for v in items) if all(map(is_integer, items)) else ()  # type: ignore[call-overload]
    if len(pair) != 2 or pair not in VARIANTS:
        raise InputError(f"variant: {shown(variant)} is not an LMS200 variant; the variants are (fov deg, resolution "
                         f"1/100 deg, ints) {', '.join(map(str, VARIANTS))} (25 = 0.25 deg only with 100 deg)")
    return pair  # type: ignore[return-value]


@dataclass
class _Chunk:
    start: float  # when the first bit goes out
    byte_s: float  # seconds per byte
    data: bytes
    baud: int
    done: Callable[[], None] | None = None
    sent: int = 0


class VirtualLMS200:
    """The device state machine.

    Args:
        source: scans to report (any iterable of :class:`Scan`; each is resampled onto the 0.5 deg
            frame). When it runs out, the device reports no more scans.
        address: device address (replies go to address + 0x80).
        time_scale: multiplies every byte time and device delay (1 = real time, 0.01 = 100x faster), in
            [MIN_TIME_SCALE, MAX_TIME_SCALE] = [1e-6, 100].
        timing: device delays; faults: fault injection.
        units, variant: power-on unit mode and (field of view deg, resolution 1/100 deg).
    """

    def __init__(
        self,
        source: Iterable[Scan],
        address: int = 0,
        time_scale: float = 1.0,
        timing: DeviceTiming | None = None,
        faults: Faults | None = None,
        units: Units = "cm",
        variant: tuple[int, int] = (180, 50),
    ) -> None:
        if not _is_real(time_scale):
            raise InputError(f"time_scale: must be a number, got {type(time_scale).__name__} {shown(time_scale)}")
        if not MIN_TIME_SCALE <= time_scale <= MAX_TIME_SCALE:  # also nan
            raise InputError(f"time_scale: must be in [{MIN_TIME_SCALE:g}, {MAX_TIME_SCALE:g}] (a million times faster "
                             f"than the device to 100 times slower), got {shown(time_scale)}")
        variant = check_variant(variant)
        units = check_units(units)  # a list was a TypeError (unhashable)
        if not is_integer(address) or not 0 <= address <= 0x7F:
            raise InputError(f"address: must be an integer in 0..127 (replies come from address + 0x80), got {shown(address)}")
        try:  # iter() decides, as before: an object with only __getitem__ is iterable too
            scans = iter(source) if not isinstance(source, (str, bytes)) else None
        except TypeError:  # None was "not iterable"
            scans = None
        if scans is None:
            raise InputError(f"source: must be an iterable of lms200.Scan, got {type(source).__name__}")
        check_instance(timing, DeviceTiming, "timing")  # a number was an AttributeError at the first transmit
        check_instance(faults, Faults, "faults")  # a number was an AttributeError ('no attribute seed')
        self._source: Iterator[Scan] = scans
        self.address = address
        self.time_scale = float(time_scale)
        self.timing = timing or DeviceTiming()
        self.faults = faults or Faults()
        self._rng = np.random.default_rng(self.faults.seed)
        self.config = bytearray(POWER_ON_CONFIG)
        self.config[CONFIG_UNITS_OFFSET] = UNITS_CODES[units]
        self._power_on_variant = variant
        self.variant = variant
        self.baud = POWER_ON_BAUD
        self.mode = MODE_ON_REQUEST
        self.source_exhausted = False
        self._taken = 0  # items taken from the source (an error names the one that is no Scan)
        self._ready: Scan | None = None
        self._ready = self._next_scan()  # built now, not after the 0x24 reply (see the module doc)
        self.scans_sent = 0
        self.requests = 0
        self.requests_dropped = 0  # host telegrams dropped unanswered while MAX_QUEUED answers waited for the line
        self._queue: deque[_Chunk] = deque()
        self._line_free = 0.0
        self._continuous_from = 0.0
        self._last_scan_index = -1
        self._rx = bytearray()
        self._rx_last = -math.inf

    # -- state ---------------------------------------------------------------------------------
    @property
    def units(self) -> Units:
        """Current unit mode ('mm' or 'cm'), from the configuration block."""
        return "mm" if self.config[CONFIG_UNITS_OFFSET] == UNITS_CODES["mm"] else "cm"

    @property
    def continuous(self) -> bool:
        return self.mode == MODE_CONTINUOUS

    def _s(self, seconds: float) -> float:
        return seconds * self.time_scale

    def _scan_period(self) -> float:
        turns = {100: 1, 50: 2, 25: 4}[self.variant[1]]
        return self._s(MIRROR_PERIOD_S * turns)

    # -- host -> device ------------------------------------------------------------------------
    def receive(self, data: bytes, now: float) -> None:
        """Bytes from the host, received at ``now`` (s); InputError for ``data`` that are not bytes
        (text was a TypeError, an array numpy's ambiguous-truth ValueError) or a ``now`` that is no
        finite number (None or text was a TypeError, 10**400 an OverflowError)."""
        data = byte_string(data, "data")
        check_number(now, "now", -MAX_CLOCK_S, MAX_CLOCK_S, unit="s")
        if not data:
            return
        if self._rx and now - self._rx_last > self.timing.rx_gap_s:
            self._rx.clear()  # the host paused mid-telegram: the device drops it
        self._rx_last = now
        self._rx += data
        self._parse_requests(now)

    def _parse_requests(self, now: float) -> None:
        buf = self._rx
        while buf:
            if buf[0] != STX:
                start = buf.find(bytes([STX]))
                del buf[: start if start >= 0 else len(buf)]
                continue
            if len(buf) < 4:
                return
            length = buf[2] | (buf[3] << 8)
            if length == 0 or length > MAX_LEN:
                del buf[:1]
                continue
            end = length + OVERHEAD_BYTES
            if len(buf) < end:
                return
            frame = bytes(buf[:end])
            del buf[:end]
            if self.faults.mute:
                continue
            if len(self._queue) >= MAX_QUEUED:  # busy: see MAX_QUEUED
                self.requests_dropped += 1
                continue
            hit = self.faults.rx_corrupt_prob and self._rng.random() < self.faults.rx_corrupt_prob
            if hit or crc16(frame[:-2]) != (frame[-2] | (frame[-1] << 8)):
                self._send(bytes([NAK]), now + self._s(self.timing.ack_s))
                continue
            if frame[1] != self.address:
                continue  # another device's telegram: silence
            self.requests += 1
            if self.faults.miss_prob and self._rng.random() < self.faults.miss_prob:
                continue  # missed during a mirror turn
            self._handle(frame[4:-2], now)

    # -- commands ------------------------------------------------------------------------------
    def _handle(self, payload: bytes, now: float) -> None:
        t_ack = now + self._s(self.timing.ack_s)
        t_reply = t_ack + self._s(self.timing.reply_s)
        self._send(bytes([ACK]), t_ack)
        cmd, data = payload[0], payload[1:]
        if cmd == CMD_MODE and data:
            self._mode(data, t_reply)
        elif cmd == CMD_MEASURE and data == b"\x01":
            self._reply(self._scan_payload(), t_reply, count_scan=True)
        elif cmd == CMD_TYPE and not data:
            self._reply(bytes([reply_code(cmd)]) + TYPE_STRING, t_reply)
        elif cmd == CMD_STATUS and not data:
            # Simplified 0xB1: software version and operating mode (the real block is 152 bytes).
            self._reply(bytes([reply_code(cmd)]) + TYPE_STRING[-7:] + bytes([self.mode]), t_reply)
        elif cmd == CMD_VARIANT and len(data) == 4:
            fov, res = struct.unpack("<HH", data)
            ok = (fov, res) in VARIANTS
            if ok:
                self._set_variant((fov, res))
            cur = struct.pack("<HH", *self.variant)
            self._reply(bytes([reply_code(cmd), 1 if ok else 0]) + cur, t_reply)
        elif cmd == CMD_GET_CONFIG and not data:
            self._reply(bytes([reply_code(cmd)]) + bytes(self.config), t_reply)
        elif cmd == CMD_SET_CONFIG:
            self._set_config(data, t_reply)
        elif cmd == CMD_RESET and not data:
            self._reply(bytes([REPLY_RESET]), t_reply, done=self._power_on)
        else:
            self._reply(bytes([REPLY_BAD_COMMAND]), t_reply)

    def _mode(self, data: bytes, t_reply: float) -> None:
        sub = data[0]
        done: Callable[[], None] | None = None
        delay = self._s(self.timing.mode_change_s)
        ok = True
        if sub == MODE_INSTALLATION:
            ok = data[1:] == PASSWORD
            delay = self._s(self.timing.installation_s)
            if ok:
                self.mode = MODE_INSTALLATION
        elif sub in (MODE_CONTINUOUS, MODE_ON_REQUEST) and len(data) == 1:
            if sub == MODE_ON_REQUEST:
                self.mode = MODE_ON_REQUEST
            else:
                def done() -> None:
                    self.mode = MODE_CONTINUOUS
                    self._continuous_from = self._line_free
        elif sub in MODE_BAUDS and len(data) == 1:
            new_baud = MODE_BAUDS[sub]

            def done() -> None:  # the reply goes out at the old baud
                self.baud = new_baud
        else:
            ok = False
        payload = bytes([reply_code(CMD_MODE), 0 if ok else 1])
        self._reply(payload, t_reply + (delay if ok else 0.0), done=done if ok else None)

    def _set_config(self, data: bytes, t_reply: float) -> None:
        ok = self.mode == MODE_INSTALLATION and len(data) == CONFIG_BYTES and data[CONFIG_UNITS_OFFSET] in (0, 1)
        if ok:
            self.config[:] = data
        payload = bytes([reply_code(CMD_SET_CONFIG), 1 if ok else 0]) + bytes(self.config)
        self._reply(payload, t_reply + (self._s(self.timing.installation_s) if ok else 0.0))

    def _power_on(self) -> None:
        """After a reset: 9600 baud, on-request mode, power-on variant; then the 0x90 string."""
        self.baud = POWER_ON_BAUD
        self.mode = MODE_ON_REQUEST
        self._set_variant(self._power_on_variant)
        self._reply(bytes([REPLY_POWER_ON]) + TYPE_STRING, self._line_free + self._s(self.timing.reset_s))

    def _set_variant(self, variant: tuple[int, int]) -> None:
        """Take ``variant``; a new one starts the count of mirror scans afresh. The index of the
        last scan sent counts scans of the old variant's period: kept, a switch to a longer period
        (0.5 -> 0.25 deg) read it as a scan twice as late, and continuous output waited until the
        clock had doubled (found by recording 0.25 deg after a 0.5 deg recording on one emulator:
        no scan, then no answer at all)."""
        if variant != self.variant:
            self._last_scan_index = -1
        self.variant = variant

    # -- device -> host ------------------------------------------------------------------------
    def _next_scan(self) -> Scan | None:
        """The source's next scan: the one held since construction first, else a new one (None
        when the source has run out)."""
        scan, self._ready = self._ready, None
        if scan is not None or self.source_exhausted:
            return scan
        try:
            item = next(self._source)
        except StopIteration:
            self.source_exhausted = True
            return None
        self._taken += 1
        if not isinstance(item, Scan):  # said here, naming the item: it failed in the adapter's thread, where
            # the host saw only a timeout (a library walkthrough passed read_log's records, not their scans)
            hint = " (a log's records: pass their scans, rec.scan for rec in read_log(path))" if isinstance(item, Record) else ""
            raise InputError(f"source: item {self._taken - 1} is a {type(item).__name__}, not an lms200.Scan{hint}")
        return item

    def _scan_payload(self) -> bytes | None:
        scan = self._next_scan()
        if scan is None:
            return None
        codes = variant_codes(resample_to_grid(scan), self.variant, self.units)
        return encode_measurement(codes, self.units)[:-1]  # _reply appends the status byte

    def _reply(self, payload: bytes | None, ready: float, done: Callable[[], None] | None = None,
               count_scan: bool = False) -> None:
        if payload is None:
            return
        payload = payload + bytes([STATUS_OK])
        if count_scan:
            self.scans_sent += 1
        self._send(build_frame(payload, self.address | REPLY_FLAG), ready, done)

    def _send(self, data: bytes, ready: float, done: Callable[[], None] | None = None) -> None:
        byte_s = self._s(10.0 / self.baud)
        start = max(ready, self._line_free)
        self._queue.append(_Chunk(start, byte_s, data, self.baud, done))
        self._line_free = start + byte_s * len(data)

    def _fill_continuous(self, now: float) -> None:
        if self._queue or self.mode != MODE_CONTINUOUS or self.faults.mute or self.source_exhausted:
            return
        # Send the newest scan completed when the line frees; if it was sent already, wait for
        # the next one (the mirror completes a scan every `period` seconds).
        period = self._scan_period()
        base = max(self._line_free, self._continuous_from, now - period)
        newest = math.floor(base / period + 1e-9)
        if newest > self._last_scan_index:
            ready = base
        else:
            newest = self._last_scan_index + 1
            ready = newest * period
        self._last_scan_index = newest
        self._reply(self._scan_payload(), ready, count_scan=True)

    def transmit(self, now: float) -> list[tuple[bytes, int]]:
        """Bytes that have left the line by ``now``, as (bytes, baud they were sent at) pieces;
        InputError for a ``now`` that is no finite number (inf was an OverflowError, None a TypeError)."""
        check_number(now, "now", -MAX_CLOCK_S, MAX_CLOCK_S, unit="s")
        if self.faults.mute:
            self._queue.clear()
            self._line_free = now
            return []
        out: list[tuple[bytes, int]] = []
        self._fill_continuous(now)
        while self._queue:
            chunk = self._queue[0]
            due = int((now - chunk.start) / chunk.byte_s + 1e-9) if now >= chunk.start else 0
            n = min(len(chunk.data), due) - chunk.sent
            if n <= 0:
                break
            piece = chunk.data[chunk.sent : chunk.sent + n]
            chunk.sent += n
            out.append((self._inject(piece), chunk.baud))
            if chunk.sent < len(chunk.data):
                break
            self._queue.popleft()
            if chunk.done is not None:
                chunk.done()
            if not self._queue:
                # The next scan is built on the next call (next_wakeup or transmit), after the
                # bytes due now are handed over: building it here (a slow source) held back the
                # tail of the reply just sent, a gap no device makes.
                break
        return [(d, b) for d, b in out if d]

    def next_wakeup(self, now: float) -> float | None:
        """When the next byte will be due (s), or None while the device waits for the host; InputError
        for a ``now`` that is no finite number."""
        check_number(now, "now", -MAX_CLOCK_S, MAX_CLOCK_S, unit="s")
        if self.faults.mute:
            return None
        self._fill_continuous(now)
        if self._queue:
            chunk = self._queue[0]
            return chunk.start + (chunk.sent + 1) * chunk.byte_s
        return None

    def _inject(self, data: bytes) -> bytes:
        f = self.faults
        if not (f.corrupt_prob or f.drop_prob):
            return data
        arr = np.frombuffer(data, dtype=np.uint8).copy()
        if f.corrupt_prob:
            hit = self._rng.random(arr.size) < f.corrupt_prob
            arr[hit] ^= self._rng.integers(1, 256, hit.sum(), dtype=np.uint8)
        if f.drop_prob:
            arr = arr[self._rng.random(arr.size) >= f.drop_prob]
        return arr.tobytes()


def garble(data: bytes, baud_sent: int, baud_read: int) -> bytes:
    """What a UART set to ``baud_read`` makes of bytes sent at ``baud_sent``: unchanged when the
    bauds agree, else a deterministic stream of wrong bytes (framing errors), about as many
    bytes as bit times fit (never a valid telegram in practice). InputError for ``data`` that are not
    bytes or a baud that is no whole number >= 1 (0 was a ZeroDivisionError, None a TypeError,
    5e-324 an OverflowError), empty data included: a baud of 0 is no line. A whole float baud
    (9600.0) is a baud, as for ``frame_seconds`` and ``baud_request``."""
    data = byte_string(data, "data")
    baud_sent = check_integer(baud_sent, "baud_sent", 1)
    baud_read = check_integer(baud_read, "baud_read", 1)
    if baud_sent == baud_read or not data:
        return data
    n = max(1, round(len(data) * baud_read / baud_sent))
    src = np.resize(np.frombuffer(data, dtype=np.uint8), n).astype(np.uint16)
    return ((src * 37 + 0x5B + np.arange(n)) & 0xFF).astype(np.uint8).tobytes().replace(bytes([STX]), b"\xfd")


__all__ = ["VirtualLMS200", "DeviceTiming", "Faults", "garble", "resample_to_grid", "variant_codes", "BAUD_MODES"]
