"""SICK LMS200 telegram codec: CRC, frames, the commands the project uses, and the 0xB0 decoder.

Pure functions (bytes in, bytes or Scans out); no I/O, no clocks. The streaming parser lives in
:mod:`lms200.framing`, the serial driver in :mod:`lms200.driver`.

Frame layout (SICK LMS2xx telegram listing; summary in the README section ``lms200``)::

    STX 0x02 | ADDR | LEN (u16 LE) | CMD | DATA ... | [STATUS, replies] | CRC16 (u16 LE)

LEN counts every byte after the length field except the CRC, so a frame is LEN + 6 bytes long.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from typing import overload

import numpy as np

from .codes import (LMS200_MAX_RANGE, Units, check_codes, check_units, codes_to_ranges, ranges_to_codes,
                    real_vector)
from .errors import InputError, LmsProtocolError, LmsStatusError
from .finite import check_integer, check_number, is_integer, is_number, shown
from .scan import Scan

STX = 0x02
ACK = 0x06
NAK = 0x15
HOST_ADDRESS = 0x00
REPLY_FLAG = 0x80  # device-to-host address = device address + 0x80; reply code = command + 0x80
MAX_LEN = 812  # largest LEN field of any LMS2xx telegram
HEADER_BYTES = 4  # STX, ADDR, LEN
OVERHEAD_BYTES = 6  # header + CRC
STATUS_OK = 0x10  # STATUS byte of a healthy LMS200
STATUS_LEVEL_MASK = 0x07  # STATUS bits 0-2: 0 ok, 1 info, 2 warning, 3 error, 4 fatal (5-7 undefined)
STATUS_ERROR_LEVEL = 3  # the first level whose scan's values are not to be used
STATUS_IMPLAUSIBLE = 0x40  # STATUS bit 6: implausible measured values
CRC_POLY = 0x8005

# Commands (host -> device) and their replies (device -> host).
CMD_RESET = 0x10
CMD_MODE = 0x20
CMD_MEASURE = 0x30
CMD_STATUS = 0x31
CMD_TYPE = 0x3A
CMD_VARIANT = 0x3B
CMD_GET_CONFIG = 0x74  # not on the protocol page: from SICK's LMS2xx telegram listing
CMD_SET_CONFIG = 0x77  # idem
REPLY_RESET = 0x91
REPLY_POWER_ON = 0x90
REPLY_BAD_COMMAND = 0x92  # "incorrect command in a correct frame"
REPLY_MEASURE = CMD_MEASURE | REPLY_FLAG  # 0xB0


def reply_code(command: int) -> int:
    """Reply code of a command: command + 0x80 (0x20 -> 0xA0, 0x30 -> 0xB0 ...)."""
    return (command | REPLY_FLAG) & 0xFF


# Sub-commands of 0x20 (operating mode).
MODE_INSTALLATION = 0x00
MODE_CONTINUOUS = 0x24  # all measured values, continuously
MODE_ON_REQUEST = 0x25  # measured values only on request (power-on default)
PASSWORD = b"SICK_LMS"  # installation-mode password of a factory-set LMS200
BAUD_MODES = {38400: 0x40, 19200: 0x41, 9600: 0x42, 500000: 0x48}
MODE_BAUDS = {v: k for k, v in BAUD_MODES.items()}
POWER_ON_BAUD = 9600

# Variants: (field of view deg, resolution in 1/100 deg) -> number of values.
VARIANTS = {(180, 100): 181, (180, 50): 361, (100, 100): 101, (100, 50): 201, (100, 25): 401}
VARIANT_OF_COUNT = {n: v for v, n in VARIANTS.items()}

# Configuration block of 0x74 / 0x77 (LMS2xx listing; not on the protocol page). The driver only
# reads and rewrites the byte below and treats the rest of the block as opaque.
CONFIG_BYTES = 32
CONFIG_UNITS_OFFSET = 5  # after WORD blanking, BYTE sensitivity, BYTE availability, BYTE mode
UNITS_CODES: dict[Units, int] = {"cm": 0x00, "mm": 0x01}
CODE_UNITS: dict[int, Units] = {v: k for k, v in UNITS_CODES.items()}


# ---------------------------------------------------------------------------------------------
# CRC
# The register update is crc = (crc << 1 [^ 0x8005 if the top bit fell out]) ^ (prev << 8 | byte).
# It is linear over GF(2): byte b at distance k from the end contributes b * x^k (+ b * x^(k+7)
# for k >= 1, its copy in the next word's high byte) modulo P = x^16 + 0x8005. The table below
# holds that contribution for every (k, b), so a CRC is one gather and one XOR reduction.
def _crc_bitwise(data: bytes) -> int:
    """The CRC one step at a time, exactly as SICK's listing states it (reference, slow)."""
    crc = 0
    prev = 0
    for byte in data:
        if crc & 0x8000:
            crc = ((crc << 1) & 0xFFFF) ^ CRC_POLY
        else:
            crc = (crc << 1) & 0xFFFF
        crc ^= (prev << 8) | byte
        prev = byte
    return crc


def _build_crc_table(rows: int) -> np.ndarray:
    powers = np.zeros(rows + 16, dtype=np.uint16)  # x^e mod P
    value = 1
    for e in range(powers.size):
        powers[e] = value
        value = ((value << 1) & 0xFFFF) ^ (CRC_POLY if value & 0x8000 else 0)
    b = np.arange(256, dtype=np.uint16)
    table = np.zeros((rows, 256), dtype=np.uint16)
    for k in range(rows):
        for j in range(8):
            term = powers[k + j] ^ (powers[k + j + 7] if k >= 1 else np.uint16(0))
            table[k] ^= np.where((b >> j) & 1, term, np.uint16(0)).astype(np.uint16)
    return table


_CRC_ROWS = MAX_LEN + HEADER_BYTES + 8
_CRC_TABLE = _build_crc_table(_CRC_ROWS)
_CRC_K = np.arange(_CRC_ROWS - 1, -1, -1)  # distance from the end, for the last n bytes: _CRC_K[-n:]


def byte_string(data: object, name: str, *, int_lists: bool = False) -> bytes:
    """``data`` (bytes, bytearray, memoryview or a 1-D uint8 array; with ``int_lists``, a list or
    tuple of integers 0..255 as well, as ``bytes()`` takes it: ``mode_request(0, list(b"SICK_LMS"))``
    worked before this check) as bytes; InputError naming ``name`` for anything else (text, None,
    a list: TypeErrors; a uint8 array's arithmetic overflowed)."""
    if isinstance(data, bytes):
        return data
    if isinstance(data, (bytearray, memoryview)):
        return bytes(data)
    if isinstance(data, np.ndarray) and data.dtype == np.uint8 and data.ndim == 1:
        return data.tobytes()
    if int_lists and isinstance(data, (list, tuple)) and all(is_integer(b) and 0 <= b <= 0xFF for b in data):
        return bytes(data)
    lists = ", list or tuple of integers 0..255" if int_lists else ""
    raise InputError(f"{name}: must be bytes (or a bytearray, memoryview, 1-D uint8 array{lists}), got {type(data).__name__}")


def crc16(data: bytes) -> int:
    """SICK's CRC-16 over ``data`` (for a frame: STX through STATUS); an int in 0..65535."""
    data = byte_string(data, "data")
    n = len(data)
    if n == 0:
        return 0
    if n > _CRC_ROWS or n < 24:
        return _crc_bitwise(data)
    arr = np.frombuffer(bytes(data), dtype=np.uint8)
    return int(np.bitwise_xor.reduce(_CRC_TABLE[_CRC_K[-n:], arr]))


def build_frame(payload: bytes, address: int = HOST_ADDRESS) -> bytes:
    """A whole telegram: STX, address, LEN, payload (command, data[, status]), CRC (low byte first).

    Raises:
        InputError: (a ValueError) for a payload that is not bytes, is empty or longer than 812 bytes,
            or an address that is no integer 0..255 (a float was struct's error, None a TypeError).
    """
    payload = byte_string(payload, "payload")
    if not payload:
        raise InputError("payload: must hold at least the command byte")
    if len(payload) > MAX_LEN:
        raise InputError(f"payload: at most {MAX_LEN} bytes, got {len(payload)}")
    address = check_integer(address, "address", 0, 0xFF, strict=True)
    head = struct.pack("<BBH", STX, address, len(payload)) + payload
    return head + struct.pack("<H", crc16(head))


# ---------------------------------------------------------------------------------------------
# Requests (payloads: pass them to build_frame)
def reset_request() -> bytes:
    """0x10: reset the device (it answers 0x91, later the 0x90 power-on string)."""
    return bytes([CMD_RESET])


def mode_request(sub_command: int, password: bytes = PASSWORD) -> bytes:
    """0x20: switch the operating mode; installation mode (0x00) carries the 8-byte password.
    InputError for a ``sub_command`` that is no integer 0..255 or a ``password`` that is not 8 bytes."""
    sub_command = check_integer(sub_command, "sub_command", 0, 0xFF, strict=True)
    if sub_command == MODE_INSTALLATION:
        password = byte_string(password, "password", int_lists=True)
        if len(password) != 8:
            raise InputError(f"password: must be 8 bytes, got {len(password)}")
        return bytes([CMD_MODE, sub_command]) + bytes(password)
    return bytes([CMD_MODE, sub_command])


def baud_request(baud: int) -> bytes:
    """0x20 with the sub-command that switches to ``baud`` (9600, 19200, 38400, 500000)."""
    if not is_number(baud) or baud not in BAUD_MODES:  # a list was a TypeError (unhashable)
        raise InputError(f"baud: the LMS200 supports {sorted(BAUD_MODES)}, got {shown(baud)}")
    return mode_request(BAUD_MODES[baud])


def measure_request() -> bytes:
    """0x30 01: request one full scan."""
    return bytes([CMD_MEASURE, 0x01])


def status_request() -> bytes:
    """0x31: request the status block."""
    return bytes([CMD_STATUS])


def type_request() -> bytes:
    """0x3A: request the type string (``LMS200;301063;V02.10 ``)."""
    return bytes([CMD_TYPE])


def variant_request(fov_deg: int, resolution_cdeg: int) -> bytes:
    """0x3B: field of view (100 or 180 deg) and resolution (100, 50, 25 hundredths of a deg)."""
    if not (is_integer(fov_deg) and is_integer(resolution_cdeg)) or (fov_deg, resolution_cdeg) not in VARIANTS:
        # a list was a TypeError (unhashable), 180.0 passed here and failed in struct
        raise InputError(
            f"variant: ({shown(fov_deg)} deg, {shown(resolution_cdeg)} hundredths of a deg) is not an LMS200 variant; "
            f"choose one of (ints) {list(VARIANTS)}"
        )
    return struct.pack("<BHH", CMD_VARIANT, fov_deg, resolution_cdeg)


def get_config_request() -> bytes:
    """0x74: request the configuration block (LMS2xx listing; reply 0xF4)."""
    return bytes([CMD_GET_CONFIG])


def set_config_request(config: bytes) -> bytes:
    """0x77: write the configuration block (installation mode only; reply 0xF7). InputError for a
    ``config`` that is not bytes or a list of integers 0..255 (5 was taken as 5 zero bytes, True as
    one, text a TypeError)."""
    return bytes([CMD_SET_CONFIG]) + byte_string(config, "config", int_lists=True)


def with_units(config: bytes, units: Units) -> bytes:
    """A configuration block with the measured-value unit byte set to ``units``; InputError for a
    ``config`` that is not bytes or a list of integers 0..255 (None or a number was a TypeError) or
    an unknown unit."""
    config = byte_string(config, "config", int_lists=True)
    units = check_units(units)
    if len(config) <= CONFIG_UNITS_OFFSET:
        raise LmsProtocolError(f"configuration block of {len(config)} bytes has no unit byte")
    block = bytearray(config)
    block[CONFIG_UNITS_OFFSET] = UNITS_CODES[units]
    return bytes(block)


def units_of_config(config: bytes) -> Units:
    """The measured-value unit a configuration block sets ('mm' or 'cm'); InputError for a ``config``
    that is not bytes (None was a TypeError, text an AttributeError)."""
    config = byte_string(config, "config")
    if len(config) <= CONFIG_UNITS_OFFSET or config[CONFIG_UNITS_OFFSET] not in CODE_UNITS:
        raise LmsProtocolError(f"configuration block {config.hex(' ')} holds no known unit code")
    return CODE_UNITS[config[CONFIG_UNITS_OFFSET]]


# ---------------------------------------------------------------------------------------------
# Measured values (0xB0)
@dataclass(frozen=True)
class Measurement:
    """The fields of one 0xB0 reply.

    Attributes:
        codes: raw 16-bit values (distance in bits 0-12, flags in bits 13-15), uint16.
        units: 'mm' or 'cm', from bits 14-15 of the count word.
        partial: True for one partial scan of an interlaced scan (bit 13).
        partial_index: which partial scan (bits 11-12).
        status: the STATUS byte.
    """

    codes: np.ndarray
    units: Units
    partial: bool
    partial_index: int
    status: int


def parse_measurement(payload: bytes) -> Measurement:
    """Split a 0xB0 payload (reply code, count word, values, status) into its fields.

    Raises:
        LmsProtocolError: for another reply code, a length that disagrees with the count word,
            or a unit code other than cm / mm.
        InputError: for a payload that is not bytes.
    """
    payload = byte_string(payload, "payload")
    if len(payload) < 4 or payload[0] != REPLY_MEASURE:
        raise LmsProtocolError(f"not a 0xB0 measured-value reply: {bytes(payload[:8]).hex(' ')}")
    count = payload[1] | (payload[2] << 8)
    n = count & 0x3FF
    if len(payload) != 4 + 2 * n:
        raise LmsProtocolError(f"0xB0 reply announces {n} values but holds {(len(payload) - 4) / 2:g}")
    unit_bits = count >> 14
    if unit_bits not in (0, 1):
        raise LmsProtocolError(f"0xB0 reply with unit code {unit_bits} (only 0 = cm and 1 = mm are known)")
    codes = np.frombuffer(payload, dtype="<u2", count=n, offset=3)
    return Measurement(
        codes=codes,
        units="mm" if unit_bits == 1 else "cm",
        partial=bool(count & 0x2000),
        partial_index=(count >> 11) & 0x3,
        status=payload[-1],
    )


def scan_geometry(n_values: int) -> tuple[float, float]:
    """(angle_min, angle_increment) in rad of an LMS200 scan of ``n_values`` beams.

    180 deg variants run from -90 deg, 100 deg variants from -50 deg (right to left).

    Raises:
        LmsProtocolError: for a count of no variant; InputError for a ``n_values`` that is no
            integer (a list was a TypeError, unhashable).
    """
    n_values = check_integer(n_values, "n_values", 0)
    try:
        fov, res = VARIANT_OF_COUNT[n_values]
    except KeyError:
        raise LmsProtocolError(
            f"a scan of {n_values} values matches no LMS200 variant (expected {sorted(VARIANT_OF_COUNT)})"
        ) from None
    return float(np.deg2rad(-fov / 2)), float(np.deg2rad(res / 100))


def status_problem(status: int) -> str | None:
    """Why the values of a scan whose STATUS byte is ``status`` are not to be used, or None: an error
    or fatal error (bits 0-2 of 3 or more, the levels past a warning) or implausible measured values
    (bit 6). Info, warnings and pollution (bit 7: a dirty front screen) leave the values measured."""
    level = status & STATUS_LEVEL_MASK
    problems = []
    if level >= STATUS_ERROR_LEVEL:
        problems.append({3: "an error", 4: "a fatal error"}.get(level, f"undefined level {level}"))
    if status & STATUS_IMPLAUSIBLE:
        problems.append("implausible measured values")
    return f"status 0x{status:02X}: {' and '.join(problems)}" if problems else None


def decode_scan(payload: bytes, stamp: float = 0.0) -> Scan:
    """A 0xB0 payload to a :class:`Scan` (ranges in m, 8183 -> +inf, invalid codes -> nan).

    Raises:
        LmsProtocolError: for a malformed reply, an unknown beam count or a partial scan of an
            interlaced scan (not supported: request full scans).
        LmsStatusError: (an LmsProtocolError) for a scan whose STATUS byte says its values are not
            to be used (:func:`status_problem`: an error, a fatal error, implausible values): its
            values were taken as measured, silently.
    """
    m = parse_measurement(payload)
    problem = status_problem(m.status)
    if problem:
        raise LmsStatusError(f"0xB0 scan with {problem}: its values are not to be used")
    if m.partial:
        raise LmsProtocolError(f"0xB0 partial scan {m.partial_index}: interlaced partial scans are not supported")
    angle_min, increment = scan_geometry(m.codes.size)
    ranges = codes_to_ranges(m.codes, m.units)
    return Scan(ranges, angle_min, increment, 0.0, LMS200_MAX_RANGE[m.units], stamp)


def encode_measurement(codes: np.ndarray, units: Units, status: int = STATUS_OK) -> bytes:
    """A 0xB0 payload carrying ``codes`` (uint16, one per beam) in ``units``; InputError naming the
    argument for codes that are not 16-bit values, an unknown unit or a status beyond a byte."""
    values = check_codes(codes).astype("<u2")
    units = check_units(units)
    if isinstance(status, bool) or not isinstance(status, (int, np.integer)) or not 0 <= status <= 0xFF:
        raise InputError(f"status: must be a byte 0..255, got {status!r}")
    if values.ndim != 1 or not 0 < values.size <= 0x3FF:
        raise InputError(f"codes: must be 1-D with 1..1023 values, got shape {values.shape}")
    count = values.size | (UNITS_CODES[units] << 14)
    return struct.pack("<BH", REPLY_MEASURE, count) + values.tobytes() + bytes([status])


def encode_scan(scan: Scan, units: Units = "mm", status: int = STATUS_OK) -> bytes:
    """A 0xB0 payload for ``scan`` (ranges rounded to the unit; +inf -> 8183, nan -> 8191); InputError
    for a ``scan`` that is no lms200.Scan (an array or None was an AttributeError), or whose
    geometry is no LMS200 variant's (:func:`scan_geometry`): a 0xB0 telegram carries no angles, its
    beam count alone gives them, so a 181-beam scan at 0.5 deg (-90 .. 0 deg) was decoded as one
    at 1 deg (-90 .. +90 deg), silently."""
    if not isinstance(scan, Scan):
        raise InputError(f"scan: must be an lms200.Scan, got {type(scan).__name__}")
    n = len(scan)
    if n in VARIANT_OF_COUNT:
        angle_min, increment = scan_geometry(n)
    if n not in VARIANT_OF_COUNT or not (
            math.isclose(scan.angle_min, angle_min, rel_tol=0.0, abs_tol=GEOMETRY_TOLERANCE_RAD)
            and math.isclose(scan.angle_increment, increment, rel_tol=GEOMETRY_TOLERANCE_RAD)):
        raise InputError(
            f"scan: {n} beams from {math.degrees(scan.angle_min):.6g} deg, {math.degrees(scan.angle_increment):.6g} deg "
            "apart, is no LMS200 variant's scan (181 or 361 beams from -90 deg at 1 or 0.5 deg; 101, 201 or 401 from "
            "-50 deg at 1, 0.5 or 0.25 deg): a 0xB0 telegram carries no angles, its beam count gives them; resample "
            "it onto a variant (lms200.virtual.resample_to_grid and variant_codes, as the virtual device does)")
    return encode_measurement(ranges_to_codes(scan.ranges, units), units, status)


def scan_telegram_seconds(n_values: int, baud: float) -> float:
    """Line time (s) of one 0xB0 scan telegram of ``n_values`` beams at ``baud``: header, payload and
    CRC (361 beams: 732 bytes, 0.19 s at 38400 baud, 0.76 s at 9600)."""
    payload = encode_measurement(np.zeros(check_integer(n_values, "n_values", 1), np.uint16), "mm")
    return frame_seconds(len(payload) + OVERHEAD_BYTES, baud)


#: rad: how far a scan's angle_min (absolute) and angle_increment (relative) may lie from its
#: variant's for encode_scan: float32 angles (a bag's) and 6-decimal text are within 1e-6
GEOMETRY_TOLERANCE_RAD = 1e-6


@overload
def frame_seconds(n_bytes: float, baud: float) -> float: ...


@overload
def frame_seconds(n_bytes: np.ndarray, baud: float) -> np.ndarray: ...


def frame_seconds(n_bytes: float | np.ndarray, baud: float) -> float | np.ndarray:
    """Time ``n_bytes`` take on the line at ``baud`` (8N1: 10 bits a byte), in seconds; for an
    array of byte counts, an array of times of its shape. InputError for an ``n_bytes`` that is no
    finite real number >= 0 (or array of them) or a ``baud`` that is no finite number > 0 (0 was a
    ZeroDivisionError, None or text a TypeError, 10**400 an OverflowError)."""
    if isinstance(n_bytes, np.ndarray):  # as n_bytes * 10.0 / baud did
        counts = real_vector(n_bytes, "n_bytes", "bytes")
        if (counts < 0).any():
            raise InputError(f"n_bytes: must be >= 0 (bytes), got {shown(n_bytes)}")
        return counts.reshape(n_bytes.shape) * 10.0 / check_number(baud, "baud", 0.0, math.inf, lo_open=True)
    return check_number(n_bytes, "n_bytes", 0.0, math.inf) * 10.0 / check_number(baud, "baud", 0.0, math.inf, lo_open=True)
