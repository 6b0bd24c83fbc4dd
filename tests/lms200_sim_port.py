"""The virtual LMS200 behind a serial port on a simulated clock: no threads, no sleeping, and the
same bytes in the same reads on every run, so a seeded fault run is reproducible exactly.

``sim_port(monkeypatch, device)`` makes ``LMS200("sim://")`` talk to ``device``; the driver's clock
(``time.monotonic``, ``time.time``, ``time.sleep``) is the simulated one. A read behaves as
pyserial's on a real port: it returns at once when ``n`` bytes are due, else when the 10 ms read
timeout has passed, with what arrived by then. Each byte takes its line time (``time_scale`` 1:
real timing, which costs nothing here).

``python tests/lms200_sim_port.py [runs]`` prints the counts of the seeded fault runs
(:func:`fault_run`): streaming with 0.2 % corrupted and 0.1 % dropped bytes, then closing.
"""

from __future__ import annotations

import itertools
import time
from dataclasses import dataclass

import numpy as np
import serial

from lms200 import driver
from lms200.protocol import NAK, frame_seconds
from lms200.scan import Scan
from lms200.virtual import Faults, VirtualLMS200, garble


class SimClock:
    """The time module with a simulated monotonic clock (s) that only sleep() and reads advance."""

    def __init__(self, start: float = 1000.0) -> None:
        self.t = start

    def monotonic(self) -> float:
        return self.t

    def time(self) -> float:
        return self.t + 1.7e9

    def sleep(self, seconds: float) -> None:
        self.t += max(0.0, seconds)

    def __getattr__(self, name: str) -> object:
        return getattr(time, name)


class SimPort:
    """A serial port wired to a VirtualLMS200 on a SimClock (bauds that differ garble, as on a UART)."""

    def __init__(self, device: VirtualLMS200, clock: SimClock, read_timeout: float = 0.01) -> None:
        self.dev, self.clock, self.read_timeout = device, clock, read_timeout
        self.baudrate = 9600
        self.is_open = True
        self._rx = bytearray()
        self.writes: list[bytes] = []

    def _pull(self) -> None:
        for piece, baud in self.dev.transmit(self.clock.t):
            self._rx += garble(piece, baud, self.baudrate)

    @property
    def in_waiting(self) -> int:
        self._pull()
        return len(self._rx)

    def read(self, n: int) -> bytes:
        deadline = self.clock.t + self.read_timeout
        self._pull()
        while len(self._rx) < n:
            wake = self.dev.next_wakeup(self.clock.t)
            if wake is None or wake > deadline:
                self.clock.t = deadline
                self._pull()
                break
            # on to when the bytes still missing would all be due (or the read's timeout)
            missing_s = (n - len(self._rx)) * frame_seconds(1, self.dev.baud) * self.dev.time_scale
            self.clock.t = min(deadline, max(self.clock.t + missing_s, wake + 1e-7))
            self._pull()
        data = bytes(self._rx[:n])
        del self._rx[:n]
        return data

    def write(self, data: bytes) -> int:
        self.writes.append(bytes(data))
        self.clock.t += frame_seconds(len(data), self.baudrate) * self.dev.time_scale  # on the line
        self.dev.receive(garble(bytes(data), self.baudrate, self.dev.baud), self.clock.t)
        return len(data)

    def flush(self) -> None:
        pass

    def reset_input_buffer(self) -> None:
        self._pull()
        self._rx.clear()

    def close(self) -> None:
        self.is_open = False


def sim_port(monkeypatch, device: VirtualLMS200) -> SimPort:  # noqa: ANN001
    """Install a SimPort for ``device``: LMS200(any url) opens it, on the simulated clock."""
    clock = SimClock()
    port = SimPort(device, clock)
    monkeypatch.setattr(serial, "serial_for_url", lambda *a, **kw: port)
    monkeypatch.setattr(driver, "time", clock)
    return port


def numbered_scans() -> itertools.cycle:
    """Scans told apart by their first range: scan i reads (1000 + i) mm there, i < 3000."""
    rng = np.random.default_rng(7)
    out = []
    for i in range(3000):
        r = rng.uniform(0.2, 8.0, 361)
        r[0] = (1000 + i) / 1000.0
        out.append(Scan.lms200(r))
    return itertools.cycle(out)


@dataclass
class RunCounts:
    naks_sent: int = 0  # NAK bytes the device sent
    naks_seen: int = 0  # NAKs the driver's parser counted
    timeouts: int = 0
    retries: int = 0
    scans: int = 0  # scans yielded
    scans_lost: int = 0  # scans sent between the first and the last yielded that were not yielded
    errors: int = 0  # runs that raised


def fault_run(seed: int, scans: int = 30, corrupt: float = 0.002, drop: float = 0.001, rx_corrupt: float = 0.0,
              baud: int = 500000, close_rx_corrupt: float | None = None, time_scale: float = 1.0) -> tuple[RunCounts, str]:
    """Open a virtual unit (mm, on a simulated clock) at ``baud``, stream ``scans`` scans with
    ``corrupt`` / ``drop`` per byte sent and ``rx_corrupt`` per request, then close with the faults
    on (``close_rx_corrupt`` per request from then on, when given). ``time_scale`` 0.01: the device
    100 times faster, as in the tests (a 10 ms read then holds many telegrams). Returns the counts
    and the error raised (or "")."""
    import pytest

    dev = VirtualLMS200(numbered_scans(), units="mm", faults=Faults(seed=seed), time_scale=time_scale)
    counts = RunCounts()
    send = dev._send

    def counting_send(data: bytes, ready: float, done=None) -> None:  # noqa: ANN001
        if data == bytes([NAK]):
            counts.naks_sent += 1
        send(data, ready, done)

    dev._send = counting_send  # type: ignore[method-assign]
    error = ""
    with pytest.MonkeyPatch.context() as mp:
        sim_port(mp, dev)
        lms = driver.LMS200("sim://", baud=baud)
        dev.faults.corrupt_prob, dev.faults.drop_prob, dev.faults.rx_corrupt_prob = corrupt, drop, rx_corrupt
        got = []
        try:
            for scan in lms.scans(stall_timeout=10.0):  # most telegrams are broken: no stall error
                got.append(int(round(scan.ranges[0] * 1000)) - 1000)
                if len(got) == scans:
                    break
        except Exception as exc:  # noqa: BLE001 - counted
            error = f"{type(exc).__name__}: {exc}"
        if close_rx_corrupt is not None:
            dev.faults.rx_corrupt_prob = close_rx_corrupt
        try:
            lms.close()
        except Exception as exc:  # noqa: BLE001 - counted
            error = error or f"{type(exc).__name__}: {exc}"
    s = lms.stats
    counts.naks_seen, counts.timeouts, counts.retries, counts.scans = lms.parser.stats.naks, s.timeouts, s.retries, len(got)
    if got:
        counts.scans_lost = got[-1] - got[0] + 1 - len(got)
    counts.errors = int(bool(error))
    return counts, error


def fault_runs(runs: int = 30, **kw: object) -> RunCounts:
    total = RunCounts()
    for seed in range(runs):
        c, _ = fault_run(seed, **kw)  # type: ignore[arg-type]
        for f in total.__dataclass_fields__:
            setattr(total, f, getattr(total, f) + getattr(c, f))
    return total


if __name__ == "__main__":
    import sys

    n = int(sys.argv[1]) if len(sys.argv) > 1 else 30
    print("streaming, 0.2 % corrupted / 0.1 % dropped:", fault_runs(n))
    print("the same, 30 % of requests corrupted:      ", fault_runs(n, rx_corrupt=0.3))
    print("the same, 50 % of requests corrupted from close() on, 4 x runs:", fault_runs(4 * n, close_rx_corrupt=0.5))
    print("streaming at time_scale 0.01, 4 x runs:", fault_runs(4 * n, time_scale=0.01))
    print("the same, 50 % of requests corrupted from close() on:", fault_runs(4 * n, close_rx_corrupt=0.5, time_scale=0.01))
