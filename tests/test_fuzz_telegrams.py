"""Property-based robustness of the LMS200 telegram stream: FrameParser + decode_scan.

Extends the fuzz of test_lms200_framing (intact frames are a subsequence of what is found) to the
whole claim: in a stream of valid telegrams with corruption inserted (garbage between telegrams,
bytes replaced inside some, truncations, a fake STX whose LEN announces up to 65535 bytes, stray
handshake bytes), whatever the chunking, every telegram the corruption did not touch is decoded
exactly, none that was touched is accepted (the CRC), and the bytes held back stay bounded."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lms200.codes import codes_to_ranges
from lms200.errors import InputError, LmsbenchError, LmsProtocolError, LmsStatusError
from lms200.framing import Frame, FrameParser
from lms200.protocol import (ACK, MAX_LEN, NAK, OVERHEAD_BYTES, REPLY_MEASURE, STX, VARIANTS, build_frame, decode_scan,
                             encode_measurement, scan_geometry, status_problem)

SETTINGS = dict(deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
MAX_HELD = MAX_LEN + OVERHEAD_BYTES  # the longest telegram: all the parser may hold back after a feed


def reply(payload: bytes) -> bytes:
    return build_frame(payload, address=0x80)


@st.composite
def telegrams(draw: st.DrawFn) -> bytes:
    """The payload of a device reply: a scan of any variant and unit with any codes (flag bits and
    special codes included), or a short reply (mode switch, variant, type string)."""
    kind = draw(st.sampled_from(["scan", "scan", "short"]))
    if kind == "scan":
        n = draw(st.sampled_from(sorted(VARIANTS.values())))
        seed = draw(st.integers(0, 2**32 - 1))
        codes = np.random.default_rng(seed).integers(0, 1 << 16, n, dtype=np.uint16)
        return encode_measurement(codes, draw(st.sampled_from(["mm", "cm"])), draw(st.integers(0, 255)))
    return draw(st.sampled_from([b"\xa0\x00\x10", b"\xbb\x01\xb4\x00\x32\x00\x10", b"\xbaLMS200;301063;V02.10 \x10"]))


@st.composite
def junk(draw: st.DrawFn) -> bytes:
    """What corruption puts between telegrams."""
    kind = draw(st.sampled_from(["bytes", "fake_stx", "handshake", "sync_bytes"]))
    if kind == "bytes":
        return draw(st.binary(min_size=1, max_size=40))
    if kind == "fake_stx":  # an STX and reply address with a LEN up to 65535 (over 812: impossible)
        length = draw(st.sampled_from([0, 1, 7, 100, 729, 811, 812, 813, 0x7FFF, 0xFFFF]) | st.integers(0, 0xFFFF))
        return bytes([STX, 0x80, length & 0xFF, length >> 8]) + draw(st.binary(max_size=12))
    if kind == "handshake":
        return bytes(draw(st.lists(st.sampled_from([ACK, NAK]), min_size=1, max_size=3)))
    return bytes(draw(st.lists(st.sampled_from([STX, 0x80, ACK, NAK, 0x00]), min_size=1, max_size=8)))


@st.composite
def touched(draw: st.DrawFn, good: bytes) -> bytes:
    """``good`` damaged: 1 to 3 bytes replaced (by different ones) or bytes removed from its end (at least 2:
    a telegram short of its last byte only is completed by the next one's STX whenever its CRC
    high byte is 0x02, which no parser can tell from a good telegram; see test_lms200_framing)."""
    f = bytearray(good)
    if draw(st.booleans()):
        for i in draw(st.sets(st.integers(0, len(f) - 1), min_size=1, max_size=3)):  # distinct: a hit undone is no hit
            f[i] ^= draw(st.integers(1, 255))
        return bytes(f)
    return bytes(f[: draw(st.integers(1, len(f) - 2))])


@st.composite
def streams(draw: st.DrawFn) -> tuple[bytes, list[bytes], list[int]]:
    parts: list[bytes] = []
    intact: list[bytes] = []
    for _ in range(draw(st.integers(1, 6))):
        if draw(st.booleans()):
            parts.append(draw(junk()))
        payload = draw(telegrams())
        good = reply(payload)
        if draw(st.integers(0, 2)) == 0:
            parts.append(draw(touched(good)))
        else:
            parts.append(good)
            intact.append(payload)
    if draw(st.booleans()):
        parts.append(draw(junk()))
    stream = b"".join(parts)
    if draw(st.booleans()):
        cuts = sorted(draw(st.lists(st.integers(0, len(stream)), max_size=8)))
    else:  # a fixed read size, as a serial port's reads come: 1 byte up to a whole telegram
        step = draw(st.sampled_from([1, 2, 3, 7, 64, 733, 4096]))
        cuts = list(range(step, len(stream), step))
    return stream, intact, cuts


def expected_scan(payload: bytes) -> tuple[np.ndarray, float, float, str]:
    count = payload[1] | (payload[2] << 8)
    n = count & 0x3FF
    units = "mm" if count >> 14 == 1 else "cm"
    codes = np.frombuffer(payload[3 : 3 + 2 * n], dtype="<u2")
    return codes_to_ranges(codes, units), *scan_geometry(n), units


@settings(max_examples=150, **SETTINGS)
@given(streams())
def test_every_untouched_telegram_is_decoded_exactly_and_no_touched_one_is_accepted(case) -> None:  # noqa: ANN001
    stream, intact, cuts = case
    p = FrameParser()
    events = []
    bounds = [0, *cuts, len(stream)]
    for lo, hi in zip(bounds[:-1], bounds[1:]):
        events += p.feed(stream[lo:hi])
        assert p.pending <= MAX_HELD  # memory stays bounded whatever arrives
        p.hides_frame()  # the driver asks this between reads: it must not change anything
    events += p.idle()
    assert p.pending <= 1  # at most a trailing STX
    frames = [e for e in events if isinstance(e, Frame)]
    assert [f.payload for f in frames] == intact  # all of them, in order, and nothing else
    assert all(e in (ACK, NAK) for e in events if not isinstance(e, Frame))
    for f in frames:
        assert stream[f.end - len(f) : f.end] == reply(f.payload)  # where it was found
        if f.code == REPLY_MEASURE and status_problem(f.payload[-1]):  # an error, implausible values
            with pytest.raises(LmsStatusError, match=r"0xB0 scan with status 0x[0-9A-F]{2}: .*: its values are not to be used"):
                decode_scan(f.payload, stamp=1.5)
        elif f.code == REPLY_MEASURE and not f.payload[2] & 0x20:
            scan = decode_scan(f.payload, stamp=1.5)
            ranges, angle_min, increment, units = expected_scan(f.payload)
            np.testing.assert_array_equal(scan.ranges, ranges)
            assert (scan.angle_min, scan.angle_increment, scan.stamp) == (angle_min, increment, 1.5)
            assert scan.range_max == {"mm": 8.183, "cm": 81.83}[units]


@settings(max_examples=200, **SETTINGS)
@given(st.binary(max_size=900) | st.builds(lambda n, body: bytes([REPLY_MEASURE, n & 0xFF, n >> 8]) + body,
                                          st.integers(0, 0xFFFF), st.binary(max_size=820)))
def test_any_payload_decodes_to_a_scan_or_is_a_protocol_error(payload: bytes) -> None:
    """decode_scan of any bytes: a Scan, or an LmsProtocolError (never an IndexError, a numpy error)."""
    try:
        scan = decode_scan(payload)
    except LmsbenchError as exc:
        assert isinstance(exc, LmsProtocolError) and not isinstance(exc, InputError), exc
        return
    n = len(scan)
    assert payload[0] == REPLY_MEASURE and len(payload) == 4 + 2 * n and not payload[2] & 0x20
    assert status_problem(payload[-1]) is None
    assert np.all(np.isnan(scan.ranges) | (scan.ranges >= 0))


@pytest.mark.parametrize("length", [812, 0xFFFF])
def test_a_flood_of_fake_headers_is_resolved_in_bounded_time_and_memory(length: int) -> None:
    """256 KiB of fake headers (STX, reply address, LEN 812: each waits for 818 bytes, and their CRC
    is computed once they have come; LEN 65535: refused at once) in 1-byte and 4 KiB reads, then a
    good telegram: the telegram is found, every fake header counted, nothing more held back."""
    fake = bytes([STX, 0x80, length & 0xFF, length >> 8]) * (1 << 16)
    good = reply(b"\xa0\x00\x10")
    for step in (1, 4096):
        p = FrameParser()
        events = []
        data = fake[: 8192] if step == 1 else fake
        for i in range(0, len(data), step):
            events += p.feed(data[i : i + step])
            assert p.pending <= MAX_HELD
        events += p.feed(good) + p.idle()
        assert events == [Frame(0x80, b"\xa0\x00\x10")]
        assert p.stats.dropped_frames == len(data) // 4 and p.pending == 0


@settings(max_examples=150, **SETTINGS)
@given(streams(), st.lists(st.sampled_from(["request", "request_streaming", "awaiting", "answered", "none"]), max_size=12))
def test_the_driver_s_request_calls_between_reads_lose_no_telegram(case, calls) -> None:  # noqa: ANN001
    """The driver tells the parser of requests between reads (``request_sent``, ``awaiting_reply``):
    handshake bookkeeping that holds bytes back, which must neither lose nor invent a telegram."""
    stream, intact, cuts = case
    p = FrameParser()
    events = []
    bounds = [0, *cuts, len(stream)]
    for j, (lo, hi) in enumerate(zip(bounds[:-1], bounds[1:])):
        call = calls[j % len(calls)] if calls else "none"
        if call == "request":
            p.request_sent()
            p.awaiting_reply = True
        elif call == "request_streaming":
            p.request_sent(streaming=True)
            p.awaiting_reply = True
        elif call == "awaiting":
            p.awaiting_reply = True
        elif call == "answered":
            p.awaiting_reply = False
        events += p.feed(stream[lo:hi])
        assert p.pending <= MAX_HELD
    events += p.idle()
    assert [e.payload for e in events if isinstance(e, Frame)] == intact
    assert all(e in (ACK, NAK) for e in events if not isinstance(e, Frame))
