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
    assert out == [0x15, Frame(0x80, b"\xb0\x01\x00\x10")]  # the NAK amid garbage is garbage
    assert p.stats.bad_crc == 1 and p.stats.bad_length == 1 and p.stats.naks == 1


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
            if kind == "truncated":
                f = f[: draw(st.integers(1, len(f) - 1))]
            else:
                i = draw(st.integers(0, len(f) - 1))
                f[i] ^= 1 << draw(st.integers(0, 7))
            parts.append(bytes(f))
    stream = b"".join(parts)
    cuts = sorted(draw(st.lists(st.integers(0, len(stream)), max_size=6)))
    return stream, intact, cuts


def is_subsequence(needles: list[bytes], haystack: list[bytes]) -> bool:
    it = iter(haystack)
    return all(any(n == h for h in it) for n in needles)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(streams())
def test_fuzz_every_intact_frame_is_recovered(case) -> None:  # noqa: ANN001
    stream, intact, cuts = case
    p = FrameParser()
    events = []
    bounds = [0, *cuts, len(stream)]
    for lo, hi in zip(bounds[:-1], bounds[1:]):
        events += p.feed(stream[lo:hi])
    events += p.idle()
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
    # A good frame inside a failed candidate's span proves that candidate false: its span is no telegram.
    good = frame(b"\xa0\x00\x10")
    false_start = bytes([0x02, 0x80, 0x0A, 0x00, 0x00])  # LEN 10 spans the ACK and part of the reply
    p = FrameParser()
    assert p.feed(false_start + bytes([ACK]) + good + bytes(8)) == [ACK, Frame(0x80, b"\xa0\x00\x10")]


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
