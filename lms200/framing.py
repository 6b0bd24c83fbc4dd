"""Streaming frame parser for LMS200 replies: bytes in any chunking in, whole frames out.

It resynchronises on garbage the way SICK's listing asks: look for ``STX ADDR`` (``02 80`` for
device 0), read LEN, check LEN <= 812 and the CRC, and drop what fails by skipping that one STX
byte and searching on, so a frame hidden behind a false start is still found. ACK / NAK bytes are
reported as handshake events in stream order only where the protocol puts a reply byte: at a
point where the stream is in step (its start, after a good frame, a handshake, the whole of a
telegram that failed only its CRC, a quiet line, or a request sent onto a quiet line: see
:meth:`FrameParser.request_sent`), and only when nothing but handshakes comes before the next
frame. Bytes skipped while resynchronising are garbage up to the next good frame, 0x06 and 0x15
among them (a telegram whose STX, address or LEN was hit is garbage whole, and its last byte,
the CRC's high byte, is 0x06 or 0x15 once in 128 such telegrams); so is the rest of a telegram
that failed its CRC, except its last byte when the telegram may have lost bytes (see ``_garbage``).

A false start whose LEN reaches beyond the bytes received so far waits for more bytes; call
:meth:`FrameParser.idle` when the line has gone quiet (a real device sends a frame without gaps;
links can pause, so :meth:`FrameParser.hides_frame` tells a proven false start from a partial frame),
which drops such stalled false starts and returns the frames behind them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Union

from .errors import InputError
from .finite import check_integer
from .protocol import ACK, MAX_LEN, NAK, OVERHEAD_BYTES, REPLY_FLAG, STX, crc16

HEAD_BYTES = 5
"""STX, address, LEN (2 bytes) and code: a failed telegram that begins with the same bytes as the
last good frame, where the stream was in step, is taken to be a telegram of that length (see
:meth:`FrameParser._garbage`)."""

MAX_STRAY = 3
"""Bytes skipped since the stream was last in step that still let a request written while
streaming put it back in step (:meth:`FrameParser.request_sent`): fewer than a telegram's 4 header
bytes. A telegram (7 bytes at least) whose header was hit is skipped whole; for its last byte to
come alone after the request, all but that byte must have been skipped before it: 5 bytes or
more with one byte lost on the line, 4 with two."""


@dataclass(frozen=True)
class Frame:
    """One telegram with a good CRC: ``payload`` = command / reply code, data and status bytes."""

    address: int
    payload: bytes
    end: int = field(default=-1, compare=False, repr=False)
    """Stream offset just past the frame's last byte (bytes fed to the parser before it; -1 when
    not made by a parser): with the host time of each read, when the frame arrived."""

    @property
    def code(self) -> int:
        """The command or reply code (first payload byte)."""
        return self.payload[0]

    def __len__(self) -> int:
        return len(self.payload) + OVERHEAD_BYTES


Event = Union[Frame, int]  # a Frame, or a handshake byte ACK (0x06) / NAK (0x15) outside frames


@dataclass
class ParserStats:
    """What the parser has seen so far.

    Attributes:
        frames: frames returned (good CRC).
        bad_crc: candidate frames dropped for a CRC mismatch.
        bad_length: candidate frames dropped for LEN 0 or LEN > 812.
        stalled: candidate frames dropped by :meth:`FrameParser.idle` (cut off by a quiet line).
        skipped_bytes: bytes outside any good frame that were not ACK / NAK (garbage).
        acks, naks: handshake bytes seen between frames (not amid garbage).
    """

    frames: int = 0
    bad_crc: int = 0
    bad_length: int = 0
    stalled: int = 0
    skipped_bytes: int = 0
    acks: int = 0
    naks: int = 0

    @property
    def dropped_frames(self) -> int:
        """Frame candidates thrown away: bad CRC + impossible length + stalled."""
        return self.bad_crc + self.bad_length + self.stalled


class FrameParser:
    """Incremental parser of device-to-host frames.

    Args:
        address: the reply address byte to synchronise on (device address + 0x80).
        max_len: largest LEN accepted (812 for the LMS2xx family).
    """

    def __init__(self, address: int = REPLY_FLAG, max_len: int = MAX_LEN) -> None:
        # an InputError naming each (300 was bytes()'s ValueError, None a TypeError, 'x' a TypeError at the
        # first feed; a max_len of 0 or less dropped every frame as too long: a parser that never yields, silently)
        address = check_integer(address, "address", 0, 0xFF, "(the reply address byte: device address + 0x80)", strict=True)
        max_len = check_integer(max_len, "max_len", 1, 0xFFFF, "(the largest LEN a frame may have; 812 for the LMS2xx)",
                                strict=True)
        self._sync = bytes([STX, address])
        self.max_len = max_len
        self._buf = bytearray()
        self._base = 0  # stream offset of the first byte held back
        self._shadow = 0  # held-back bytes that are the rest of a telegram with a bad CRC
        self._shadow_open = 0  # that telegram may have lost bytes: 1, and its last byte may be a handshake: 2
        self._shadow_like = False  # that telegram began like the last good frame: its length is known (see _garbage)
        self._head = b""  # the first HEAD_BYTES bytes of the last good frame
        self._in_step = True  # the next byte is where a handshake may come (not amid a resynchronisation)
        self._stale = 0  # held-back bytes received before a request in on-request mode (see request_sent)
        self._mark = 0  # stats.skipped_bytes when the stream was last put in step (a frame, a handshake, ...)
        self.awaiting_reply: bool | None = None
        """Whether a request waits for its handshake. The device answers a request with one
        handshake byte (ACK or NAK), so the exception of :meth:`_garbage` (the last byte of a
        telegram that may have lost bytes is the NAK behind it) applies only while this is True,
        and the first handshake counted sets it False. The driver sets it True before it writes
        each request and False when the request is done; None (a parser not told of requests):
        the exception always applies."""
        self.received = 0  # bytes fed so far (the stream offset of the next byte)
        self.stats = ParserStats()

    @property
    def pending(self) -> int:
        """Bytes held back while waiting for the rest of a frame."""
        return len(self._buf)

    def reset(self) -> None:
        """Forget any buffered bytes (e.g. after a baud change); keeps the counters."""
        self.stats.skipped_bytes += len(self._buf)
        self._base += len(self._buf)
        self._buf.clear()
        self._shadow = 0
        self._shadow_open = 0
        self._shadow_like = False
        self._in_step = True
        self._stale = 0
        self._mark = self.stats.skipped_bytes

    @property
    def resynchronising(self) -> bool:
        """Whether bytes were skipped since the last good frame (or handshake, or quiet line): while
        so, no byte counts as ACK / NAK."""
        return not self._in_step

    def request_sent(self, streaming: bool = False) -> None:
        """The host is about to write a request (call it just before, with nothing unread on the
        port): the bytes after it may begin the answer, whose first byte is a handshake.

        On-request mode (``streaming`` False), where the device sends nothing unasked: with no
        bytes held back (a quiet line) the stream is in step, even after garbage. With bytes held
        back (a stray STX) it is in step after them when they and the bytes skipped since the
        stream was last in step are at most :data:`MAX_STRAY`: the held bytes are then stale,
        garbage unless the bytes after them complete a frame with a good CRC (a late reply, which
        the driver tells from the answer by its code). A stray STX held back swallowed the NAK
        behind it, which cost a timeout.

        Continuous mode (``streaming`` True), with scan telegrams in flight: in step only when no
        bytes are held back and at most :data:`MAX_STRAY` were skipped since the stream was last
        in step (a stray byte after the last good frame swallowed the NAK to a stop request).

        More bytes than that may be the head of a broken telegram, whose last byte (0x06 / 0x15
        in 1 of 128) would come alone after the request: the stream stays resynchronising."""
        held = len(self._buf)
        if held and (streaming or self.stats.skipped_bytes - self._mark + held > MAX_STRAY):
            return
        if streaming and self.stats.skipped_bytes - self._mark > MAX_STRAY:
            return
        self._stale = held
        self._shadow, self._shadow_open, self._shadow_like, self._in_step = 0, 0, False, True  # _mark stays: a request is no sign of step

    def feed(self, data: bytes) -> list[Event]:
        """Add received bytes; returns the complete frames and handshake bytes, in stream order.
        ``data`` is bytes, a bytearray or a memoryview (None or text: an InputError naming it; None
        was taken as no bytes, text a TypeError)."""
        if not isinstance(data, (bytes, bytearray, memoryview)):
            raise InputError(f"data: must be the bytes received (bytes, bytearray or memoryview), got {type(data).__name__}")
        if data:
            self._buf += data
            self.received += len(data)
        return self._scan(final=False)

    def idle(self) -> list[Event]:
        """The line has gone quiet: drop stalled false starts and return the frames behind them.

        Bytes that may still begin a frame (a lone STX, or a complete header whose frame would not
        yet be complete only because its LEN is false) are resolved; a trailing lone STX is kept.
        A quiet line ends any resynchronisation: the next byte may be a handshake.
        """
        events = self._scan(final=True)
        self._in_step = True
        self._mark = self.stats.skipped_bytes
        return events

    def hides_frame(self) -> bool:
        """Whether the bytes held back contain a complete frame with a good CRC behind their first
        byte: proof that the candidate they begin with is a false start (a corrupted LEN), which
        :meth:`idle` may drop at once. Without one the held-back bytes are a consistent partial
        frame, which a stalled link (TCP, a USB adapter) may still complete."""
        buf, sync = self._buf, self._sync
        pos = buf.find(sync, 1)
        while pos >= 0:
            if len(buf) - pos >= 4:
                length = buf[pos + 2] | (buf[pos + 3] << 8)
                end = pos + length + OVERHEAD_BYTES
                if 0 < length <= self.max_len and end <= len(buf):
                    if crc16(bytes(buf[pos : end - 2])) == buf[end - 2] | (buf[end - 1] << 8):
                        return True
            pos = buf.find(sync, pos + 1)
        return False

    def frames(self, data: bytes) -> list[Frame]:
        """Like :meth:`feed`, keeping only the frames."""
        return [e for e in self.feed(data) if isinstance(e, Frame)]

    # -----------------------------------------------------------------------------------------
    def _garbage(self, events: list[Event], garbage: bytes, shadowed: int = 0, open_end: int = 0, like: bool = False) -> None:
        """Account for bytes outside frames (a run that ends where a frame candidate starts, or at
        the end of what has arrived).

        The first ``shadowed`` bytes are the rest of a telegram that failed its CRC: garbage. Its
        last byte (the CRC's high byte) is 0x06 or 0x15 once in 128 corrupted telegrams, and was
        taken for a handshake (a fake NAK made the driver resend, a fake ACK hid a real NAK behind
        it). A telegram that failed only its CRC high byte had its LEN right: the stream is in step
        again after it. One whose CRC low byte is wrong too (``open_end`` 1 or 2) may have lost bytes, so
        LEN reached past its real end and its last byte may be the handshake that followed (one
        byte lost put a real NAK there, which was swallowed and the request waited out its
        timeout): that byte is a handshake when it ends the run (a second handshake after it is
        the real one), only while a request waits for its handshake (``awaiting_reply``: ``open_end``
        2; 1 when not). A NAK taken wrongly costs a resend; one
        missed costs a timeout. With a corrupted telegram's last byte 0x06 / 0x15 in 1 of 128,
        the exception made most of the fake handshakes left while streaming.

        A telegram that failed its CRC (``like``) but began where the stream was in step with the
        same :data:`HEAD_BYTES` bytes as the last good frame has its LEN right, and a telegram loses
        bytes but never gains any: it ends at its LEN or before. While a request waits for its
        handshake, the byte right after that end (``garbage[shadowed]``, carried to the next feed
        when it has not come yet) is the handshake if it is 0x06 / 0x15; had bytes been lost, that
        position would hold the next telegram's header. A NAK right behind a scan with a
        corrupted byte was garbage (its CRC low byte wrong too) and cost the request's timeout.
        Such a telegram that lost bytes ends before a good frame found inside its span (the
        next telegram): while a request waits, the byte just before that frame is the handshake
        if it is 0x06 / 0x15 (``_scan`` holds it back until the frame is complete). A NAK behind
        a scan that lost 2 bytes or more was taken for garbage of a false start.

        The other bytes are handshakes only when the stream is in step before them and they are
        all 0x06 / 0x15 (a reply byte comes alone, then a frame or nothing). Anything else is
        garbage, 0x06 / 0x15 included, and puts the stream out of step until the next good frame:
        a telegram whose STX, address or LEN was hit is skipped whole, and its last byte is no
        handshake. A real handshake amid such garbage is lost: an ACK costs nothing (the reply
        still counts), a NAK a timeout and a resend."""
        if not garbage:
            return
        n = len(garbage)
        span = min(max(shadowed, 0), n)  # bytes of the telegram that failed its CRC
        handshakes = b""
        if span and open_end == 2 and shadowed == n and garbage[-1] in (ACK, NAK):
            span, handshakes, self._in_step = n - 1, garbage[-1:], True
        elif like and open_end == 2 and self.awaiting_reply and 0 <= shadowed < n and garbage[shadowed] in (ACK, NAK):
            span, handshakes, self._in_step = shadowed, garbage[shadowed : shadowed + 1], True
        elif span:
            self._in_step = shadowed <= n and not open_end  # after a whole telegram with only a bad CRC
        rest = garbage[span + len(handshakes):]
        if rest and self._in_step and all(b in (ACK, NAK) for b in rest):
            handshakes = rest
        elif rest:
            span, self._in_step = n, False
        self.stats.skipped_bytes += span
        if handshakes:
            self._mark = self.stats.skipped_bytes
            if self.awaiting_reply:
                self.awaiting_reply = False  # the request's one handshake has come
        for b in handshakes:
            if b == ACK:
                self.stats.acks += 1
            else:
                self.stats.naks += 1
            events.append(b)

    def _scan(self, final: bool) -> list[Event]:
        buf = self._buf
        events: list[Event] = []
        pos = 0
        size = len(buf)
        sync = self._sync
        stats = self.stats
        shadow = self._shadow  # bytes before this index belong to a telegram that failed its CRC
        open_end = self._shadow_open
        like = self._shadow_like  # that telegram began like the last good frame (its span ends at `shadow`)
        stale = self._stale  # bytes before this index came before a request (on-request mode)

        def run(pos: int, stop: int) -> None:
            """Account for the garbage run buf[pos:stop]; its stale part is garbage, and the
            stream is in step where the bytes received after the request begin."""
            nonlocal stale
            if stale and pos <= stale:
                if stop < stale:
                    stats.skipped_bytes += stop - pos
                    return
                stats.skipped_bytes += stale - pos
                pos, stale = stale, 0
                self._in_step = True
            self._garbage(events, bytes(buf[pos:stop]), shadow - pos, open_end, like and shadow >= pos)
        while True:
            start = buf.find(sync, pos)
            if start < 0:
                # Keep a trailing STX: it may be the first byte of the next frame.
                keep = size - 1 if size > pos and buf[size - 1] == STX else size
                if not final and like and pos < keep < shadow and self.awaiting_reply and buf[keep - 1] in (ACK, NAK):
                    keep -= 1  # inside a telegram of known length: the handshake if a frame starts after it
                run(pos, keep)
                pos = keep
                break
            # The candidate at `start`: waits for more bytes (None), fails, or is a good frame.
            verdict, end = None, 0
            if size - start < 4:
                verdict = "stalled" if final else None  # a header cut short by a quiet line
            else:
                length = buf[start + 2] | (buf[start + 3] << 8)
                end = start + length + OVERHEAD_BYTES
                if length == 0 or length > self.max_len:
                    verdict = "bad_length"
                elif end > size:
                    verdict = "stalled" if final else None
                elif crc16(bytes(buf[start : end - 2])) != buf[end - 2] | (buf[end - 1] << 8):
                    verdict = "bad_crc"
                else:
                    verdict = "good"
            lost = like and pos < start < shadow and self.awaiting_reply  # see _garbage
            if lost and verdict is None and buf[start - 1] in (ACK, NAK):
                run(pos, start - 1)  # the byte before the frame: decided once the frame is complete
                pos = start - 1
                break
            if lost and verdict == "good":
                shadow, open_end = start - 1, 2  # the telegram lost bytes: it ends before this frame
            elif verdict == "good" and start < shadow:
                shadow, like = pos, False  # a good frame inside the failed one: that was a false start, not a telegram
            run(pos, start)
            pos = start
            if verdict is None:
                break
            if verdict == "good":
                self._head = bytes(buf[start : start + HEAD_BYTES])
                events.append(Frame(buf[start + 1], bytes(buf[start + 4 : end - 2]), self._base + end))
                stats.frames += 1
                pos = end
                self._in_step = True
                self._mark = stats.skipped_bytes
                if stale and pos >= stale:
                    stale = 0  # a late reply completed by bytes received after the request
                continue
            if verdict == "bad_crc":
                stats.bad_crc += 1
                if end > shadow:  # the low CRC byte right: only the high one was hit, LEN was right
                    # open_end: it may have lost bytes (1), and its last byte may be the NAK behind
                    # it while a request waits for its answer (2; see _garbage)
                    open_end = 0
                    if crc16(bytes(buf[start : end - 2])) & 0xFF != buf[end - 2]:
                        open_end = 1 if self.awaiting_reply is False else 2
                    # begun where the stream was in step (or where the last such telegram's span ended), like
                    # the last good frame: a telegram of known length
                    in_step = self._in_step or (like and start == shadow)
                    like = in_step and bytes(buf[start : start + HEAD_BYTES]) == self._head
                    shadow = end
            elif verdict == "bad_length":
                stats.bad_length += 1
            else:
                stats.stalled += 1
            stats.skipped_bytes += 1
            self._in_step = False  # resynchronising: no handshake before the next good frame
            pos = start + 1
        if stale and stale <= pos:  # every stale byte resolved: the bytes after the request are read in step
            stale, self._in_step = 0, True
        self._stale = stale - pos if stale else 0
        self._shadow = max(0, shadow - pos)
        like = like and shadow >= pos  # the telegram's span ends here or further on: the byte after it is still to come
        self._shadow_like = like
        self._shadow_open = open_end if self._shadow > 0 or like else 0
        del buf[:pos]
        self._base += pos
        return events
