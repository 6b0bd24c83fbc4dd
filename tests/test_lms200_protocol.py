"""LMS200 codec: the test vectors of SICK's listing, the CRC against a bitwise reference, 0xB0 decoding."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from lms200 import Scan
from lms200.errors import LmsProtocolError
from lms200.protocol import (
    build_frame,
    crc16,
    decode_scan,
    encode_scan,
    mode_request,
    measure_request,
    reset_request,
    type_request,
    units_of_config,
    variant_request,
    with_units,
)

# Full frames from the protocol page (docs/lms200-protocol.md), CRC last.
VECTORS = {
    "reset": "02 00 01 00 10 34 12",
    "request one scan": "02 00 02 00 30 01 31 18",
    "request type": "02 00 01 00 3A 1E 12",
    "variant 180/0.5": "02 00 05 00 3B B4 00 32 00 3B 1F",
    "variant reply": "02 80 07 00 BB 01 B4 00 32 00 10 03 9D",
    "mode switch acknowledged": "02 80 03 00 A0 00 10 16 0A",
    "installation mode": "02 00 0A 00 20 00 53 49 43 4B 5F 4C 4D 53 BE C5",
    "type reply": "02 80 17 00 BA 4C 4D 53 32 30 30 3B 33 30 31 30 36 33 3B 56 30 32 2E 31 30 20 10 22 61",
}


def reference_crc(data: bytes) -> int:
    """SICK's CRC written out bit by bit from the listing's C code (independent of the table)."""
    crc, prev = 0, 0
    for byte in data:
        top = crc & 0x8000
        crc = (crc << 1) & 0xFFFF
        if top:
            crc ^= 0x8005
        crc ^= (prev << 8) | byte
        prev = byte
    return crc


@pytest.mark.parametrize("name", list(VECTORS))
def test_listing_vectors(name: str) -> None:
    frame = bytes.fromhex(VECTORS[name])
    assert crc16(frame[:-2]) == struct.unpack("<H", frame[-2:])[0]
    assert build_frame(frame[4:-2], address=frame[1]) == frame


def test_request_builders_give_listing_frames() -> None:
    assert build_frame(reset_request()) == bytes.fromhex(VECTORS["reset"])
    assert build_frame(measure_request()) == bytes.fromhex(VECTORS["request one scan"])
    assert build_frame(type_request()) == bytes.fromhex(VECTORS["request type"])
    assert build_frame(variant_request(180, 50)) == bytes.fromhex(VECTORS["variant 180/0.5"])
    assert build_frame(mode_request(0x00)) == bytes.fromhex(VECTORS["installation mode"])


def test_crc_matches_bitwise_reference_on_random_data() -> None:
    rng = np.random.default_rng(1)
    for n in [0, 1, 2, 23, 24, 25, 100, 731, 816, 817, 818, 900]:
        data = rng.integers(0, 256, n, dtype=np.uint8).tobytes()
        assert crc16(data) == reference_crc(data), n


def test_crc_detects_every_single_bit_error_of_a_scan_frame() -> None:
    rng = np.random.default_rng(2)
    data = bytearray(rng.integers(0, 256, 726, dtype=np.uint8).tobytes())
    good = crc16(bytes(data))
    for pos in range(0, 726, 37):
        for bit in range(8):
            data[pos] ^= 1 << bit
            assert crc16(bytes(data)) != good
            data[pos] ^= 1 << bit


def test_build_frame_rejects_bad_input() -> None:
    with pytest.raises(ValueError, match="payload"):
        build_frame(b"")
    with pytest.raises(ValueError, match="payload"):
        build_frame(bytes(813))
    with pytest.raises(ValueError, match="address"):
        build_frame(b"\x10", address=256)
    with pytest.raises(ValueError, match="variant"):
        variant_request(180, 25)


def _b0(values: list[int], count_word: int) -> bytes:
    return bytes([0xB0]) + struct.pack("<H", count_word) + struct.pack(f"<{len(values)}H", *values) + b"\x10"


def test_decode_full_scan_in_mm_with_special_codes_and_flags() -> None:
    values = [1000 + i for i in range(361)]
    values[0] = 8183  # above maximum -> +inf
    values[1] = 8191  # not valid -> nan
    values[2] = 8190  # dazzling -> nan
    values[3] = 0xE000 | 2500  # field A/B/dazzle flags set on a valid 2.5 m reading
    values[4] = 8182  # largest valid reading
    payload = _b0(values, 0x4169)
    assert payload[1:3] == bytes([0x69, 0x41])  # the protocol page: 361 values in mm
    scan = decode_scan(payload, stamp=12.5)
    assert len(scan) == 361 and scan.stamp == 12.5
    assert scan.angle_min == pytest.approx(-np.pi / 2) and scan.angle_increment == pytest.approx(np.deg2rad(0.5))
    assert scan.range_max == pytest.approx(8.183)
    assert np.isposinf(scan.ranges[0]) and np.isnan(scan.ranges[1]) and np.isnan(scan.ranges[2])
    assert scan.ranges[3] == pytest.approx(2.5) and scan.ranges[4] == pytest.approx(8.182)
    assert scan.ranges[360] == pytest.approx(1.360)


def test_decode_cm_and_the_100_degree_variants() -> None:
    scan = decode_scan(_b0([250] * 181, 181), 0.0)  # units bits 00 = cm
    assert scan.ranges[0] == pytest.approx(2.5) and scan.range_max == pytest.approx(81.83)
    assert scan.angle_increment == pytest.approx(np.deg2rad(1.0))
    scan = decode_scan(_b0([100] * 401, 0x4000 | 401), 0.0)
    assert scan.angle_min == pytest.approx(np.deg2rad(-50)) and scan.angle_max == pytest.approx(np.deg2rad(50))


@pytest.mark.parametrize(
    "payload, message",
    [
        (_b0([1] * 361, 0x4168), "announces 360 values"),
        (_b0([1] * 360, 0x4168), "matches no LMS200 variant"),
        (_b0([1] * 361, 0x6169), "partial scan"),
        (_b0([1] * 361, 0x8169), "unit code 2"),
        (b"\xb1\x00\x00\x10", "not a 0xB0"),
    ],
)
def test_decode_rejects_malformed_replies(payload: bytes, message: str) -> None:
    with pytest.raises(LmsProtocolError, match=message):
        decode_scan(payload)


def test_encode_decode_round_trip_rounds_to_the_unit() -> None:
    rng = np.random.default_rng(3)
    ranges = rng.uniform(0.0, 9.0, 361)
    ranges[::17] = np.inf
    ranges[::23] = np.nan
    back = decode_scan(encode_scan(Scan.lms200(ranges), "mm")).ranges
    expected = np.where(ranges > 8.1825, np.inf, np.round(ranges, 3))
    expected[::17] = np.inf
    expected[::23] = np.nan
    np.testing.assert_allclose(back, expected, atol=1e-12)


def test_units_byte_of_the_configuration_block() -> None:
    block = bytes(range(32))
    assert units_of_config(with_units(block, "mm")) == "mm"
    assert with_units(block, "cm")[5] == 0 and with_units(block, "cm")[6:] == block[6:]
    with pytest.raises(LmsProtocolError, match="unit"):
        units_of_config(bytes([0, 0, 0, 0, 0, 7]))


@pytest.mark.parametrize("ranges, angle_min, increment, shown", [
    (np.full(181, 2.0), -np.pi / 2, np.pi / 360, "181 beams from -90 deg, 0.5 deg apart"),  # decoded as 1 deg, -90 .. +90
    (np.full(361, 2.0), -np.pi / 4, np.pi / 720, "361 beams from -45 deg, 0.25 deg apart"),  # decoded as 0.5 deg from -90
    (np.full(361, 2.0), -np.pi / 2 + 0.01, np.pi / 360, "361 beams from -89.427 deg, 0.5 deg apart"),
    (np.full(400, 2.0), -np.pi / 2, np.pi / 360, "400 beams from -90 deg, 0.5 deg apart"),  # a payload decode_scan refused
])
def test_encode_scan_refuses_a_scan_whose_geometry_the_telegram_cannot_carry(ranges, angle_min, increment, shown) -> None:
    """A 0xB0 telegram carries no angles: decode_scan takes them from the beam count. encode_scan
    wrote any scan's ranges, so a 181-beam scan at 0.5 deg came back spanning twice its angle,
    silently; now it is an InputError naming the scan and its geometry."""
    from lms200.errors import InputError

    with pytest.raises(InputError, match=rf"^scan: {shown}, is no LMS200 variant's scan .*resample it"):
        encode_scan(Scan(ranges, angle_min, increment, 0.0, 8.0))


def test_encode_scan_takes_every_variant_float32_angles_included() -> None:
    """The five variants' geometries, also as a bag's float32 angles, encode and decode to their
    beam count and angles."""
    for n, (fov, res) in [(181, (180, 100)), (361, (180, 50)), (101, (100, 100)), (201, (100, 50)), (401, (100, 25))]:
        amin, inc = np.deg2rad(-fov / 2), np.deg2rad(res / 100)
        for a, i in ((amin, inc), (float(np.float32(amin)), float(np.float32(inc)))):
            back = decode_scan(encode_scan(Scan(np.full(n, 2.5), a, i, 0.0, 8.0)))
            assert len(back) == n and back.angle_min == pytest.approx(amin, abs=1e-12)
            assert back.angle_increment == pytest.approx(inc, rel=1e-12) and (back.ranges == 2.5).all()


@pytest.mark.parametrize("status, problem", [
    (0x13, "status 0x13: an error"), (0x14, "status 0x14: a fatal error"), (0x16, "status 0x16: undefined level 6"),
    (0x50, "status 0x50: implausible measured values"), (0xD4, "status 0xD4: a fatal error and implausible measured values"),
])
def test_a_scan_whose_status_byte_says_its_values_are_not_to_be_used_is_refused(status: int, problem: str) -> None:
    """Found by fuzzing: decode_scan took the values of a scan whose STATUS byte (bits 0-2: 0 ok,
    1 info, 2 warning, 3 error, 4 fatal; bit 6 implausible values) said they were not to be used."""
    from lms200.errors import LmsStatusError
    from lms200.protocol import encode_measurement

    payload = encode_measurement(np.full(181, 1000, np.uint16), "mm", status)
    with pytest.raises(LmsStatusError, match=f"^0xB0 scan with {problem}: its values are not to be used$") as info:
        decode_scan(payload)
    assert isinstance(info.value, LmsProtocolError)
    for fine in (0x10, 0x11, 0x12, 0x90, 0x00):  # ok, info, warning, pollution (a dirty front screen), no flag
        assert decode_scan(encode_measurement(np.full(181, 1000, np.uint16), "mm", fine)).ranges[0] == 1.0
