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
from lms200.framing import FrameParser
from lms200 import noise, protocol, tum, virtual
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
    (lambda: protocol.frame_seconds(10**400, 9600), r"^n_bytes: must be a finite number >= 0, got an int beyond"),  # OverflowError
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
    # fuzz round 8: FrameParser's arguments (300 bytes()'s ValueError, None a TypeError, a max_len of 'x' a TypeError
    # at the first feed, of 0 or -3 a parser that dropped every frame as too long, silently)
    (lambda: FrameParser(address=300), r"^address: must be an integer in 0\.\.255 \(the reply address byte"),
    (lambda: FrameParser(address=None), r"^address: must be an integer in 0\.\.255 .* got None$"),
    (lambda: FrameParser(max_len=0), r"^max_len: must be an integer in 1\.\.65535 \(the largest LEN .* got 0$"),
    (lambda: FrameParser(max_len="x"), r"^max_len: must be an integer in 1\.\.65535 .* got 'x'$"),
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


def test_codec_and_virtual_device_take_again_what_worked_before_the_checks() -> None:
    """A review of b538d7c / 1bebcfd found valid calls refused that worked on f45cc33 (before the
    checks): a count as a whole float, an array or Fraction of bytes, a whole float baud, a list
    variant, (1, 361) ranges, a password as a list or tuple of ints, a source with only
    __getitem__. Each now gives the old result, computed here from the formulas."""
    from fractions import Fraction

    seconds = protocol.frame_seconds(np.array([10, 20]), 9600)
    assert isinstance(seconds, np.ndarray) and seconds.tolist() == [100.0 / 9600, 200.0 / 9600]
    assert protocol.frame_seconds(Fraction(1, 2), 9600) == 5.0 / 9600
    assert protocol.frame_seconds(10, 9600.0) == 100.0 / 9600
    half_deg = (-math.pi / 2, math.radians(0.5))
    assert protocol.scan_geometry(361.0) == pytest.approx(half_deg, rel=1e-15)
    assert beam_angles(361.0) == pytest.approx(half_deg, rel=1e-15)
    n = round(2 * 38400 / 9600)  # garble's stream: as many bytes as bit times fit, byte k from data[k % 2]
    expected = bytes((b"ab"[k % 2] * 37 + 0x5B + k) & 0xFF for k in range(n)).replace(b"\x02", b"\xfd")
    assert virtual.garble(b"ab", 9600.0, 38400) == expected == b"`\x86b\x88d\x8af\x8c"
    assert virtual.garble(b"ab", 9600.0, 9600.0) == b"ab"
    ranges = np.linspace(1.0, 5.0, 361)  # 1 m to 5 m by 1.111 cm
    cm = np.round(ranges * 100).astype(np.uint16)
    assert virtual.variant_codes(ranges, [180, 50], "cm").tolist() == cm.tolist()
    row = virtual.variant_codes(ranges.reshape(1, 361), (180, 50), "cm")
    assert row.shape == (1, 361) and row[0].tolist() == cm.tolist()
    assert virtual.variant_codes(ranges.reshape(1, 361), (180, 100), "cm").tolist() == [cm[::2].tolist()]
    installation = bytes([0x20, 0x00]) + b"SICK_LMS"
    assert protocol.mode_request(0, list(b"SICK_LMS")) == protocol.mode_request(0, tuple(b"SICK_LMS")) == installation

    class OldStyle:  # the sequence protocol: iter() walks it by index until IndexError
        def __getitem__(self, i: int) -> Scan:
            return [SCAN][i]

    dev = virtual.VirtualLMS200(OldStyle())
    dev.receive(protocol.build_frame(protocol.measure_request()), 0.0)
    sent = b"".join(chunk for chunk, _ in dev.transmit(10.0))
    assert sent[:1] == bytes([protocol.ACK]) and len(sent) == 1 + 732
    # what the checks were for stays refused: bool, 2.5 as a count, 0 baud (an empty payload too), nan, text
    for call, message in [
        (lambda: protocol.frame_seconds(True, 9600), r"^n_bytes: must be a finite number >= 0, got True$"),
        (lambda: protocol.frame_seconds(np.array([10, -1]), 9600), r"^n_bytes: must be >= 0 \(bytes\)"),
        (lambda: protocol.frame_seconds(np.array([10, np.nan]), 9600), r"^n_bytes: must be finite"),
        (lambda: protocol.frame_seconds(np.array(["a"]), 9600), r"^n_bytes: must be a \(k, 1\) array of real numbers"),
        (lambda: protocol.scan_geometry(361.5), r"^n_values: must be an integer >= 0, got 361\.5$"),
        (lambda: protocol.scan_geometry(math.nan), r"^n_values: must be an integer >= 0, got nan$"),
        (lambda: beam_angles(True), r"^n: must be an integer .* got True$"),
        (lambda: virtual.garble(b"", 0, 0), r"^baud_sent: must be an integer >= 1, got 0$"),
        (lambda: virtual.garble(b"ab", 9600.5, 9600), r"^baud_sent: must be an integer >= 1, got 9600\.5$"),
        (lambda: virtual.variant_codes(ranges, [180, 50.5], "cm"), r"^variant: \[180, 50\.5\] is not an LMS200 variant"),
        (lambda: virtual.variant_codes(ranges.reshape(19, 19), (180, 50), "cm"), r"^ranges: must be the 361 ranges"),
        (lambda: protocol.mode_request(True), r"^sub_command: must be an integer in 0\.\.255, got True$"),
        (lambda: protocol.mode_request(0, [83] * 7 + [256]), r"^password: must be bytes"),
        (lambda: protocol.mode_request(0, "SICK_LMS"), r"^password: must be bytes"),
        (lambda: protocol.build_frame(b"1", address=True), r"^address: must be an integer in 0\.\.255, got True$"),
        (lambda: protocol.build_frame(b"1", address=2.0), r"^address: must be an integer in 0\.\.255, got 2\.0$"),
        (lambda: virtual.VirtualLMS200(b"abc"), r"^source: must be an iterable of lms200\.Scan, got bytes$"),
    ]:
        with pytest.raises(InputError, match=message):
            call()


# -- lms200.noise, lms200.tum ----------------------------------------------------------------------
@pytest.mark.parametrize("call, message", [
    (lambda: noise.estimate_quantum("abc"), r"^ranges: must be a \(k, 1\) array of real numbers"),  # numpy's ValueError
    (lambda: noise.robust_scale(b"\x00\x01"), r"^z: must be a \(k, 1\) array of real numbers"),
    (lambda: noise.interlace_stride(None), r"^angle_increment: must be a finite number in \(0, 6\.28319\] rad, got None$"),
    (lambda: noise.interlace_stride(0.0), r"^angle_increment: must be a finite number in \(0, 6\.28319\] rad, got 0\.0$"),  # OverflowError
    (lambda: noise.line_residuals("abc", 0.01), r"^ranges: must be real numbers"),
    (lambda: noise.line_residuals(np.ones((2, 361)), 0.01), r"^ranges: must be 1-D \(the ranges of one scan, m\), got shape \(2, 361\)$"),
    (lambda: noise.line_residuals(SCAN.ranges, 10**400), r"^angle_increment: must be a finite number .* got an int beyond"),
    (lambda: noise.line_residuals(SCAN.ranges, 0.01, range_min=None), r"^range_min: must be a finite number >= 0 m, got None$"),
    (lambda: noise.line_residuals(SCAN.ranges, 0.01, range_max="8"), r"^range_max: must be a number >= 0 m, got '8'$"),
    (lambda: noise.line_residuals(SCAN.ranges, 0.01, stride=0), r"^stride: must be an integer >= 1 \(beams\), got 0$"),  # broadcast error
    (lambda: noise.line_residuals(SCAN.ranges, 0.01, stride=-1), r"^stride: must be an integer >= 1"),
    (lambda: noise.line_residuals(SCAN.ranges, 0.01, stride=2.5), r"^stride: must be an integer >= 1 \(beams\), got 2\.5$"),  # taken as 2
    (lambda: noise.estimate_range_noise(SCAN, max_range=0.0), r"^min_range, max_range: the band \[min_range, max_range\) is empty"),
    (lambda: noise.estimate_range_noise(SCAN, min_range=math.inf), r"^min_range, max_range: the band"),
    (lambda: tum.quaternion_to_yaw(None), r"^q: must be a \(k, 4\) array of real numbers"),  # not enough values to unpack
    (lambda: tum.quaternion_to_yaw([0.0, 0.0, 1.0]), r"^q: must be a \(k, 4\) array .* got shape \(1, 3\)$"),
    (lambda: tum.quaternion_to_yaw("abcd"), r"^q: must be a \(k, 4\) array of real numbers"),
    (lambda: tum.yaw_to_quaternion("a"), r"^theta: must be a \(k, 1\) array of real numbers"),  # numpy's ValueError
])
def test_noise_and_tum_helpers_name_the_bad_argument(call, message: str) -> None:
    with pytest.raises(InputError, match=message) as info:
        call()
    assert "\n" not in str(info.value)


def test_noise_and_tum_helpers_keep_their_valid_inputs() -> None:
    """Same numbers as before for valid inputs: a list, a float32 array, the default stride, an
    infinite range_max, quaternions of any norm and shape (4,) or (n, 4)."""
    rng = np.random.default_rng(1)
    ranges = 3.0 + rng.normal(0, 0.01, 361)
    z, r0, centre = noise.line_residuals(list(ranges), math.pi / 360)
    assert z.size == r0.size == centre.size > 300 and noise.interlace_stride(math.pi / 360) == 2
    assert np.array_equal(noise.line_residuals(ranges, math.pi / 360, 0.0, math.inf, 2)[0], z)
    assert noise.robust_scale(z)[1] == pytest.approx(0.01, rel=0.2)
    assert noise.estimate_quantum(np.round(ranges, 2).astype(np.float32)) == 0.01
    assert noise.estimate_range_noise(Scan.lms200(ranges), min_range=1.0, max_range=5.0).sigma_m == pytest.approx(0.01, rel=0.2)
    assert tum.quaternion_to_yaw([0, 0, 1, 1]) == pytest.approx([math.pi / 2])
    assert tum.quaternion_to_yaw(np.array([[0, 0, 0, 1.0], [0, 0, 0, 0]])).tolist()[0] == 0.0
    assert np.isnan(tum.quaternion_to_yaw([0, 0, 0, 0])[0])  # no rotation: nan, as documented
    assert tum.yaw_to_quaternion(0.0).tolist() == [[0.0, 0.0, 0.0, 1.0]]


# -- configuration telegrams, the virtual device's clock, timing and faults --------------------------
TELEGRAM = protocol.build_frame(protocol.measure_request())


def _device(**kw: object) -> virtual.VirtualLMS200:
    return virtual.VirtualLMS200([SCAN], time_scale=0.01, **kw)  # type: ignore[arg-type]


@pytest.mark.parametrize("call, message", [
    (lambda: protocol.set_config_request(5), r"^config: must be bytes .* got int$"),  # was 5 zero bytes, silently
    (lambda: protocol.set_config_request("abc"), r"^config: must be bytes .* got str$"),  # TypeError
    (lambda: protocol.with_units(None, "mm"), r"^config: must be bytes .* got NoneType$"),  # TypeError
    (lambda: protocol.units_of_config("abcdefg"), r"^config: must be bytes .* got str$"),  # AttributeError
    (lambda: _device().receive(TELEGRAM, None), r"^now: must be a finite number in \[-1e\+12, 1e\+12\] s, got None$"),  # TypeError
    (lambda: _device().receive(TELEGRAM, 10**400), r"^now: must be a finite number in .* got an int beyond"),  # OverflowError
    (lambda: _device().transmit(math.inf), r"^now: must be a finite number in \[-1e\+12, 1e\+12\] s, got inf$"),  # OverflowError
    (lambda: _device().transmit(1e308), r"^now: must be a finite number in \[-1e\+12, 1e\+12\] s, got 1e\+308$"),  # int(inf)
    (lambda: _device().transmit("1"), r"^now: must be a finite number in .* got '1'$"),  # TypeError
    (lambda: _device().next_wakeup(None), r"^now: must be a finite number in .* got None$"),
    (lambda: _device(faults=0.5), r"^faults: must be a lms200\.Faults or None, got float$"),  # AttributeError: seed
    (lambda: _device(timing="fast"), r"^timing: must be a lms200\.DeviceTiming or None, got str$"),
    (lambda: virtual.DeviceTiming(ack_s=None), r"^ack_s: must be a finite number in \[0, 3600\] s, got None$"),  # TypeError later
    (lambda: virtual.DeviceTiming(reset_s=10**400), r"^reset_s: must be a finite number in \[0, 3600\] s, got an int beyond"),
    (lambda: virtual.Faults(corrupt_prob="0.1"), r"^corrupt_prob: must be a finite number in \[0, 1\], got '0\.1'$"),  # UFuncTypeError
    (lambda: virtual.Faults(drop_prob=2.0), r"^drop_prob: must be a finite number in \[0, 1\], got 2\.0$"),
    (lambda: virtual.Faults(seed=-1), r"^seed: must be a whole number >= 0, got -1$"),
])
def test_config_telegrams_and_device_clock_name_the_bad_argument(call, message: str) -> None:
    with pytest.raises(InputError, match=message) as info:
        call()
    assert "\n" not in str(info.value)


def test_device_keeps_its_valid_clock_timing_and_faults() -> None:
    dev = _device(timing=virtual.DeviceTiming(ack_s=0, reply_s=np.float32(0.01)), faults=virtual.Faults(miss_prob=0, seed=np.int64(2)))
    dev.receive(TELEGRAM, np.float64(0.0))
    assert dev.next_wakeup(0) is not None
    assert b"".join(piece for piece, _ in dev.transmit(10)).startswith(bytes([protocol.ACK, protocol.STX]))
    block = protocol.with_units(bytearray(32), "mm")
    assert protocol.units_of_config(memoryview(block)) == "mm" and protocol.set_config_request(block)[1:] == block


def _set(record: object, name: str, value: object) -> None:
    setattr(record, name, value)


@pytest.mark.parametrize("record, name, value, message", [
    (virtual.Faults, "corrupt_prob", 2, r"^corrupt_prob: must be a finite number in \[0, 1\], got 2$"),  # every byte hit
    (virtual.Faults, "drop_prob", math.nan, r"^drop_prob: must be a finite number in \[0, 1\], got nan$"),
    (virtual.Faults, "mute", "no", r"^mute: must be True or False, got 'no'$"),  # muted the device
    (virtual.Faults, "seed", -1, r"^seed: must be a whole number >= 0, got -1$"),
    (virtual.Faults, "corupt_prob", 0.1, r"^Faults has no field 'corupt_prob' \(did you mean corrupt_prob\?\)$"),
    (virtual.DeviceTiming, "ack_s", -1, r"^ack_s: must be a finite number in \[0, 3600\] s, got -1$"),
    (virtual.DeviceTiming, "reply", 0.1, r"^DeviceTiming has no field 'reply' \(did you mean reply_s\?\)$"),
])
def test_faults_and_timing_changed_on_a_running_device_are_checked(record, name: str, value: object, message: str) -> None:
    """The fields of Faults are meant to be changed while a device runs (its docstring): a value
    set later was not checked (``corrupt_prob = 2`` corrupted every byte, ``mute = "no"`` muted
    the device, a misspelt name was a new attribute nothing read), and the field keeps its value."""
    held = record()
    dev = _device(**{"faults" if record is virtual.Faults else "timing": held})
    before = repr(held)
    with pytest.raises(InputError, match=message):
        _set(held, name, value)
    assert repr(held) == before and not hasattr(held, "corupt_prob") and not hasattr(held, "reply")
    valid = {"corrupt_prob": 0.25, "drop_prob": 0.5, "mute": True, "seed": 7, "ack_s": 0.01}
    if name in valid:  # a valid value is taken, and is what the device reads
        _set(held, name, valid[name])
        assert getattr(dev.faults if record is virtual.Faults else dev.timing, name) == valid[name]
    for quiet in (np.bool_(False), 0, 0.0, None, 1):  # what worked before the checks still does
        dev.faults.mute = quiet
        assert dev.faults.mute is quiet


def test_faults_checks_leave_subclass_fields_private_names_and_given_values_alone() -> None:
    """A review of the checks above: a subclass's own field was checked as a probability
    (``MyFaults(burst=3)`` refused), a private attribute refused, values stored as floats (a
    Fraction or 0 changed type), ``mute=None`` refused; and ``del faults.mute`` passed, to fail
    at the device's next read. Now as before the checks, and deleting a field is an InputError."""
    import dataclasses
    import fractions

    @dataclasses.dataclass
    class BurstFaults(virtual.Faults):
        burst: int = 3

    faults = BurstFaults(corrupt_prob=fractions.Fraction(1, 4), mute=None, burst=30)
    faults._note = "kept"
    assert (faults.burst, faults._note, faults.mute) == (30, "kept", None)
    assert type(faults.corrupt_prob) is fractions.Fraction and repr(virtual.Faults(drop_prob=0)).startswith(
        "Faults(corrupt_prob=0.0, drop_prob=0,")
    with pytest.raises(InputError, match=r"^drop_prob: must be a finite number in \[0, 1\], got 3$"):
        faults.drop_prob = 3
    with pytest.raises(InputError, match=r"^BurstFaults has no field 'brust' \(did you mean burst\?\)$"):
        faults.brust = 3
    with pytest.raises(InputError, match=r"^Faults\.mute cannot be deleted; set it to another value$"):
        del virtual.Faults().mute
    timing = virtual.DeviceTiming()
    with pytest.raises(InputError, match=r"^DeviceTiming\.ack_s cannot be deleted"):
        del timing.ack_s
    assert dataclasses.replace(faults, seed=4).seed == 4 and dataclasses.asdict(timing)["reply_s"] == 0.01


def test_a_configuration_block_given_as_a_list_of_bytes_is_sent_as_before() -> None:
    """``set_config_request([0] * 32)`` and ``with_units(list, 'cm')`` worked before the checks of
    b538d7c (a second review found them refused): a list of integers 0..255 is bytes again; a
    list holding 256 or text is still an InputError naming ``config``."""
    from lms200.errors import InputError
    from lms200.protocol import CONFIG_UNITS_OFFSET, UNITS_CODES, set_config_request, with_units

    block = list(range(32))
    assert set_config_request(block) == bytes([0x77]) + bytes(block)
    assert set_config_request(tuple(block)) == set_config_request(bytes(block))
    cm = with_units(block, "cm")
    assert cm[CONFIG_UNITS_OFFSET] == UNITS_CODES["cm"] and len(cm) == 32
    for bad in ([256] * 32, ["a"] * 32, "abc", None):
        with pytest.raises(InputError, match=r"^config: must be bytes"):
            set_config_request(bad)


@pytest.mark.parametrize("make, message", [
    (lambda a: a.PtyAdapter(None), r"^device: must be an lms200\.virtual\.VirtualLMS200, got NoneType$"),  # thread died, AttributeError at close
    (lambda a: a.TcpServer("x"), r"^device: must be an lms200\.virtual\.VirtualLMS200, got str$"),
    (lambda a: a.PtyAdapter(virtual.VirtualLMS200([SCAN]), clock=5), r"^clock: must be a function giving seconds, got 5$"),
    (lambda a: a.TcpServer(virtual.VirtualLMS200([SCAN]), None), r"^host: must be an address or a host name"),  # AttributeError
    (lambda a: a.TcpServer(virtual.VirtualLMS200([SCAN]), "127.0.0.1", 99999),
     r"^port: must be an integer in 0\.\.65535 \(0: a free one\), got 99999$"),  # OverflowError from bind()
    (lambda a: a.TcpServer(virtual.VirtualLMS200([SCAN]), "127.0.0.1", True), r"^port: must be an integer .* got True$"),  # bound port 1
    (lambda a: a.TcpServer(virtual.VirtualLMS200([SCAN]), "127.0.0.1", 1.5), r"^port: must be an integer .* got 1\.5$"),  # TypeError
])
def test_adapters_name_a_bad_argument_before_they_start(make, message: str) -> None:
    from lms200 import adapters

    with pytest.raises(InputError, match=message):
        make(adapters)


def test_an_adapter_still_takes_a_numpy_port() -> None:
    from lms200.adapters import TcpServer

    with TcpServer(virtual.VirtualLMS200([SCAN]), "127.0.0.1", np.int64(0)) as adapter:
        assert adapter.url.startswith("socket://127.0.0.1:") and adapter.port > 0


def test_calibrate_scans_reads_an_endless_repeat_to_a_bound() -> None:
    """calibrate_scans(itertools.repeat(scan)) passed over each repeat of the scan before and read on
    for ever (fuzzing the Python API, 2026-12-07); now at most MAX_READ items, then the count."""
    import itertools

    from lms200.calibration import MAX_READ, calibrate_scans

    scan = Scan.lms200(np.full(361, 2.0))
    with pytest.raises(InputError, match=rf"^scans: calibrating needs at least 2 distinct scans .*got {MAX_READ} scans but "
                                         rf"only 1 distinct: {MAX_READ - 1} repeat the scan before them"):
        calibrate_scans(itertools.islice(itertools.repeat(scan), MAX_READ + 5))  # endless: the same (old code: "got 200005")


@pytest.mark.parametrize(("bound", "used"), [(20 * 1000, 20), (20 * 1000 - 1, 19)])
def test_calibrate_scans_keeps_a_bounded_number_of_beams(monkeypatch: pytest.MonkeyPatch, bound: int, used: int) -> None:
    """calibrate_scans kept up to MAX_SCANS (20,000) scans whatever their width: 2.6 GB of ranges at
    16,384 beams. It now stops at MAX_KEPT_BEAMS beams too (made 20 scans of 1,000 beams here), which
    at an LMS200's 361 beams is the scan bound itself, so no log of 361 beams or fewer changes. A scan
    that would take the beams past the bound is not kept (it was, then the bound was tested: 20 scans
    under a bound of 19,999 beams)."""
    import lms200.calibration as calibration

    assert calibration.MAX_KEPT_BEAMS == calibration.MAX_SCANS * 361
    monkeypatch.setattr(calibration, "MAX_KEPT_BEAMS", bound)
    rng = np.random.default_rng(2)
    inc = np.pi / 999
    b = -np.pi / 2 + inc * np.arange(1000)
    walls = np.minimum(3.0 / np.maximum(np.abs(np.cos(b)), 1e-3), 2.5 / np.maximum(np.abs(np.sin(b)), 1e-3))
    scans = (Scan(np.minimum(walls, 7.9) + 0.005 * rng.standard_normal(1000), -np.pi / 2, inc, 0.0, 8.0, stamp=0.1 * k)
             for k in range(50))
    assert calibration.calibrate_scans(scans).n_scans == used  # was 50


def test_quarter_degree_midpoints_of_too_close_and_no_return_are_not_valid_without_a_warning() -> None:
    """Fuzz round 10: a -inf (too close) beside a +inf gave the 0.25 deg midpoint -inf + inf, numpy's RuntimeWarning
    "invalid value encountered in add" at every such scan (the driver read the scans right)."""
    ranges = np.full(361, 2.0)
    ranges[10], ranges[11], ranges[20] = -np.inf, np.inf, -np.inf
    codes = virtual.variant_codes(ranges, (100, 25), "mm")  # beams 80..280 at 0.5 deg: none of these
    assert codes.tolist() == [2000] * 401
    codes = virtual.variant_codes(np.roll(ranges, 80), (100, 25), "mm")  # beam 90 = -inf, 91 = +inf, 100 = -inf
    assert codes[[20, 21, 22, 39, 40, 41]].tolist() == [8191, 8191, 8183, 8191, 8191, 8191]


@pytest.mark.parametrize("field", ["angle_min", "angle_increment", "range_min", "range_max", "stamp"])
def test_a_masked_scalar_field_of_a_scan_is_refused_as_masked_without_numpys_warning(field: str) -> None:
    """Probe 14: Scan(..., angle_min=np.ma.masked) printed numpy's 'UserWarning: Warning: converting a masked
    element to nan.' and then said 'angle_min: must be finite, got nan', a value no one gave. Now one
    ScanError saying it is masked, no warning; an unmasked masked scalar is its value, as before."""
    import warnings

    from lms200 import Scan
    from lms200.errors import ScanError

    kw: dict = dict(angle_min=-np.pi / 2, angle_increment=np.pi / 360, range_min=0.0, range_max=8.183, stamp=0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for masked in (np.ma.masked, np.ma.masked_array(1.0, mask=True)):
            with pytest.raises(ScanError, match=rf"^{field}: must be a number, got a masked value \(it has none\)$"):
                Scan(np.full(361, 2.0), **{**kw, field: masked})
        scan = Scan(np.full(361, 2.0), **{**kw, field: np.ma.masked_array(kw[field])})
    assert getattr(scan, field) == kw[field]


def test_a_masked_array_of_several_values_as_a_scalar_field_is_named_so() -> None:
    """A review: Scan(angle_min=np.ma.array([1., 2.], mask=[True, False])) said "got a masked value (it
    has none)": it is a masked array of 2 values, which has a value (numpy's repr was several lines)."""
    from lms200 import Scan
    from lms200.errors import ScanError

    kw: dict = dict(angle_increment=np.pi / 360, range_min=0.0, range_max=8.183)
    for value, n in ((np.ma.array([1.0, 2.0], mask=[True, False]), 2), (np.ma.array([1.0, 2.0, 3.0]), 3),
                     (np.ma.array([], dtype=float), 0)):
        with pytest.raises(ScanError, match=rf"^angle_min: must be a number, got a masked array of {n} values$"):
            Scan(np.full(361, 2.0), angle_min=value, **kw)
    with pytest.raises(ScanError, match=r"^angle_min: must be a number, got a masked value \(it has none\)$"):
        Scan(np.full(361, 2.0), angle_min=np.ma.array([1.0], mask=[True]), **kw)
