"""Benchmark: LMS200 frame parser and 0xB0 decoder throughput against the 500 kbaud line rate.

A stream of full 361-value scan telegrams (732 bytes) with ACK bytes and garbage between them is
fed in 4 KiB chunks, as a serial port delivers it. At 500 000 baud (10 bits a byte) the line
carries at most 500000 / 10 / 732 = 68.3 full telegrams a second.
"""

from __future__ import annotations

import time

import numpy as np

from lms200.codes import ranges_to_codes
from lms200.framing import Frame, FrameParser
from lms200.protocol import build_frame, decode_scan, encode_measurement

NAME = "lms200"
LINE_RATE_SCANS_PER_S = 500_000 / 10 / 732


def _stream(n_frames: int, seed: int = 0) -> bytes:
    rng = np.random.default_rng(seed)
    parts = []
    for _ in range(n_frames):
        codes = ranges_to_codes(rng.uniform(0.2, 8.0, 361), "mm")
        parts.append(b"\x06" + build_frame(encode_measurement(codes, "mm"), 0x80))
        if rng.random() < 0.1:
            parts.append(rng.integers(0, 256, 16, dtype=np.uint8).tobytes())
    return b"".join(parts)


def _run_once(stream: bytes, decode: bool) -> tuple[float, int]:
    parser = FrameParser()
    count = 0
    t0 = time.perf_counter_ns()
    for i in range(0, len(stream), 4096):
        for ev in parser.feed(stream[i : i + 4096]):
            if isinstance(ev, Frame):
                if decode:
                    decode_scan(ev.payload)
                count += 1
    return (time.perf_counter_ns() - t0) * 1e-9, count


def run(quick: bool = False) -> list[dict]:
    n = 300 if quick else 3000
    stream = _stream(n)
    rows = []
    for decode in (False, True):
        best = min(_run_once(stream, decode)[0] for _ in range(1 if quick else 3))
        rate = n / best
        rows.append({
            "what": "parse+decode to Scan" if decode else "parse frames (CRC checked)",
            "scans_per_s": rate,
            "mbytes_per_s": len(stream) / best / 1e6,
            "x_line_rate_500k": rate / LINE_RATE_SCANS_PER_S,
        })
    return rows
