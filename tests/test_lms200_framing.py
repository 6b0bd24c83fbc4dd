"""The streaming frame parser: resynchronisation, drop counters, and a property-based fuzz."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lms200.framing import Frame, FrameParser
from lms200.protocol import ACK, NAK, build_frame


def frame(payload: bytes) -> bytes:
    return build_frame(payload, address=0x80)


def test_frames_split_byte_by_byte_with_acks_between() -> None:
    a, b = frame(b"\xa0\x00\x10"), frame(b"\xba" + b"LMS200" + b"\x10")
    stream = bytes([ACK]) + a + bytes([ACK]) + b
    p = FrameParser()
    events = []
    for i in range(len(stream)):
        events += p.feed(stream[i : i + 1])
    assert events == [ACK, Frame(0x80, b"\xa0\x00\x10"), ACK, Frame(0x80, b"\xbaLMS200\x10")]
    assert p.stats.acks == 2 and p.stats.skipped_bytes == 0 and p.stats.dropped_frames == 0


def test_bad_crc_and_impossible_length_are_counted_and_skipped() -> None:
    good = frame(b"\xb0\x01\x00\x10")
    bad = bytearray(good)
    bad[5] ^= 0x01
    too_long = bytes([0x02, 0x80, 0x2D, 0x03])  # LEN 813
    p = FrameParser()
    out = p.feed(bytes(bad) + too_long + b"gar\x15bage\x15" + good)
    # 0x15 amid garbage is garbage, and so is the one just before the frame: while resynchronising
    # no byte is a handshake (it is what the last byte of a telegram with its header hit looks like)
    assert out == [Frame(0x80, b"\xb0\x01\x00\x10")]
    assert p.stats.bad_crc == 1 and p.stats.bad_length == 1 and p.stats.naks == 0


def test_false_start_waits_then_idle_recovers_the_frame_behind_it() -> None:
    good = frame(b"\xa0\x00\x10")
    false_start = bytes([0x02, 0x80, 0x00, 0x02])  # announces 512 bytes that never come
    p = FrameParser()
    assert p.frames(false_start + good) == []
    assert p.idle() == [Frame(0x80, b"\xa0\x00\x10")]
    assert p.stats.stalled == 1 and p.pending == 0


def test_frames_for_other_addresses_are_ignored() -> None:
    p = FrameParser(address=0x81)
    assert p.frames(frame(b"\xa0\x00\x10") + build_frame(b"\xa0\x01\x10", address=0x81)) == [Frame(0x81, b"\xa0\x01\x10")]


# -- fuzz ---------------------------------------------------------------------------------------


@st.composite
def streams(draw):  # noqa: ANN001, ANN201
    """A byte stream of intact frames mixed with garbage, truncated frames and bit-flipped frames."""
    parts: list[bytes] = []
    intact: list[bytes] = []
    for _ in range(draw(st.integers(1, 8))):
        kind = draw(st.sampled_from(["frame", "frame", "garbage", "truncated", "flipped", "header"]))
        if kind == "frame":
            n = draw(st.sampled_from([1, 3, 12, 40, 726]))
            payload = draw(st.binary(min_size=n, max_size=n))
            parts.append(frame(payload))
            intact.append(payload)
        elif kind == "garbage":
            parts.append(draw(st.binary(max_size=60)))
        elif kind == "header":  # a plausible false start: STX, reply address, random length
            parts.append(bytes([0x02, 0x80]) + draw(st.binary(min_size=0, max_size=3)))
        else:
            f = bytearray(frame(draw(st.binary(min_size=1, max_size=60))))
            if kind == "truncated":  # at least 2 bytes short: a frame short of its last byte only
                # is completed by the next frame's STX whenever its CRC high byte is 0x02 (1 in 256),
                # and no parser can tell that frame from a good one (found by this fuzz, session 33)
                f = f[: draw(st.integers(1, len(f) - 2))]
            else:
                i = draw(st.integers(0, len(f) - 1))
                f[i] ^= 1 << draw(st.integers(0, 7))
            parts.append(bytes(f))
    stream = b"".join(parts)
    cuts = sorted(draw(st.lists(st.integers(0, len(stream)), max_size=6)))
    return stream, intact, cuts


def feed_cut(p: FrameParser, stream: bytes, cuts: list[int]) -> list:
    """The events of ``stream`` fed in pieces cut at ``cuts``, then of a quiet line."""
    events = []
    bounds = [0, *cuts, len(stream)]
    for lo, hi in zip(bounds[:-1], bounds[1:]):
        events += p.feed(stream[lo:hi])
    return events + p.idle()


def is_subsequence(needles: list[bytes], haystack: list[bytes]) -> bool:
    it = iter(haystack)
    return all(any(n == h for h in it) for n in needles)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(streams())
def test_fuzz_every_intact_frame_is_recovered(case) -> None:  # noqa: ANN001
    stream, intact, cuts = case
    p = FrameParser()
    events = feed_cut(p, stream, cuts)
    got = [e.payload for e in events if isinstance(e, Frame)]
    assert is_subsequence(intact, got)
    assert all(e in (ACK, NAK) for e in events if not isinstance(e, Frame))
    assert p.stats.frames == len(got)
    assert p.pending <= 1  # at most a trailing STX is held back


def test_fuzz_random_noise_never_raises_and_counts_every_byte() -> None:
    rng = np.random.default_rng(5)
    noise = rng.integers(0, 256, 20000, dtype=np.uint8).tobytes()
    p = FrameParser()
    for i in range(0, len(noise), 997):
        p.feed(noise[i : i + 997])
    p.idle()
    s = p.stats
    assert s.frames == 0
    assert s.skipped_bytes + s.acks + s.naks + p.pending == len(noise)


def test_hides_frame_tells_a_false_start_from_a_partial_frame() -> None:
    good = frame(b"\xa0\x00\x10")
    p = FrameParser()
    assert p.feed(good[:5]) == [] and p.pending == 5 and not p.hides_frame()  # a reply cut by a stalled link
    assert p.feed(good[5:]) == [Frame(0x80, b"\xa0\x00\x10")]
    assert p.feed(bytes([0x02, 0x80, 0x00, 0x02]) + good[:-1]) == [] and not p.hides_frame()  # not yet complete
    assert p.feed(good[-1:]) == [] and p.hides_frame()  # a good frame behind LEN 512: a false start
    assert p.idle() == [Frame(0x80, b"\xa0\x00\x10")] and p.stats.stalled == 1


def test_the_crc_byte_of_a_corrupted_telegram_is_no_handshake() -> None:
    """Review 32 (frm.py): the type reply with its CRC high byte hit into 0x15, then a scan, gave
    [NAK, frame]: the broken telegram's last byte was taken for a NAK (0x06: for an ACK). Bytes
    of a telegram that failed its CRC are garbage now; a handshake right after it still counts."""
    ba = bytearray(frame(b"\xba" + b"LMS200;301063;V02.10 " + b"\x10"))
    b0 = frame(b"\xb0\x01\x00\x10")
    for tail in (NAK, ACK):
        ba[-1] = tail
        p = FrameParser()
        assert p.feed(bytes(ba) + b0) == [Frame(0x80, b"\xb0\x01\x00\x10")]
        assert (p.stats.acks, p.stats.naks, p.stats.bad_crc, p.stats.skipped_bytes) == (0, 0, 1, len(ba))
        p = FrameParser()  # the broken telegram in one read, a real handshake in the next
        assert p.feed(bytes(ba)) == [] and p.feed(bytes([NAK])) == [NAK] and p.stats.naks == 1
        p = FrameParser()
        assert p.feed(bytes(ba) + bytes([ACK]) + b0) == [ACK, Frame(0x80, b"\xb0\x01\x00\x10")]
    # A good frame inside a failed candidate's span proves that candidate false: its span is no
    # telegram, and the frame is found; the bytes between are skipped while resynchronising, an
    # 0x06 among them too (it counted as an ACK before the closing note of session 32).
    good = frame(b"\xa0\x00\x10")
    false_start = bytes([0x02, 0x80, 0x0A, 0x00, 0x00])  # LEN 10 spans the ACK and part of the reply
    p = FrameParser()
    assert p.feed(false_start + bytes([ACK]) + good + bytes(8)) == [Frame(0x80, b"\xa0\x00\x10")]
    p = FrameParser()  # a request sent onto the quiet line after it: its ACK counts
    assert p.feed(false_start) == [] and p.idle() == [] and not p.resynchronising
    p.request_sent()
    assert p.feed(bytes([ACK]) + good) == [ACK, Frame(0x80, b"\xa0\x00\x10")]


def test_a_nak_behind_a_telegram_that_lost_a_byte_is_still_a_nak() -> None:
    """Review 32c (nakvar.py): a scan telegram that lost one byte on the line reaches, by its LEN,
    one byte further: onto the NAK behind it, which was skipped as the failed telegram's CRC byte
    (NAK seen False for '1 byte lost' and 'LEN+1'; the request waited out its timeout). The span's
    last byte is a handshake when the telegram's CRC low byte is wrong too (so more than the high
    byte was hit); a telegram whose only fault is its CRC high byte still hides none."""
    from lms200.protocol import encode_measurement

    scan = frame(encode_measurement(np.full(361, 1000, np.uint16), "mm"))
    longer = bytearray(scan)
    longer[2] += 1
    cases = {"1 byte lost": scan[:100] + scan[101:], "LEN+1": bytes(longer)}
    for name, bad in cases.items():
        for tail in (scan, b""):
            p = FrameParser()
            events = p.feed(bad + bytes([NAK]) + tail)
            assert events[0] == NAK, name  # old: no NAK
            assert (p.stats.naks, p.stats.bad_crc, p.stats.frames) == (1, 1, 1 if tail else 0), name
            assert p.stats.skipped_bytes + p.stats.naks + p.pending == len(bad) + 1
    # The broken telegram's own last byte 0x06, then the real NAK: the NAK is the handshake.
    p = FrameParser()
    assert p.feed(cases["1 byte lost"][:-1] + bytes([ACK, NAK]) + scan)[0] == NAK and p.stats.acks == 0
    # Only the CRC high byte hit (0x15 / 0x06): no handshake, as before.
    for value in (NAK, ACK):
        hit = bytearray(scan)
        hit[-1] = value
        p = FrameParser()
        assert p.feed(bytes(hit) + scan) == [Frame(0x80, scan[4:-2])] and p.stats.acks + p.stats.naks == 0


def _scan_telegram(first: int) -> bytes:
    from lms200.protocol import encode_measurement

    values = np.full(361, 1000, np.uint16)
    values[0] = first
    return frame(encode_measurement(values, "mm"))


def _header_hits(telegram: bytes) -> dict[str, bytes]:
    """The telegram with each header byte (STX, address, LEN low, LEN high) hit: every single-bit
    flip, and the byte lost."""
    out = {}
    for k, name in enumerate(("STX", "address", "LEN low", "LEN high")):
        for bit in range(8):
            hit = bytearray(telegram)
            hit[k] ^= 1 << bit
            out[f"{name} bit {bit}"] = bytes(hit)
        out[f"{name} lost"] = telegram[:k] + telegram[k + 1 :]
    return out


def _header_hit_streams(good_values: tuple[int, int, int]):
    """Each of the 40 header hits of a scan telegram ending in 0x15 and of one ending in 0x06, between
    three good scans: (the good telegrams, the hit's name, the broken telegram, the stream)."""
    goods = [_scan_telegram(v) for v in good_values]
    for first, tail in ((217, NAK), (154, ACK)):
        victim = _scan_telegram(first)
        assert victim[-1] == tail
        for name, broken in _header_hits(victim).items():
            yield goods, name, broken, goods[0] + broken + goods[1] + goods[2]


def test_a_telegram_whose_header_was_hit_leaves_no_handshake_and_loses_no_frame() -> None:
    """Closing note of session 32: a telegram whose STX, address or LEN was hit is garbage whole,
    and its last byte (the CRC's high byte) ended the garbage run before the next frame (or a
    read), where it was taken for a handshake: an NAK made a waiting request resend, an ACK hid a
    real NAK. Scan telegrams whose CRC high byte is 0x15 and 0x06, each of 40 header hits, in a
    stream between good scans, fed whole, byte by byte and cut around the hit: no handshake, and
    every good scan behind it is found. Old: a handshake in 36 of the 40 hits fed whole (33 byte by byte)."""
    for goods, name, broken, stream in _header_hit_streams((1, 2, 3)):
        at = len(goods[0])
        cut_sets = {"whole": [], "byte by byte": list(range(1, len(stream))),
                    "around the hit": [at + c for c in (1, 2, 3, 4, 5, 100, len(broken) - 1, len(broken))]}
        if name == "STX bit 2":  # 0x02 -> 0x06 ending a read where the stream is in step: taken
            # for an ACK (it cannot be told from one until the next byte comes), see docs/lms200.md
            cut_sets = {k: [c for c in v if c != at + 1] for k, v in cut_sets.items()}
        for how, cuts in cut_sets.items():
            p = FrameParser()
            events = feed_cut(p, stream, cuts)
            assert [e for e in events if not isinstance(e, Frame)] == [], (name, how)
            assert [e.payload for e in events] == [g[4:-2] for g in goods], (name, how)
            assert (p.stats.acks, p.stats.naks) == (0, 0)


def test_handshakes_count_only_where_the_stream_is_in_step() -> None:
    """A reply byte comes alone, then a frame or nothing: after a good frame, a handshake, the
    whole of a telegram that failed only its CRC, a quiet line, or a request sent onto a quiet
    line. Amid a resynchronisation (after skipped bytes, before the next good frame) 0x06 / 0x15
    are garbage; an 0x06 followed by anything but a frame or another handshake is too."""
    good = frame(b"\xa0\x00\x10")
    p = FrameParser()
    assert p.feed(bytes([ACK]) + good + bytes([NAK])) == [ACK, Frame(0x80, b"\xa0\x00\x10"), NAK]
    assert p.feed(b"\x06\x80\xd6\x02") == [] and p.resynchronising  # a hit STX, not an ACK
    assert p.feed(bytes([NAK])) == [] and p.feed(good) == [Frame(0x80, b"\xa0\x00\x10")]
    assert not p.resynchronising and p.feed(bytes([NAK])) == [NAK]
    assert (p.stats.acks, p.stats.naks, p.stats.skipped_bytes) == (1, 2, 5)
    p.feed(b"noise")
    p.request_sent()  # nothing held back: the answer starts here
    assert p.feed(bytes([NAK])) == [NAK]
    p.feed(b"noise\x02")  # a trailing STX held back after 5 bytes of garbage: more than MAX_STRAY
    p.request_sent()
    assert p.resynchronising and p.feed(bytes([NAK])) == []


def test_a_stray_stx_held_back_when_a_request_is_written_does_not_swallow_the_nak() -> None:
    """Review 33b, case 1 (on-request mode): one stray STX held back by the parser, then the
    request, then the device's NAK: the parent of 9b86e73 counted it, 9b86e73 did not (the
    request reset the stream only with nothing held back), and the driver waited out its timeout
    instead of resending. The device sends nothing unasked, so the held bytes are stale."""
    p = FrameParser()
    assert p.feed(b"\x02") == [] and p.pending == 1
    p.request_sent()
    assert p.feed(bytes([NAK])) == [NAK]  # 9b86e73: []
    assert (p.stats.naks, p.stats.skipped_bytes, p.pending) == (1, 1, 0)
    # An ACK and the reply behind a stray STX: both count.
    reply = frame(b"\xa0\x00\x10")
    p.feed(b"\x02")
    p.request_sent()
    assert p.feed(bytes([ACK]) + reply) == [ACK, Frame(0x80, b"\xa0\x00\x10")]
    # A late reply whose head was held back when the request was written is still a frame.
    p.feed(reply[:3])
    p.request_sent()
    assert p.feed(reply[3:] + bytes([ACK]) + reply) == [Frame(0x80, b"\xa0\x00\x10"), ACK, Frame(0x80, b"\xa0\x00\x10")]
    assert (p.stats.acks, p.stats.naks, p.stats.skipped_bytes) == (2, 1, 2)


def test_a_broken_late_reply_held_back_when_a_request_is_written_leaves_no_handshake() -> None:
    """The held bytes made stale by a request may be the head of a late reply that was hit on the
    line. Every bit flip and loss of every byte of a reply ending in 0x15, cut at every byte with
    bytes held back at the cut and the request written there: the rest of it never reads as a
    handshake (at most MAX_STRAY bytes held and skipped since the last good frame let the stream
    be in step after them; a telegram has 7 bytes at least, so at least 2 of it follow). The
    exception for a telegram that may have lost a byte (its last byte ending the run is the NAK
    behind it while a reply is awaited) is switched off here: it is the same with or without a
    request (see test_a_nak_behind_a_telegram_that_lost_a_byte_is_still_a_nak)."""
    reply = next(r for r in (frame(bytes([0xA0, j, 0x10])) for j in range(256)) if r[-1] == NAK)
    broken = []
    for k in range(len(reply)):
        broken.append(reply[:k] + reply[k + 1 :])
        for bit in range(8):
            hit = bytearray(reply)
            hit[k] ^= 1 << bit
            broken.append(bytes(hit))
    held = 0
    for b in broken:
        for cut in range(1, len(b)):
            p = FrameParser()
            p.awaiting_reply = False  # the exception for a telegram that may have lost a byte: off
            p.feed(frame(b"\xba" + b"LMS200" + b"\x10")[2:])  # garbage before, then the broken reply
            p.feed(frame(b"\xba" + b"LMS200" + b"\x10"))
            p.feed(b[:cut])
            if not p.pending:
                continue  # nothing held back: a request onto a quiet line (docs/lms200.md, what is left)
            held += 1
            p.request_sent()
            events = p.feed(b[cut:]) + p.idle()
            assert [e for e in events if not isinstance(e, Frame)] == [], (b.hex(), cut)
    assert held > 300


def test_a_stray_byte_after_a_scan_does_not_swallow_the_nak_to_a_request_while_streaming() -> None:
    """Review 33b, case 2 (continuous mode): a good scan, one stray byte in its own read, then the
    NAK to a stop request in its own read: the parent of 9b86e73 counted the NAK, 9b86e73 did not
    (the driver did not tell the parser of requests written while streaming). Now a request
    written with nothing held back and at most MAX_STRAY bytes skipped since the last good frame
    puts the stream in step; more than that may be a broken telegram's head, and does not."""
    scan = _scan_telegram(1000)
    p = FrameParser()
    assert [e.code for e in p.feed(scan)] == [0xB0] and p.feed(b"\x33") == [] and p.resynchronising
    p.request_sent(streaming=True)
    assert p.feed(bytes([NAK])) == [NAK]  # 9b86e73: []
    p = FrameParser()
    p.feed(scan + b"\x33")
    assert p.feed(bytes([NAK])) == []  # no request written: still garbage
    for stray, counted in ((b"\x33\x44\x55", [NAK]), (b"\x33\x44\x55\x66", []), (b"\x02", [])):
        p = FrameParser()
        p.feed(scan)
        p.feed(stray)  # a trailing STX is held back: a telegram may be in flight
        p.request_sent(streaming=True)
        assert p.feed(bytes([NAK])) == counted, stray


def test_a_request_written_while_streaming_brings_back_no_handshake_from_a_header_hit() -> None:
    """The 40 header hits of a scan telegram ending in 0x15 (0x06) between good scans, fed byte by
    byte with a request written while streaming (request_sent(streaming=True)) before every byte:
    no handshake, every good scan."""
    for goods, name, broken, stream in _header_hit_streams((11, 12, 13)):
        for step in (1, 7):
            cuts = list(range(0, len(stream), step))
            if name == "STX bit 2":  # 0x02 -> 0x06 ending a read in step: an ACK, see above
                cuts = [c for c in cuts if c != len(goods[0]) + 1]
            p = FrameParser()
            events = []
            for i, j in zip(cuts, cuts[1:] + [len(stream)]):
                p.request_sent(streaming=True)
                events += p.feed(stream[i:j])
            assert [e for e in events if not isinstance(e, Frame)] == [], (name, step)
            assert [e.payload for e in events] == [g[4:-2] for g in goods], (name, step)


def test_the_last_byte_of_a_telegram_that_may_have_lost_one_is_a_nak_only_while_a_reply_is_awaited() -> None:
    """A telegram whose CRC low byte is wrong too may have lost a byte, and its last byte, ending
    the run, was taken for the NAK behind it: a corrupted scan ending in 0x15 between good scans
    read as a NAK. A NAK answers a request: with no reply awaited (the driver sets
    awaiting_reply only while it waits, and the first handshake clears it) the byte is garbage;
    while one is, or when the parser is not told (None), it is still a NAK."""
    goods = [_scan_telegram(v) for v in (11, 12)]
    victim = bytearray(_scan_telegram(217))
    victim[100] ^= 0x01
    for awaiting, handshakes in ((True, [NAK]), (None, [NAK]), (False, [])):
        for stream, frames in ((goods[0] + victim + goods[1], goods), (goods[0] + victim, goods[:1])):
            p = FrameParser()
            p.awaiting_reply = awaiting
            events = p.feed(stream)
            assert [e for e in events if not isinstance(e, Frame)] == handshakes
            assert [e.payload for e in events if isinstance(e, Frame)] == [g[4:-2] for g in frames]
            assert p.stats.bad_crc == 1

    p = FrameParser()
    p.awaiting_reply = True
    assert p.feed(bytes([ACK]) + goods[0] + victim + goods[1])[:1] == [ACK]  # the answer's handshake
    assert (p.awaiting_reply, p.stats.acks, p.stats.naks) == (False, 1, 0)  # 9b86e73: (1, 1)


def test_the_byte_right_after_a_broken_scan_of_known_length_is_the_handshake_only_there() -> None:
    """While a request waits for its handshake, a scan that failed its CRC but began in step with
    the last good scan's 5 header bytes ends at its LEN or before: the byte right after that end is
    the handshake (0x15 there: a NAK; old: garbage, the CRC low byte being wrong too). Not where
    the header differs (LEN hit: its end is unknown), not for the byte after that one, and not
    while no request waits."""
    from lms200.protocol import crc16

    good = _scan_telegram(5)
    broken = bytearray(_scan_telegram(6))
    broken[300] ^= 0x40
    assert crc16(bytes(broken[:-2])) & 0xFF != broken[-2]
    len_hit = bytearray(broken)
    len_hit[2] ^= 0x01  # LEN 0x2D7: its span takes one more byte

    def naks(stream: bytes, awaiting: bool | None, chunk: int = 4096) -> int:
        p = FrameParser()
        p.feed(good)
        p.awaiting_reply = awaiting
        for i in range(0, len(stream), chunk):
            p.feed(stream[i : i + chunk])
        return p.stats.naks

    after = bytes(broken) + b"\x15" + _scan_telegram(7)
    assert [naks(after, True, c) for c in (4096, 7, 1)] == [1, 1, 1]  # old: [0, 0, 0]
    assert naks(after, False) == 0 and naks(after, None) == 0
    assert naks(bytes(len_hit) + b"\x33\x15" + _scan_telegram(7), True) == 0
    assert naks(bytes(broken) + b"\x33\x15" + _scan_telegram(7), True) == 0
    assert naks(bytes(broken) + b"\x15\x33" + _scan_telegram(7), True) == 1  # pinned by the length, garbage after it


def test_a_nak_behind_a_telegram_that_lost_two_bytes_or_more_is_a_nak_and_loses_no_frame() -> None:
    """Left open by session 36 (docs/lms200.md, "what is left"): a telegram that began in step with
    the last good frame's 5 header bytes (its length known) but lost 2 bytes or more on the line
    reaches, by its LEN, past the NAK behind it into the next telegram; the parser skipped its STX,
    found the next telegram inside its span, took the broken one for a false start and the NAK for
    garbage (the request waited out its timeout). Such a telegram lost bytes (it never gains any),
    so it ends before the frame found in its span: the byte just before that frame is the
    handshake while a request waits for one. Hand-built from the listing's vectors (variant reply
    02 80 07 00 BB 01 B4 00 32 00 10 03 9D, mode reply 02 80 03 00 A0 00 10 16 0A) and scans."""
    variant = bytes.fromhex("02 80 07 00 BB 01 B4 00 32 00 10 03 9D")
    mode = bytes.fromhex("02 80 03 00 A0 00 10 16 0A")
    lost_two = bytes.fromhex("02 80 07 00 BB 01 B4 00 10 03 9D")  # 32 00 lost
    header_only = bytes.fromhex("02 80 07 00 BB")  # all but the header lost
    for broken in (lost_two, header_only):
        for tail in (variant, mode):
            for chunk in (64, 7, 1):
                p = FrameParser()
                assert p.feed(variant) == [Frame(0x80, variant[4:-2])]
                p.awaiting_reply = True
                stream = broken + bytes([NAK]) + tail
                events = []
                for i in range(0, len(stream), chunk):
                    events += p.feed(stream[i : i + chunk])
                assert events == [NAK, Frame(0x80, tail[4:-2])], (broken.hex(), chunk)  # old: [Frame]
                assert (p.stats.naks, p.stats.bad_crc, p.stats.skipped_bytes, p.pending) == (1, 1, len(broken), 0)
                assert p.awaiting_reply is False
    # Scans: every loss of 2..727 bytes (header kept), the NAK, then two good scans: one NAK, both scans.
    goods = [_scan_telegram(v) for v in (21, 22, 23)]
    victim = _scan_telegram(24)
    for lost in (2, 3, 17, 400, 727):
        for at in (5, 100, len(victim) - lost):
            broken = victim[:at] + victim[at + lost :]
            for chunk in (4096, 7, 1):
                p = FrameParser()
                p.feed(goods[0])
                p.awaiting_reply = True
                stream = broken + bytes([NAK]) + goods[1] + goods[2]
                events = feed_cut(p, stream, list(range(chunk, len(stream), chunk)))
                assert events == [NAK] + [Frame(0x80, g[4:-2]) for g in goods[1:]], (lost, at, chunk)  # old: no NAK
    # No request waiting, or the header differs from the last good frame's (its length unknown): garbage, as before.
    for awaiting, first in ((False, lost_two), (None, lost_two), (True, bytes.fromhex("02 80 07 00 BA 01 B4 00 10 03 9D"))):
        p = FrameParser()
        p.feed(variant)
        p.awaiting_reply = awaiting
        assert p.feed(first + bytes([NAK]) + variant) == [Frame(0x80, variant[4:-2])]
    # Without a NAK behind it, the broken telegram's last byte is no handshake (9D here) and nothing is lost.
    p = FrameParser()
    p.feed(variant)
    p.awaiting_reply = True
    assert p.feed(lost_two + mode + bytes([ACK])) == [Frame(0x80, mode[4:-2]), ACK]
