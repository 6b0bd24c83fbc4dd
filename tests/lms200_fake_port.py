"""A scripted serial port for driver tests: each request written is answered by (delay, bytes)
pieces that become readable ``delay`` seconds after the write, so a test can stall a reply
mid-frame, deliver a backlog in one read, or answer with a corrupted telegram. Install it with
``fake_port(monkeypatch, script)``; ``script(payload, n)`` gets the request's payload (command
and data) and how many telegrams were written so far, and returns the pieces."""

from __future__ import annotations

import time
from typing import Callable

import numpy as np
import serial

from lms200.protocol import ACK, build_frame, encode_measurement

Script = Callable[[bytes, int], list[tuple[float, bytes]]]
CONFIG_MM = bytes([0, 0, 0, 0, 0x0D, 1]) + bytes(26)  # the configuration block, units mm
ACK_BYTE = bytes([ACK])
TYPE_REPLY = b"\xba" + b"LMS200;301063;V02.10 " + b"\x10"


def reply(payload: bytes) -> bytes:
    return build_frame(bytes(payload), 0x80)


def scan_frame(value: int = 1000) -> bytes:
    return reply(encode_measurement(np.full(361, value, np.uint16), "mm"))


def answer(payload: bytes) -> list[tuple[float, bytes]]:
    """What a healthy unit in mm sends back: ACK after 2 ms, the reply after 10 ms."""
    cmd = payload[0]
    body = {0x3A: TYPE_REPLY, 0x20: b"\xa0\x00\x10", 0x74: b"\xf4" + CONFIG_MM + b"\x10"}.get(cmd)
    if cmd == 0x3B:
        body = b"\xbb\x01" + payload[1:5] + b"\x10"
    return [] if body is None else [(0.002, bytes([ACK])), (0.010, reply(body))]


class FakePort:
    def __init__(self, script: Script) -> None:
        self.script = script
        self.queue: list[tuple[float, bytes]] = []
        self.baudrate = 9600
        self.is_open = True
        self.writes: list[bytes] = []

    @property
    def in_waiting(self) -> int:
        now = time.monotonic()
        return sum(len(b) for t, b in self.queue if t <= now)

    def read(self, n: int) -> bytes:
        deadline = time.monotonic() + 0.01
        while True:
            now = time.monotonic()
            due = [b for t, b in self.queue if t <= now]
            if due:  # everything that has arrived, up to n bytes, in one read
                data = b"".join(due)
                self.queue = [(t, b) for t, b in self.queue if t > now]
                if len(data) > n:
                    self.queue.insert(0, (now, data[n:]))
                return data[:n]
            if now >= deadline:
                return b""
            time.sleep(0.001)

    def write(self, data: bytes) -> int:
        self.writes.append(bytes(data))
        now = time.monotonic()
        self.queue += [(now + dt, b) for dt, b in self.script(bytes(data[4:-2]), len(self.writes))]
        self.queue.sort(key=lambda x: x[0])
        return len(data)

    def flush(self) -> None:
        pass

    def reset_input_buffer(self) -> None:
        self.queue.clear()

    def close(self) -> None:
        self.is_open = False


def fake_port(monkeypatch, script: Script) -> FakePort:  # noqa: ANN001
    port = FakePort(script)
    monkeypatch.setattr(serial, "serial_for_url", lambda *a, **kw: port)
    return port
