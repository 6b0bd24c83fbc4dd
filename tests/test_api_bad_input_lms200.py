"""Bad input to lms200's codec, virtual device and geometry helpers (the API hunt of 2026-12-04,
session 33): each user error is an ``InputError`` (an ``LmsbenchError``) whose message names the
argument and what it must be, never Python's TypeError / ZeroDivisionError / OverflowError,
struct's error or numpy's ambiguous-truth ValueError."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lms200 import LmsbenchError, Scan
from lms200.errors import InputError, LmsProtocolError
from lms200 import protocol, virtual
from lms200.laser_geometry import LaserGeometry, beam_angles

SCAN = Scan.lms200(np.full(361, 3.0))


@pytest.mark.parametrize("call, message", [
    (lambda: protocol.build_frame(b"\x20", 2.5), r"^address: must be an integer in 0\.\.255, got 2\.5$"),  # struct.error
    (lambda: protocol.build_frame(b"\x20", None), r"^address: must be an integer in 0\.\.255, got None$"),  # TypeError
    (lambda: protocol.build_frame(b"\x20", [1]), r"^address: must be an integer"),
    (lambda: protocol.mode_request(0.0), r"^sub_command: must be an integer in 0\.\.255, got 0\.0$"),  # TypeError
    (lambda: protocol.mode_request("a"), r"^sub_command: must be an integer"),
    (lambda: protocol.mode_request(0, password=5), r"^password: must be bytes"),  # TypeError: len() of an int
    (lambda: protocol.baud_request([9600]), r"^baud: the LMS200 supports \[9600, 19200, 38400, 500000\], got \[9600\]$"),
    (lambda: protocol.variant_request([180], 50), r"^variant: \(\[180\] deg, 50 hundredths of a deg\) is not an LMS200 variant"),
    (lambda: protocol.variant_request(180.0, 50), r"^variant: \(180\.0 deg"),  # passed, then struct.error
    (lambda: protocol.scan_geometry([361]), r"^n_values: must be an integer >= 0, got \[361\]$"),  # unhashable
    (lambda: protocol.encode_scan(None), r"^scan: must be an lms200\.Scan, got NoneType$"),  # AttributeError
    (lambda: protocol.encode_scan(SCAN, units=["mm"]), r"^units: must be 'mm' or 'cm', got \['mm'\]$"),  # unhashable
    (lambda: protocol.encode_measurement(np.zeros(3, np.uint16), np.array(["mm"])), r"^units: must be 'mm' or 'cm'"),
    (lambda: protocol.frame_seconds(10, 0), r"^baud: must be a finite number > 0, got 0$"),  # ZeroDivisionError
    (lambda: protocol.frame_seconds(None, 9600), r"^n_bytes: must be a finite number >= 0, got None$"),  # TypeError
    (lambda: protocol.frame_seconds(10**400, 9600), r"^n_bytes: must be a finite number >= 0, got a int beyond"),  # OverflowError
    (lambda: beam_angles(0), r"^n: must be an integer in 1\.\.2147483648 \(beams\), got 0$"),  # a plain ValueError
    (lambda: beam_angles(None), r"^n: must be an integer"),  # TypeError
    (lambda: beam_angles(10**400), r"^n: must be an integer .* got 1000"),  # OverflowError
    (lambda: virtual.resample_to_grid(None), r"^scan: must be an lms200\.Scan, got NoneType$"),  # TypeError: len()
    (lambda: virtual.resample_to_grid(np.ones(361)), r"^scan: must be an lms200\.Scan, got ndarray$"),
    (lambda: virtual.variant_codes(np.ones(361), 180, "mm"), r"^variant: 180 is not an LMS200 variant"),  # cannot unpack
    (lambda: virtual.variant_codes("abc", (180, 50), "mm"), r"^ranges: must be real numbers"),  # numpy's ValueError
    (lambda: virtual.variant_codes(np.ones(360), (180, 50), "mm"), r"^ranges: must be the 361 ranges .* got shape \(360,\)$"),
    (lambda: virtual.VirtualLMS200(None), r"^source: must be an iterable of lms200\.Scan, got NoneType$"),  # not iterable
    (lambda: virtual.VirtualLMS200(3.0), r"^source: must be an iterable of lms200\.Scan, got float$"),
    (lambda: virtual.VirtualLMS200([SCAN]).receive("abc", 0.0), r"^data: must be bytes .* got str$"),  # TypeError
    (lambda: virtual.VirtualLMS200([SCAN]).receive(np.array([1.0]), 0.0), r"^data: must be bytes .* got ndarray$"),
    (lambda: virtual.garble(b"abc", 0, 9600), r"^baud_sent: must be an integer >= 1, got 0$"),  # ZeroDivisionError
    (lambda: virtual.garble(b"abc", 9600, None), r"^baud_read: must be an integer >= 1, got None$"),  # TypeError
    (lambda: virtual.garble(b"abc", 5e-324, 9600), r"^baud_sent: must be an integer >= 1, got 5e-324$"),  # OverflowError
    (lambda: virtual.garble("abc", 9600, 19200), r"^data: must be bytes"),
])
def test_codec_and_virtual_device_name_the_bad_argument(call, message: str) -> None:
    with pytest.raises(InputError, match=message) as info:
        call()
    assert isinstance(info.value, LmsbenchError) and "\n" not in str(info.value)


def test_codec_and_virtual_device_keep_their_valid_inputs() -> None:
    """The checks refuse nothing that worked: numpy ints, 9600.0 for a baud request, an unknown
    beam count is still the protocol's error, a beam-count mismatch still a ValueError."""
    assert protocol.build_frame(b"\x20", np.int64(3))[:2] == b"\x02\x03"
    assert protocol.baud_request(9600.0) == protocol.baud_request(9600) == bytes([0x20, 0x42])
    assert protocol.mode_request(np.uint8(0x25)) == bytes([0x20, 0x25])
    assert protocol.frame_seconds(1, 9600) == pytest.approx(10 / 9600)
    assert protocol.scan_geometry(np.int64(181)) == pytest.approx((-math.pi / 2, math.pi / 180))
    with pytest.raises(LmsProtocolError, match="362 values matches no LMS200 variant"):
        protocol.scan_geometry(362)
    assert beam_angles(np.int64(361)) == pytest.approx((-math.pi / 2, math.pi / 360))
    with pytest.raises(ValueError, match="span more than 360 deg"):
        beam_angles(1000, LaserGeometry(resolution=math.radians(1)))
    assert virtual.garble(b"abc", 9600, 9600) == b"abc" and len(virtual.garble(b"abcdef", 9600, 19200)) == 12
    assert virtual.variant_codes(virtual.resample_to_grid(SCAN), (180, 100), "mm").tolist() == [3000] * 181
    dev = virtual.VirtualLMS200(iter([SCAN]))
    dev.receive(bytearray(), 0.0)
    dev.receive(protocol.build_frame(protocol.measure_request()), 0.0)
    sent = b"".join(chunk for chunk, _ in dev.transmit(10.0))
    assert sent[:1] == bytes([protocol.ACK]) and len(sent) == 1 + 732  # ACK, then the 361-value 0xB0 frame
