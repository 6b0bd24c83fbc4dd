"""The virtual LMS200 as a state machine on a simulated clock: replies, pacing, units, faults."""

from __future__ import annotations

import numpy as np
import pytest

from lms200 import Scan
from lms200.codes import ranges_to_codes
from lms200.framing import Frame, FrameParser
from lms200.protocol import (
    ACK,
    NAK,
    build_frame,
    decode_scan,
    get_config_request,
    measure_request,
    mode_request,
    set_config_request,
    type_request,
    variant_request,
    with_units,
)
from lms200.virtual import Faults, VirtualLMS200, garble


def scans(n: int = 20, seed: int = 0) -> list[Scan]:
    rng = np.random.default_rng(seed)
    return [Scan.lms200(rng.uniform(0.2, 8.0, 361)) for _ in range(n)]


class Host:
    """Drives a device on a simulated clock and parses what it sends, with arrival times."""

    def __init__(self, device: VirtualLMS200) -> None:
        self.dev, self.t, self.parser = device, 0.0, FrameParser()
        self.events: list[tuple[float, object]] = []

    def send(self, payload: bytes, address: int = 0) -> None:
        self.dev.receive(build_frame(payload, address), self.t)

    def run(self, seconds: float, step: float = 0.0005) -> list[object]:
        start = len(self.events)
        end = self.t + seconds
        while self.t < end:
            self.t += step
            for data, _baud in self.dev.transmit(self.t):
                self.events += [(self.t, e) for e in self.parser.feed(data)]
        return [e for _, e in self.events[start:]]


def test_replies_are_the_listing_frames() -> None:
    host = Host(VirtualLMS200(scans()))
    host.send(type_request())
    host.send(variant_request(180, 50))
    host.send(mode_request(0x25))
    events = host.run(0.3)
    frames = [build_frame(e.payload, e.address) for e in events if isinstance(e, Frame)]
    assert events[0] == ACK and events.count(ACK) == 3
    assert frames == [
        bytes.fromhex("02 80 17 00 BA 4C 4D 53 32 30 30 3B 33 30 31 30 36 33 3B 56 30 32 2E 31 30 20 10 22 61"),
        bytes.fromhex("02 80 07 00 BB 01 B4 00 32 00 10 03 9D"),
        bytes.fromhex("02 80 03 00 A0 00 10 16 0A"),
    ]


def test_nak_on_bad_crc_and_silence_for_another_address() -> None:
    host = Host(VirtualLMS200(scans()))
    bad = bytearray(build_frame(type_request()))
    bad[-1] ^= 0xFF
    host.dev.receive(bytes(bad), 0.0)
    assert host.run(0.1) == [NAK]
    host.send(type_request(), address=5)
    assert host.run(0.1) == []
    host.send(b"\x55")  # no such command: 0x92 in a correct frame
    assert [e.code for e in host.run(0.1) if isinstance(e, Frame)] == [0x92]


def test_requested_scan_carries_the_source_in_the_current_units() -> None:
    source = scans(3)
    host = Host(VirtualLMS200(source, units="cm"))
    host.send(measure_request())
    (reply,) = [e for e in host.run(1.0) if isinstance(e, Frame)]
    assert reply.payload[2] >> 6 == 0  # cm
    np.testing.assert_array_equal(ranges_to_codes(decode_scan(reply.payload).ranges, "cm"), ranges_to_codes(source[0].ranges, "cm"))


def test_units_change_needs_installation_mode_and_the_password() -> None:
    host = Host(VirtualLMS200(scans(), units="cm"))
    host.send(get_config_request())
    config = [e for e in host.run(0.2) if isinstance(e, Frame)][0].payload[1:-1]
    host.send(set_config_request(with_units(config, "mm")))
    assert [e.payload[1] for e in host.run(0.2) if isinstance(e, Frame)] == [0]  # refused
    host.send(mode_request(0x00, b"WRONG_PW"))
    assert [e.payload[1] for e in host.run(0.2) if isinstance(e, Frame)] == [1]  # refused
    # Installation mode and the configuration write take 3 s each at time_scale 1.
    sent = host.t
    host.send(mode_request(0x00))
    assert [e.payload[1] for e in host.run(3.5) if isinstance(e, Frame)] == [0]
    assert 3.0 < host.events[-1][0] - sent < 3.1
    sent = host.t
    host.send(set_config_request(with_units(config, "mm")))
    assert [e.payload[1] for e in host.run(3.5) if isinstance(e, Frame)] == [1]
    assert 3.0 < host.events[-1][0] - sent < 3.1 and host.dev.units == "mm"


@pytest.mark.parametrize("baud, interval", [(38400, 732 * 10 / 38400), (500000, 2 / 75)])
def test_continuous_output_is_paced_by_the_baud_rate(baud: int, interval: float) -> None:
    dev = VirtualLMS200(scans(30))
    dev.baud = baud
    host = Host(dev)
    host.send(mode_request(0x24))
    host.run(1.2, step=0.0002)
    times = np.array([t for t, e in host.events if isinstance(e, Frame) and e.code == 0xB0])
    assert len(times) >= 4
    # 38400 baud: back to back, 732 bytes take 190.6 ms; 500000: one scan per 26.7 ms (37.5 Hz).
    np.testing.assert_allclose(np.diff(times)[1:], interval, atol=0.0005)  # the first goes at once


def test_time_scale_speeds_up_everything_alike() -> None:
    dev = VirtualLMS200(scans(30), time_scale=0.01)
    dev.baud = 38400
    host = Host(dev)
    host.send(mode_request(0x24))
    host.run(0.012, step=0.000002)
    times = np.array([t for t, e in host.events if isinstance(e, Frame) and e.code == 0xB0])
    np.testing.assert_allclose(np.diff(times), 0.01 * 732 * 10 / 38400, atol=0.00001)


def test_baud_change_reply_goes_out_at_the_old_baud() -> None:
    dev = VirtualLMS200(scans())
    dev.receive(build_frame(mode_request(0x48)), 0.0)
    pieces = []
    t = 0.0
    while t < 0.2:
        t += 0.001
        pieces += dev.transmit(t)
    assert {b for _, b in pieces} == {9600} and dev.baud == 500000


def test_faults_mute_miss_and_corrupt() -> None:
    host = Host(VirtualLMS200(scans(), faults=Faults(mute=True)))
    host.send(type_request())
    assert host.run(0.2) == []
    host = Host(VirtualLMS200(scans(), faults=Faults(miss_prob=1.0)))
    host.send(type_request())
    assert host.run(0.2) == [] and host.dev.requests == 1
    host = Host(VirtualLMS200(scans(), faults=Faults(rx_corrupt_prob=1.0)))
    host.send(type_request())
    assert host.run(0.2) == [NAK]
    dev = VirtualLMS200(scans(40), faults=Faults(corrupt_prob=0.002, seed=3))
    dev.baud = 500000
    host = Host(dev)
    host.send(mode_request(0x24))
    got = [e for e in host.run(1.0) if isinstance(e, Frame) and e.code == 0xB0]
    assert host.parser.stats.bad_crc > 0 and len(got) + host.parser.stats.bad_crc >= dev.scans_sent - 1


def test_garble_changes_bytes_only_when_bauds_differ() -> None:
    data = build_frame(type_request())
    assert garble(data, 9600, 9600) == data
    assert 0x02 not in garble(data, 9600, 38400)


def test_reset_answers_0x91_then_the_power_on_string_at_9600_baud() -> None:
    dev = VirtualLMS200(scans(), units="mm")
    dev.baud, dev.variant = 38400, (100, 25)
    host = Host(dev)
    host.send(b"\x10")
    frames = [e for e in host.run(1.5) if isinstance(e, Frame)]
    assert [f.code for f in frames] == [0x91, 0x90] and frames[1].payload[1:-1] == b"LMS200;301063;V02.10 "
    assert dev.baud == 9600 and dev.variant == (180, 50) and dev.units == "mm"  # units live in EEPROM
    t91, t90 = [t for t, e in host.events if isinstance(e, Frame)]
    assert t90 - t91 == pytest.approx(1.0 + 29 * 10 / 9600, abs=0.002)


def test_variants_report_the_right_beams() -> None:
    ranges = np.linspace(1.0, 4.6, 361)
    src = [Scan.lms200(ranges)] * 5
    for variant, expected in [((180, 100), ranges[::2]), ((100, 50), ranges[80:281]), ((100, 100), ranges[80:281:2])]:
        host = Host(VirtualLMS200(src, units="mm", variant=variant))
        host.send(measure_request())
        (reply,) = [e for e in host.run(1.0) if isinstance(e, Frame)]
        np.testing.assert_allclose(decode_scan(reply.payload).ranges, np.round(expected, 3), atol=1e-12)
    host = Host(VirtualLMS200(src, units="mm", variant=(100, 25)))
    host.send(measure_request())
    (reply,) = [e for e in host.run(1.0) if isinstance(e, Frame)]
    scan = decode_scan(reply.payload)
    assert len(scan) == 401 and scan.ranges[1] == pytest.approx(np.round((ranges[80] + ranges[81]) / 2, 3), abs=1e-12)


def test_a_reply_is_handed_over_before_the_next_scan_is_built() -> None:
    """Review 32 (slowsrc.py): the tail of the 0xA0 reply that starts continuous output was handed
    over only after the device had built its first scan (the simulator's first ray cast takes
    0.3-0.5 s), a gap mid-frame no device makes; the driver dropped the reply and resent after
    3.5 s. The first scan is now built when the device is (see the next test); every later one
    only after the bytes due went out: the second when the first telegram has arrived whole."""
    seen: list[list[object]] = []
    events: list[tuple[float, object]] = []

    def source():  # noqa: ANN202
        while True:
            seen.append([e for _, e in events if isinstance(e, Frame)])
            yield Scan.lms200(np.full(361, 2.0))

    host = Host(VirtualLMS200(source()))
    host.events = events
    assert seen == [[]]  # the first scan: built with the device, before any request
    host.send(mode_request(0x24))
    host.run(1.0)  # 9600 baud: the first telegram takes 0.76 s
    assert seen[1][0] == Frame(0x80, b"\xa0\x00\x10") and seen[1][1].code == 0xB0 and len(seen[1]) == 2


def test_the_first_scan_of_continuous_output_is_built_before_the_request() -> None:
    """Closing note of session 32: the device asked its source for the first scan only once the
    0xA0 reply to 0x20 0x24 had gone out, so a slow first scan (the simulator's first ray cast,
    0.5-0.85 s) stood between the reply and the first telegram: the real unit sends its newest
    scan at once. The source's first scan is now taken when the device is built; the telegram
    starts as the reply ends (a build timed on the host's clock: 0.5 s here, old gap 0.5 s)."""
    built: list[int] = []
    hosts: list[Host] = []

    def source():  # noqa: ANN202
        while True:
            if not built and hosts:
                hosts[0].t += 0.5  # the first build takes 0.5 s of the host's time
            built.append(1)
            yield Scan.lms200(np.full(361, 2.0))

    dev = VirtualLMS200(source())
    dev.baud = 500000
    hosts.append(Host(dev))
    host = hosts[0]
    host.send(mode_request(0x24))
    host.run(0.3, step=0.0001)
    host.run(0.3, step=0.0001)  # the old build's 0.5 s jump passed the end of the first run
    times = [(t, e.code) for t, e in host.events if isinstance(e, Frame)]
    (t_reply, code), (t_scan, first) = times[:2]
    assert (code, first) == (0xA0, 0xB0)
    assert t_scan - t_reply < 732 * 10 / 500000 + 0.002  # the telegram's line time (old: 0.5 s more)


def test_quarter_degree_midpoints_follow_nan_then_inf() -> None:
    """The docstring said "mean of two valid neighbours, else nan"; next to +inf the midpoint is
    +inf (8183), next to nan it is nan (8191), as the code always did."""
    from lms200.virtual import variant_codes

    r = np.full(361, 2.0)
    r[100], r[102], r[103] = np.inf, np.nan, np.inf
    codes = variant_codes(r, (100, 25), "mm")
    # 0.5 deg beam b is value 2 * (b - 80) of the 401; between them the midpoints
    assert codes[2 * 19 + 1 : 2 * 24].tolist() == [8183, 8183, 8183, 2000, 8191, 8191, 8191, 8183, 8183]
    #                                   mid 99|100, 100 (inf), mid 100|101, 101, mid 101|102 (nan), 102 (nan),
    #                                   mid 102|103 (nan, inf: nan), 103 (inf), mid 103|104 (inf)


@pytest.mark.parametrize("first, second", [((180, 50), (100, 25)), ((180, 100), (180, 50)), ((100, 25), (180, 100))])
def test_continuous_output_after_a_variant_change_starts_at_once(first, second) -> None:
    """`lmsbench lms200 record` at 0.25 deg after one at 0.5 deg on the same emulator got no scan:
    the index of the last scan sent, counted at the old period, read at the new (longer) one put the
    next scan at twice the clock (an hour of uptime: an hour's wait), and the device then answered
    nothing. The clock here starts at 1000 s, as a monotonic clock does."""
    import itertools

    dev = VirtualLMS200(itertools.cycle(scans(10)), units="mm", variant=first)
    dev.baud = 500000
    host = Host(dev)
    host.t = 1000.0
    for variant in (first, second, first):
        host.send(variant_request(*variant))
        host.send(mode_request(0x24))
        host.run(0.3, step=0.0002)
        start = host.t
        host.run(0.4, step=0.0002)
        times = [t for t, e in host.events if t > start and isinstance(e, Frame) and e.code == 0xB0]
        period = 0.0133333 * {100: 1, 50: 2, 25: 4}[variant[1]]
        assert len(times) >= 4 and np.diff(times).max() < period * 1.6, (variant, times[:3])
        host.send(mode_request(0x25))
        host.run(0.1, step=0.0002)


@pytest.mark.parametrize("angle_min", [0.0, -np.pi, -2 * np.pi, np.pi / 2])
def test_a_full_turn_scan_fills_the_whole_frame_whatever_its_first_bearing(angle_min: float) -> None:
    """A 720-beam 360 deg scan (0.5 deg apart) served by the virtual device: each beam of the
    LMS200's -90 .. +90 deg frame is the scan's beam of that bearing, compared modulo a full turn.
    From angle_min 0 (0 .. 359.5 deg, as some 360 deg drivers publish) the 180 beams -90 .. -0.5 deg
    came out nan (their bearings, 270 .. 359.5 deg, were not found), so half the frame read invalid."""
    from lms200.virtual import resample_to_grid

    ranges = 1.0 + 0.01 * np.arange(720)  # beam k at angle_min + k * 0.5 deg
    scan = Scan(ranges, angle_min, np.pi / 360, 0.0, 8.0)
    frame_deg = -90.0 + 0.5 * np.arange(361)
    beam = np.rint(np.mod(frame_deg - np.rad2deg(angle_min), 360.0) / 0.5).astype(int) % 720
    np.testing.assert_array_equal(resample_to_grid(scan), ranges[beam])
    if angle_min == 0.0:
        assert resample_to_grid(scan)[:3].tolist() == [6.4, 6.41, 6.42]  # beams 540.. (270 deg), not nan


def test_a_partial_scan_still_leaves_the_frame_it_does_not_cover_nan() -> None:
    """Bearings compared modulo a full turn change nothing for a scan narrower than the frame:
    101 beams at 0.9 deg from -45 deg fill the frame's -45 .. +45 deg, the rest stays nan; and a
    target within half a beam outside the scan still takes its end beam."""
    from lms200.virtual import resample_to_grid

    scan = Scan(1.0 + 0.01 * np.arange(101), -np.pi / 4, np.deg2rad(0.9), 0.0, 8.0)
    out = resample_to_grid(scan)
    covered = np.flatnonzero(~np.isnan(out))
    assert (covered[0], covered[-1]) == (90, 270)
    assert out[90] == 1.0 and out[270] == 2.0 and out[180] == pytest.approx(1.5)


def test_a_host_flooding_requests_without_reading_gets_a_bounded_queue() -> None:
    """Found by fuzzing the emulator's input (round 8): requests written without reading the answers
    (a flood of scan requests, or of telegrams with a bad CRC, each NAKed) queued every answer, a
    simulated scan each, without bound (400 scan requests: 800 chunks, 2 s). A telegram received while
    MAX_QUEUED answers wait is dropped unanswered and counted; the answers queued go out whole."""
    from lms200.virtual import MAX_QUEUED

    host = Host(VirtualLMS200(scans(3)))
    bad = bytearray(build_frame(type_request()))
    bad[-1] ^= 0xFF
    host.dev.receive(bytes(bad) * 100 + build_frame(measure_request()) * 100, 0.0)
    assert len(host.dev._queue) == MAX_QUEUED  # old: 300 (100 NAKs, 100 ACKs and 100 scans)
    assert host.dev.requests_dropped == 200 - MAX_QUEUED
    assert host.run(0.05) == [NAK] * MAX_QUEUED
    host.send(measure_request())  # the line free again: answered (732 bytes at 9600 baud: 0.76 s)
    events = host.run(1.0)
    assert events[0] == ACK and [len(e.payload) for e in events[1:]] == [4 + 2 * 361]
