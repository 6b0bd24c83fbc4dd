"""Compression bombs: a ROS 1 bag whose bz2 or lz4 chunk, or a ROS 2 bag whose zstd message,
decompresses to far more than its size. rosbags decompresses each whole, in memory; lms200.bag
bounds it (MAX_DECOMPRESSED_BYTES) and refuses the bag naming it, never reading it into memory."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from lms200 import Record, Scan, read_log, write_log
from lms200.bag import BagError, BagTooLargeError
from lms200.errors import LmsbenchError

ROOT = Path(__file__).resolve().parents[1]
MiB = 2**20


def _records(n: int = 3) -> list[Record]:
    return [Record(scan=Scan(np.full(5, 1.0), -0.1, 0.05, 0.0, 8.0, stamp=float(k))) for k in range(n)]


def _lz4_bomb(data: bytes, zeros_mib: int) -> bytes:
    """One lz4 frame holding ``data`` and then ``zeros_mib`` MiB of zeros (independent 4 MiB blocks,
    each 16 KB compressed: the frame is built, not compressed whole)."""
    import lz4.frame

    kw = dict(block_size=lz4.frame.BLOCKSIZE_MAX4MB, block_linked=False, store_size=False, content_checksum=False)
    frame = lz4.frame.compress(bytes(4 * MiB), **kw)  # a 7-byte header (4 MiB blocks), one block, a 4-byte end mark
    return frame[:7] + lz4.frame.compress(data, **kw)[7:-4] + frame[7:-4] * (zeros_mib // 4) + frame[-4:]


def _bz2_bomb(data: bytes, zeros_mib: int) -> bytes:
    """``data``'s bz2 stream and then ``zeros_mib`` streams of 1 MiB of zeros (about 45 bytes each);
    ``bz2.decompress`` (rosbags') reads every stream."""
    import bz2

    return bz2.compress(data, 9) + bz2.compress(bytes(MiB), 9) * zeros_mib


def _ros1_bomb(path: Path, kind: str, zeros_mib: int, monkeypatch) -> Path:
    """A ROS 1 bag of three scans (write_log) in one chunk compressed as ``kind``, with zeros after them."""
    import rosbags.rosbag1 as rosbag1

    base = rosbag1.Writer

    class Bomb(base):  # type: ignore[misc, valid-type]
        def __init__(self, *args, **kwargs) -> None:
            super().__init__(*args, **kwargs)
            self.set_compression(base.CompressionFormat[kind.upper()])
            self.compressor = lambda data: (_lz4_bomb if kind == "lz4" else _bz2_bomb)(data, zeros_mib)

    with monkeypatch.context() as m:
        m.setattr(rosbag1, "Writer", Bomb)
        write_log(path, _records())
    return path


def _ros2_bomb(path: Path, zeros_mib: int, monkeypatch) -> Path:
    """A ROS 2 bag of three scans, each message zstd-compressed (compression_mode: message) with
    ``zeros_mib`` frames of 1 MiB of zeros after it."""
    import rosbags.rosbag2 as rosbag2
    from rosbags.rosbag2 import writer as writer2

    zstd = writer2.zstd
    base = rosbag2.Writer
    zeros = zstd.compress(bytes(MiB))

    class Bomb(base):  # type: ignore[misc, valid-type]
        def __init__(self, *args, **kwargs) -> None:
            super().__init__(*args, **kwargs)
            self.set_compression(rosbag2.CompressionMode.MESSAGE, rosbag2.CompressionFormat.ZSTD)

    class BombZstd:
        def __getattr__(self, name):
            return getattr(zstd, name)

        @staticmethod
        def compress(data: bytes) -> bytes:
            return zstd.compress(data) + zeros * zeros_mib

    with monkeypatch.context() as m:
        m.setattr(rosbag2, "Writer", Bomb)
        m.setattr(writer2, "zstd", BombZstd())
        write_log(path, _records(), fmt="bag2")
    return path


def _refused_at_the_bound(bag, bound: str, monkeypatch, message: str) -> None:
    """With ``lms200.bag``'s ``bound`` at 4 MiB, reading ``bag`` is the BagTooLargeError
    ``message``, with or without skip_bad_lines (not a damaged message to skip)."""
    import lms200.bag

    monkeypatch.setattr(lms200.bag, bound, 4 * MiB)
    with pytest.raises(BagTooLargeError) as e:
        list(read_log(bag))
    assert str(e.value) == message
    with pytest.raises(BagTooLargeError):
        list(read_log(bag, skip_bad_lines=True))


@pytest.mark.parametrize("kind", ["bz2", "lz4"])
def test_a_ros1_bomb_chunk_is_refused_naming_the_bag(tmp_path, monkeypatch, kind):
    import lms200.bag

    bag = _ros1_bomb(tmp_path / "bomb.bag", kind, 8, monkeypatch)
    assert bag.stat().st_size < 200_000  # 8 MiB of zeros after the scans
    _refused_at_the_bound(bag, "MAX_DECOMPRESSED_BYTES", monkeypatch, (
        f"{bag}: a{'n' if kind == 'lz4' else ''} {kind} chunk decompresses to more than 4 MiB "
        "(lms200.bag.MAX_DECOMPRESSED_BYTES): a compression bomb, or chunks or messages far "
        "larger than a bag of laser scans holds; not read"))
    monkeypatch.setattr(lms200.bag, "MAX_DECOMPRESSED_BYTES", 16 * MiB)  # within the bound: read as ever
    assert [r.scan.stamp for r in read_log(bag)] == [0.0, 1.0, 2.0]


def test_a_ros2_bomb_message_is_refused_naming_the_bag(tmp_path, monkeypatch):
    import lms200.bag

    bag = _ros2_bomb(tmp_path / "bomb2", 8, monkeypatch)
    monkeypatch.setattr(lms200.bag, "MAX_DECOMPRESSED_BYTES", 4 * MiB)
    with pytest.raises(BagTooLargeError, match=r"^" + str(bag) + r": topic /scan after message 0: a zstd-compressed "
                       r"message decompresses to more than 4 MiB \(lms200.bag.MAX_DECOMPRESSED_BYTES\)"):
        list(read_log(bag))
    plain = _ros2_bomb(tmp_path / "plain2", 0, monkeypatch)  # zstd-compressed messages, no bomb: read as ever
    assert [r.scan.stamp for r in read_log(plain)] == [0.0, 1.0, 2.0]


CHILD = r"""
import resource, sys
from lms200 import read_log
from lms200.bag import BagError
import lz4.frame, bz2, rosbags.rosbag1, rosbags.highlevel  # loaded before the limit
status = dict(line.split(":", 1) for line in open("/proc/self/status"))
limit = int(status["VmSize"].split()[0]) * 1024 + LIMIT_MB * 2**20
resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
try:
    n = len(list(read_log(sys.argv[1])))
    print("read", n)
except BagError as exc:
    print(type(exc).__name__, exc)
except MemoryError:
    print("MemoryError")
"""
LIMIT_MB = 400  # MAX_DECOMPRESSED_BYTES (128 MiB) twice over, and room


def test_a_1_gib_lz4_bomb_is_refused_within_bounded_memory(tmp_path, monkeypatch):
    """A 4 MB bag whose one lz4 chunk holds 1 GiB: read in a process of at most 400 MB more
    address space than it started with (it was a MemoryError there, and 1 GiB resident without)."""
    bag = _ros1_bomb(tmp_path / "big.bag", "lz4", 1024, monkeypatch)
    assert bag.stat().st_size < 5 * MiB
    out = subprocess.run([sys.executable, "-c", CHILD.replace("LIMIT_MB", str(LIMIT_MB)), str(bag)], cwd=ROOT,
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith(f"BagTooLargeError {bag}: an lz4 chunk decompresses to more than 128 MiB "), out.stdout


def _ros2_file_bomb(path: Path, zeros_mib: int, monkeypatch) -> Path:
    """A file-compressed ROS 2 bag (compression_mode: file, zstd) of three scans whose storage file
    decompresses to the sqlite3 file and then ``zeros_mib`` MiB of zeros (which sqlite3 reads past)."""
    import rosbags.rosbag2 as rosbag2
    from rosbags.rosbag2 import writer as writer2

    base = rosbag2.Writer

    class FileCompressed(base):  # type: ignore[misc, valid-type]
        def __init__(self, *args, **kwargs) -> None:
            super().__init__(*args, **kwargs)
            self.set_compression(rosbag2.CompressionMode.FILE, rosbag2.CompressionFormat.ZSTD)

    with monkeypatch.context() as m:
        m.setattr(rosbag2, "Writer", FileCompressed)
        write_log(path, _records(), fmt="bag2")
    (storage,) = path.glob("*.zstd")
    zstd = writer2.zstd
    c = zstd.ZstdCompressor()
    storage.write_bytes(c.compress(zstd.decompress(storage.read_bytes()))
                        + b"".join(c.compress(bytes(MiB)) for _ in range(zeros_mib)) + c.flush())
    return path


def test_a_file_compressed_ros2_bomb_is_refused_before_it_fills_the_disk(tmp_path, monkeypatch):
    """rosbags decompresses a file-compressed ROS 2 bag's storage file whole to a temporary file,
    bounded in memory but not on disk: a 2 KB file of 16 MiB of zeros wrote all 16 MiB (a bomb of a
    few MB, the disk). It is refused once more than MAX_DECOMPRESSED_FILE_BYTES are decompressed,
    naming the file, and the temporary file is removed."""
    import tempfile

    import lms200.bag

    bag = _ros2_file_bomb(tmp_path / "bomb2", 16, monkeypatch)
    assert sum(p.stat().st_size for p in bag.iterdir()) < 10_000
    temp = tmp_path / "temp"
    temp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(temp))
    _refused_at_the_bound(bag, "MAX_DECOMPRESSED_FILE_BYTES", monkeypatch, (
        f"{bag / 'bomb2.db3.zstd'}: a zstd-compressed storage file (compression_mode: file) "
        "decompresses to more than 4 MiB (lms200.bag.MAX_DECOMPRESSED_FILE_BYTES): a compression "
        "bomb, or a bag far larger than one of laser scans; not read"))
    assert list(temp.iterdir()) == []
    monkeypatch.setattr(lms200.bag, "MAX_DECOMPRESSED_FILE_BYTES", 32 * MiB)  # within the bound: read as ever
    assert [r.scan.stamp for r in read_log(bag)] == [0.0, 1.0, 2.0]


def test_a_file_compressed_ros2_bag_is_refused_before_it_leaves_the_temporary_folder_short(tmp_path, monkeypatch):
    """The decompression leaves MIN_FREE_TEMP_BYTES free in the temporary folder, or half of what was
    free at its start where that is less: a bag of a few KB was refused on a folder with 900 MiB free
    (review), whatever its size."""
    import tempfile

    import lms200.bag

    bag = _ros2_file_bomb(tmp_path / "bomb2", 16, monkeypatch)

    def refused(free: int, reserve_mib: int) -> None:
        monkeypatch.setattr(lms200.bag, "_free_temp_bytes", lambda: free)
        with pytest.raises(BagTooLargeError, match=r"^" + str(bag / "bomb2.db3.zstd") + r": a zstd-compressed storage "
                           r"file \(compression_mode: file\), decompressed to the temporary folder " + tempfile.gettempdir()
                           + rf" \(where rosbags reads it\), would leave less than {reserve_mib} MiB free there "
                           r"\(lms200.bag.MIN_FREE_TEMP_BYTES, or half the free space at the start; \d+ MiB decompressed "
                           r"so far\); not read \(TMPDIR names a folder with more room\)$"):
            list(read_log(bag))

    refused(24 * MiB, 12)  # half of 24 MiB: refused after 12 of its 16 MiB
    monkeypatch.setattr(lms200.bag, "MIN_FREE_TEMP_BYTES", 8 * MiB)
    refused(20 * MiB, 8)  # the bound where it is less than half
    for free in (900 * MiB, 2 * 1024 * MiB):  # a few MB leave plenty of either
        monkeypatch.setattr(lms200.bag, "_free_temp_bytes", lambda free=free: free)
        assert [r.scan.stamp for r in read_log(bag)] == [0.0, 1.0, 2.0]


def test_a_file_compressed_ros2_bomb_is_one_line_and_status_2_from_the_command(tmp_path, monkeypatch, capsys):
    import lms200.bag
    from experiments.cli import main

    bag = _ros2_file_bomb(tmp_path / "bomb2", 8, monkeypatch)
    monkeypatch.setattr(lms200.bag, "MAX_DECOMPRESSED_FILE_BYTES", 4 * MiB)
    assert main(["info", str(bag)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"lmsbench info: error: {bag / 'bomb2.db3.zstd'}: a zstd-compressed storage file ")
    assert err.count("\n") == 1


def test_a_ros2_metadata_yaml_too_big_to_parse_is_refused_unread(tmp_path, capsys) -> None:
    """Found by fuzzing: a ROS 2 bag's metadata.yaml was parsed whole three times (the command line's
    check, the reader's and rosbags'), in pure Python: one of 5.5 MB held `lmsbench info` 340 s at
    1 GB resident. Over lms200.bag.MAX_METADATA_BYTES (1 MiB) it is refused before any parse."""
    import re
    import time

    from experiments.cli import main
    from lms200.bag import MAX_METADATA_BYTES, BagError

    bag = tmp_path / "b2"
    write_log(bag, [Record(Scan(np.full(5, 1.0), -0.1, 0.05, 0.0, 8.0, stamp=t)) for t in (1.0, 2.0)], fmt="bag2")
    meta = bag / "metadata.yaml"
    assert [r.scan.stamp for r in read_log(bag)] == [1.0, 2.0]
    with open(meta, "a") as f:
        f.write("# padding\n" * (MAX_METADATA_BYTES // 10))
    message = f"{meta}: {meta.stat().st_size:,} bytes, more than the 1,048,576 a ROS 2 bag's metadata.yaml may hold"
    start = time.monotonic()
    with pytest.raises(BagError, match=re.escape(message)):
        list(read_log(bag))
    assert main(["info", str(bag)]) == 2
    assert capsys.readouterr().err.startswith(f"lmsbench info: error: {message} (refused unread")
    assert time.monotonic() - start < 2  # old: both parsed it (10 s of comments; minutes of content)


def _bag_with_definition(path: Path, extra: int, unindexed: bool = False) -> Path:
    """A ROS 1 bag of two LaserScans whose connection carries LaserScan's message definition and
    ``extra`` bytes of comment lines (a definition's comments are part of it, as ROS writes them);
    ``unindexed``: its index cut off and index_pos 0, as a killed recording leaves it."""
    import math
    import struct

    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC)
    T = ts.types
    msgdef, md5 = ts.generate_msgdef("sensor_msgs/msg/LaserScan")
    line = "# " + "x" * 77 + "\n"
    with Writer(path) as w:
        c = w.add_connection("/scan", "sensor_msgs/msg/LaserScan", typestore=ts,
                             msgdef=msgdef + line * (extra // len(line)), md5sum=md5)
        for k in range(2):
            msg = T["sensor_msgs/msg/LaserScan"](
                header=T["std_msgs/msg/Header"](seq=k, stamp=T["builtin_interfaces/msg/Time"](sec=10 + k, nanosec=0),
                                                 frame_id="laser"),
                angle_min=-math.pi / 2, angle_max=math.pi / 2, angle_increment=math.pi / 360, time_increment=0.0,
                scan_time=0.0, range_min=0.01, range_max=8.0, ranges=np.full(361, 2.0, np.float32),
                intensities=np.zeros(0, np.float32))
            w.write(c, (10 + k) * 10**9, ts.serialize_ros1(msg, "sensor_msgs/msg/LaserScan"))
    if unindexed:
        data = bytearray(path.read_bytes())
        at = data.index(b"index_pos=") + 10
        index_pos = struct.unpack("<Q", data[at:at + 8])[0]
        data[at:at + 8] = bytes(8)
        path.write_bytes(bytes(data[:index_pos]))
    return path


@pytest.mark.parametrize("unindexed", [False, True], ids=["indexed", "unindexed"])
def test_a_ros1_connection_of_an_absurd_message_definition_is_refused_unread(tmp_path, capsys, unindexed) -> None:
    """Review: a ROS 1 bag whose LaserScan connection carried a 5.6 MB message definition held
    `lmsbench info` 6 s at 65 MB as comment lines (rosbags parses the definition, up to 50 bytes of memory a byte;
    58 s and 340 MB as field lines). A connection of more than lms200.bag.MAX_CONNECTION_BYTES
    (256 KiB; a definition is a few KB) is refused from the record lengths, before rosbags reads it."""
    import re
    import warnings

    from experiments.cli import main
    from lms200.bag import MAX_CONNECTION_BYTES

    ok = _bag_with_definition(tmp_path / "ok.bag", 100_000, unindexed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the unindexed bag's recovery warning
        assert [r.scan.stamp for r in read_log(ok)] == [10.0, 11.0]
    bag = _bag_with_definition(tmp_path / "big.bag", MAX_CONNECTION_BYTES, unindexed)
    with pytest.raises(BagTooLargeError, match=re.escape(f"{bag}: connection 0 (/scan) holds ")):
        list(read_log(bag))
    assert main(["info", str(bag)]) == 2  # old: exit 0 after parsing it
    err = capsys.readouterr().err
    assert re.fullmatch(rf"lmsbench info: error: {re.escape(str(bag))}: connection 0 \(/scan\) holds 262,\d{{3}} bytes of "
                        r"type, md5sum and message definition, more than the 262,144 a ROS 1 bag's connection may "
                        r"\(lms200.bag.MAX_CONNECTION_BYTES\): an absurd message definition, or damage; not read\n", err)


def test_a_connection_records_header_too_long_is_worded_as_its_header() -> None:
    """A review: a connection record whose header (op, conn and topic) passed the bound was said to
    hold that many "bytes of type, md5sum and message definition", which its header does not hold."""
    from lms200.bag import _connection_too_large

    assert str(_connection_too_large("x.bag", None, None, 300_000)) == (
        "x.bag: a connection record's header (its op, conn and topic) holds 300,000 bytes, more than the 262,144 a "
        "ROS 1 bag's connection may (lms200.bag.MAX_CONNECTION_BYTES): damage; not read")


def _laser_scan(ts, **header):  # noqa: ANN001, ANN003, ANN202
    """A LaserScan message of ``ts`` (a rosbags typestore) at 10 s: 361 beams over 180 deg, all 2 m;
    ``header``: fields a ROS 1 header adds (seq)."""
    import math

    T = ts.types
    return T["sensor_msgs/msg/LaserScan"](
        header=T["std_msgs/msg/Header"](**header, stamp=T["builtin_interfaces/msg/Time"](sec=10, nanosec=0),
                                        frame_id="laser"),
        angle_min=-math.pi / 2, angle_max=math.pi / 2, angle_increment=math.pi / 360, time_increment=0.0,
        scan_time=0.0, range_min=0.01, range_max=8.0, ranges=np.full(361, 2.0, np.float32),
        intensities=np.zeros(0, np.float32))


def _bag_with_connections(path: Path, definitions: list[str], one_type: bool = False, type_name: str = "") -> Path:
    """A ROS 1 bag of one LaserScan on /scan and a connection /junkJ of type junk_msgs/msg/JJ with
    each of ``definitions`` (its message definition); ``one_type``: all of type junk_msgs/msg/J0;
    ``type_name``: all of that type (one lmsbench reads, whose definitions it parses)."""
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC)
    msgdef, md5 = ts.generate_msgdef("sensor_msgs/msg/LaserScan")
    with Writer(path) as w:
        c = w.add_connection("/scan", "sensor_msgs/msg/LaserScan", typestore=ts, msgdef=msgdef, md5sum=md5)
        for j, definition in enumerate(definitions):
            name = type_name or f"junk_msgs/msg/J{0 if one_type else j}"
            own = get_typestore(Stores.EMPTY)
            own.register(get_types_from_msg(definition, name))
            w.add_connection(f"/junk{j}", name, msgdef=definition, md5sum=own.generate_msgdef(name)[1])
        w.write(c, 10 * 10**9, ts.serialize_ros1(_laser_scan(ts, seq=0), "sensor_msgs/msg/LaserScan"))
    return path


def test_a_bags_message_definitions_are_bounded_together(tmp_path, capsys, monkeypatch) -> None:
    """A review: the bound of one connection's definition (256 KiB) did not bound the cost, most of
    which is rosbags registering the types (code generated for each field), nor a bag's connections
    together: one connection of 250 KB of field lines held `lmsbench info` 13 s at 280 MB, three 44 s
    at 556 MB. The distinct definitions of a bag together may hold MAX_DEFINITION_FIELDS field lines
    (4,096) and MAX_DEFINITIONS_BYTES characters, every IDL section counted; a ROS 1 bag's connection
    records together MAX_CONNECTIONS_TOTAL_BYTES. Here three connections of 1,500 field lines each
    (each alone well under every bound) are refused before rosbags registers them."""
    import re
    import struct

    from experiments.cli import main

    fields = "".join(f"int32 f{i}\n" for i in range(1500))
    registered = []
    ok = _bag_with_connections(tmp_path / "ok.bag", [fields] * 3, one_type=True)  # one definition, three connections
    assert [r.scan.stamp for r in read_log(ok)] == [10.0]
    definitions = [fields, fields + "int32 g\n", fields + "int32 h\n"]
    import rosbags.typesys.store as store

    real_register = store.Typestore.register
    monkeypatch.setattr(store.Typestore, "register", lambda self, typs: (registered.append(len(typs)),
                                                                          real_register(self, typs))[1])
    # of types lmsbench does not read, the definitions are not parsed (fuzz round 8: see test_bags)
    junk = _bag_with_connections(tmp_path / "junk.bag", definitions)
    registered.clear()
    assert main(["info", str(junk)]) == 0
    assert registered and max(registered) < 20  # LaserScan's types alone
    capsys.readouterr()
    bag = _bag_with_connections(tmp_path / "many.bag", definitions, type_name="nav_msgs/msg/Odometry")
    registered.clear()
    assert main(["info", str(bag)]) == 2  # old: exit 0 after registering 4,500 fields
    err = capsys.readouterr().err
    assert re.fullmatch(rf"lmsbench info: error: {re.escape(str(bag))}: nav_msgs/msg/Odometry's message definition brings the "
                        r"field lines of the bag's message definitions to 4,515, more than the 4,096 a bag's may "
                        r"\(lms200.bag.MAX_DEFINITION_FIELDS; the 164 ROS Noetic types, each with the definitions it nests, total "
                        r"2,011\): absurd message "
                        r"definitions, or damage; not parsed\n", err)
    assert registered == []  # refused before rosbags registers a type (old: [8], 4,500 fields with LaserScan's)
    # a ROS 1 bag's connection records together, told from the index before rosbags reads them
    monkeypatch.setattr("lms200.bag.MAX_CONNECTIONS_TOTAL_BYTES", 20_000)
    comments = "# " + "x" * 77 + "\n"
    big = _bag_with_connections(tmp_path / "big.bag", [comments * 150] * 2)
    assert main(["info", str(big)]) == 2
    err = capsys.readouterr().err
    assert re.fullmatch(rf"lmsbench info: error: {re.escape(str(big))}: its 3 connections hold 2\d,\d{{3}} bytes of type, "
                        r"md5sum and message definition together, more than the 20,000 a ROS 1 bag's may "
                        r"\(lms200.bag.MAX_CONNECTIONS_TOTAL_BYTES\): absurd message definitions, or damage; not read\n", err)
    # a bag never closed: the connection records as its chunks give them (each connection once)
    data = bytearray(big.read_bytes())
    at = data.index(b"index_pos=") + 10
    index_pos = struct.unpack("<Q", data[at:at + 8])[0]
    data[at:at + 8] = bytes(8)
    cut = tmp_path / "cut.bag"
    cut.write_bytes(bytes(data[:index_pos]))
    assert main(["info", str(cut)]) == 2
    err = capsys.readouterr().err
    assert re.fullmatch(rf"lmsbench info: error: {re.escape(str(cut))}: its 3 connections hold 2\d,\d{{3}} bytes of type, "
                        r"md5sum and message definition together, more than the 20,000 a ROS 1 bag's may "
                        r"\(lms200.bag.MAX_CONNECTIONS_TOTAL_BYTES\): absurd message definitions, or damage; not read\n", err)


def test_a_rosbags_without_a_parser_lmsbench_bounds_still_reads_bags(tmp_path, monkeypatch) -> None:
    """A review: the bound looked up rosbags' parsers by name (getattr without a default): a rosbags
    without one of them failed every bag open with AttributeError. Such a name is now left alone."""
    from rosbags.highlevel import anyreader

    monkeypatch.delattr(anyreader, "get_types_from_idl")
    fields = "int32 a\n"
    bag = _bag_with_connections(tmp_path / "ok.bag", [fields])
    assert [r.scan.stamp for r in read_log(bag)] == [10.0]  # old: AttributeError


def _ros2_bag_with_definition(path: Path, extra: str) -> Path:
    """A ROS 2 bag (sqlite3) at ``path`` of one LaserScan whose stored message definition is
    LaserScan's own followed by ``extra`` (comment lines)."""
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    msgdef, _ = ts.generate_msgdef("sensor_msgs/msg/LaserScan", ros_version=2)
    with Writer(path, version=8) as w:
        c = w.add_connection("/scan", "sensor_msgs/msg/LaserScan", typestore=ts,
                             msgdef=msgdef + extra, rihs01=ts.hash_rihs01("sensor_msgs/msg/LaserScan"))
        w.write(c, 10 * 10**9, ts.serialize_cdr(_laser_scan(ts), "sensor_msgs/msg/LaserScan"))
    return path


def test_a_bag_named_like_words_of_the_message_is_still_named(tmp_path, capsys, monkeypatch) -> None:
    """A review: whether an error named the bag was told by the bag's path appearing anywhere in the
    message: a ROS 2 bag folder named `bag` (or msg, a, data) matched words of the message, so
    `lmsbench info bag` said "error: sensor_msgs/msg/LaserScan's message definition holds ...", naming
    no file. Errors that name no file are now marked so."""
    from experiments.cli import main

    monkeypatch.chdir(tmp_path)
    _ros2_bag_with_definition(Path("bag"), ("# a bag's msg " + "x" * 65 + "\n") * 3400)
    assert main(["info", "bag"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("lmsbench info: error: bag: sensor_msgs/msg/LaserScan's message definition holds ")  # old: no "bag: "


def test_a_ros2_bags_absurd_message_definition_is_refused_unparsed(tmp_path, capsys) -> None:
    """The same in a ROS 2 bag, whose message definitions come from its storage file (sqlite3 here):
    one of 5.6 MB of comment lines held `lmsbench info` 4.5 s at 63 MB. A definition of more than
    MAX_CONNECTION_BYTES characters is refused before rosbags parses it."""
    import re

    from experiments.cli import main
    from lms200.bag import MAX_CONNECTION_BYTES

    line = "# " + "x" * 77 + "\n"
    for name, extra in (("ok", 100_000), ("big", MAX_CONNECTION_BYTES)):
        _ros2_bag_with_definition(tmp_path / name, line * (extra // len(line)))
    assert [r.scan.stamp for r in read_log(tmp_path / "ok")] == [10.0]
    bag = tmp_path / "big"
    assert main(["info", str(bag)]) == 2  # old: exit 0 after parsing it
    err = capsys.readouterr().err
    assert re.fullmatch(rf"lmsbench info: error: {re.escape(str(bag))}: sensor_msgs/msg/LaserScan's message definition "
                        r"holds 262,\d{3} characters, more than the 262,144 a bag's may \(lms200.bag.MAX_CONNECTION_BYTES\): "
                        r"an absurd message definition, or damage; not parsed\n", err)


LASERSCAN_IDL = '''// generated from rosidl_adapter/resource/msg.idl.em
// with input from sensor_msgs/msg/LaserScan.msg
// generated code does not contain a copyright notice

#include "std_msgs/msg/Header.idl"

module sensor_msgs {
  module msg {
    @verbatim (language="comment", text=
      "Single scan from a planar laser range-finder" "\\n"
      "" "\\n"
      "If you have another ranging device with different behavior (e.g. a sonar" "\\n"
      "array), please find or create a different message, since applications" "\\n"
      "will make fairly laser-specific assumptions about this data")
    struct LaserScan {
      @verbatim (language="comment", text=
        "timestamp in the header is the acquisition time of" "\\n"
        "the first ray in the scan." "\\n"
        "" "\\n"
        "in frame frame_id, angles are measured around" "\\n"
        "the positive Z axis (counterclockwise, if Z is up)" "\\n"
        "with zero angle being forward along the x axis")
      std_msgs::msg::Header header;

      @verbatim (language="comment", text=
        "start angle of the scan [rad]")
      @unit (value="rad")
      float angle_min;

      @verbatim (language="comment", text=
        "end angle of the scan [rad]")
      float angle_max;

      @default (value=0.0) float range_min;

      sequence<float> ranges;
    };
  };
};
'''


def test_idl_comment_and_annotation_lines_are_not_counted_as_fields():
    """A ros2idl definition carries every .msg comment as an @verbatim annotation of quoted-string lines:
    _field_lines counted each (this snippet 29 lines for its 5 fields), so real ROS 2 definitions met
    MAX_DEFINITION_FIELDS 5-8x sooner than their fields. A declaration behind an annotation on its line counts."""
    from lms200.bag import _field_lines

    # 2 modules, struct, 5 declarations, 3 closing braces (#include reads as a MSG comment); no @verbatim, @unit
    # or quoted line (old: 29)
    assert _field_lines(LASERSCAN_IDL) == 11
    assert _field_lines("uint32 seq\n# a comment\ntime stamp\n\nstring frame_id\n") == 3  # MSG as before


def _ros2_bag_of_topics(path: Path, topics: int, storage: str = "sqlite3", types: tuple[str, ...] = ()) -> Path:
    """A ROS 2 bag at ``path`` of ``topics`` LaserScan topics (one definition), one message on the first,
    and a topic /otherK of each of ``types``."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=8, storage_plugin=plugin) as w:
        conns = [w.add_connection(f"/scan{k}", "sensor_msgs/msg/LaserScan", typestore=ts) for k in range(topics)]
        for k, typ in enumerate(types):
            w.add_connection(f"/other{k}", typ, typestore=ts)
        w.write(conns[0], 10 * 10**9, ts.serialize_cdr(_laser_scan(ts), "sensor_msgs/msg/LaserScan"))
    return path


def test_a_ros2_bags_topics_and_definitions_are_bounded_in_number_and_size(tmp_path, capsys, monkeypatch) -> None:
    """A review: a ROS 2 bag's message definitions were bounded per definition and as distinct ones
    parsed, but the rows rosbags reads from the storage file (every topic, every message_definitions
    row, every mcap schema and channel) only by the file's size: 20,000 rows of one definition read
    whole. A storage file may list MAX_CONNECTIONS topics and as many definitions, holding
    MAX_CONNECTIONS_TOTAL_BYTES characters together (here lowered to keep the bags small)."""
    import sqlite3

    from experiments.cli import main

    monkeypatch.setattr("lms200.bag.MAX_CONNECTIONS", 4, raising=False)  # raising: the old code had none
    ok = _ros2_bag_of_topics(tmp_path / "ok", 4)
    assert [r.scan.stamp for r in read_log(ok, topic="/scan0")] == [10.0]
    for storage, which in (("sqlite3", "many.db3 lists 5 topics, more than the 4"),
                           ("mcap", "many.mcap lists more than 4 topics (channels), the most")):
        bag = _ros2_bag_of_topics(tmp_path / "many", 5, storage)
        assert main(["info", str(bag), "--topic", "/scan0"]) == 2  # old: exit 0
        err = capsys.readouterr().err
        assert err == (f"lmsbench info: error: {bag}: its storage file {which} a ROS 2 bag's may "
                       "(lms200.bag.MAX_CONNECTIONS): absurd, or damage; not read\n"), err
        import shutil

        shutil.rmtree(bag)
    # one definition repeated in rows of message_definitions: each row is read, whatever its text
    one = _ros2_bag_of_topics(tmp_path / "one", 1)
    db = sqlite3.connect(one / "one.db3")
    row = db.execute("SELECT topic_type, encoding, encoded_message_definition, type_description_hash "
                     "FROM message_definitions").fetchone()
    size = len(row[2]) + sum(len(v) for v in (row[0], row[1], row[3]))
    db.executemany("INSERT INTO message_definitions (topic_type, encoding, encoded_message_definition, "
                   "type_description_hash) VALUES (?, ?, ?, ?)", [row] * 4)
    db.commit()
    db.close()
    assert main(["info", str(one)]) == 2  # old: exit 0
    assert capsys.readouterr().err == (f"lmsbench info: error: {one}: its storage file one.db3 lists 5 message definitions, "
                                       "more than the 4 a ROS 2 bag's may (lms200.bag.MAX_CONNECTIONS): absurd, or damage; "
                                       "not read\n")
    monkeypatch.setattr("lms200.bag.MAX_CONNECTIONS", 4096)
    monkeypatch.setattr("lms200.bag.MAX_CONNECTIONS_TOTAL_BYTES", 4 * size)
    topic = _sqlite_chars(one / "one.db3")[0]
    assert main(["info", str(one)]) == 2
    assert capsys.readouterr().err == (f"lmsbench info: error: {one}: its storage file one.db3's 1 topics and 5 message "
                                       f"definitions hold {topic + 5 * size:,} characters together, more than the "
                                       f"{4 * size:,} a ROS 2 bag's may (lms200.bag.MAX_CONNECTIONS_TOTAL_BYTES): absurd "
                                       "message definitions, or damage; not read\n")


def _sqlite_chars(db3: Path) -> tuple[int, int]:
    """The characters of a sqlite3 storage file's topics and of its message definitions, as lms200.bag counts them."""
    import sqlite3

    db = sqlite3.connect(db3)
    try:
        topics = db.execute("SELECT sum(length(name) + length(type) + length(serialization_format) + "
                            "length(offered_qos_profiles) + length(type_description_hash)) FROM topics").fetchone()[0]
        defs = db.execute("SELECT sum(length(topic_type) + length(encoding) + length(encoded_message_definition) + "
                          "length(type_description_hash)) FROM message_definitions").fetchone()[0]
    finally:
        db.close()
    return topics, defs


def _mcap_chars(mcap: Path) -> tuple[int, int]:
    """The characters of an mcap storage file's channels and of its schemas, as lms200.bag counts them."""
    from rosbags.rosbag2.storage_mcap import McapReader

    reader = McapReader(mcap)
    reader.open()
    try:
        def held(records: dict) -> int:  # noqa: ANN001
            return sum(len(v) for r in records.values() for v in tuple(r)[1:] if isinstance(v, (str, bytes)))

        return held(reader.channels), held(reader.schemas)
    finally:
        reader.close()


OTHER_TYPES = ("std_msgs/msg/String", "std_msgs/msg/Int32", "geometry_msgs/msg/Point")


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_a_ros2_storage_file_of_max_connections_distinct_types_is_read(tmp_path, monkeypatch, storage) -> None:
    """A review: rosbags' mcap reader makes a default Schema(0, '__schemaless__', ...) for each channel
    (``schemas.get(id, default)`` evaluates it), which was counted as one more schema: 4 distinct types
    under MAX_CONNECTIONS = 4 were refused ("lists 5 message definitions (schemas)") while the sqlite3
    file of the same bag was read. Both read it; a fifth type is refused in both, the mcap file named."""
    monkeypatch.setattr("lms200.bag.MAX_CONNECTIONS", 4)
    bag = _ros2_bag_of_topics(tmp_path / "four", 1, storage, OTHER_TYPES)
    assert [r.scan.stamp for r in read_log(bag, topic="/scan0")] == [10.0]  # mcap old: BagTooLargeError
    bag = _ros2_bag_of_topics(tmp_path / "five", 1, storage, OTHER_TYPES + ("std_msgs/msg/Bool",))
    which = ("five.db3 lists 5 topics, more than the 4" if storage == "sqlite3"
             else "five.mcap lists more than 4 message definitions (schemas), the most")
    with pytest.raises(BagTooLargeError) as exc:
        list(read_log(bag, topic="/scan0"))
    assert str(exc.value) == (f"{bag}: its storage file {which} a ROS 2 bag's may (lms200.bag.MAX_CONNECTIONS): "
                              "absurd, or damage; not read")


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_a_ros2_storage_files_topics_and_definitions_are_bounded_in_one_total(tmp_path, monkeypatch, storage) -> None:
    """A review: docs/data.md bounds the characters of a storage file's topics and message definitions
    together (MAX_CONNECTIONS_TOTAL_BYTES), but the topics (channels) and the definitions (schemas)
    were checked each on its own, so up to twice the bound was read. They count in one total."""
    bag = _ros2_bag_of_topics(tmp_path / "b", 3, storage, OTHER_TYPES)
    file = bag / f"b.{'db3' if storage == 'sqlite3' else 'mcap'}"
    topics, defs = (_sqlite_chars if storage == "sqlite3" else _mcap_chars)(file)
    assert topics > 0 and defs > 0
    monkeypatch.setattr("lms200.bag.MAX_CONNECTIONS_TOTAL_BYTES", topics + defs)
    assert [r.scan.stamp for r in read_log(bag, topic="/scan0")] == [10.0]  # at the bound: read
    monkeypatch.setattr("lms200.bag.MAX_CONNECTIONS_TOTAL_BYTES", topics + defs - 1)  # above each alone
    assert max(topics, defs) <= topics + defs - 1
    with pytest.raises(BagTooLargeError) as exc:  # old: read
        list(read_log(bag, topic="/scan0"))
    hold = (f"b.db3's 6 topics and 4 message definitions hold {topics + defs:,} characters together, more than the "
            f"{topics + defs - 1:,}" if storage == "sqlite3" else
            f"b.mcap's topics (channels) and message definitions (schemas) hold more than {topics + defs - 1:,} "
            "characters together, the most")
    assert str(exc.value) == (f"{bag}: its storage file {hold} a ROS 2 bag's may "
                              "(lms200.bag.MAX_CONNECTIONS_TOTAL_BYTES): absurd message definitions, or damage; not read")


def _mcap_with_declared_record(path: Path, op: int, declared: int) -> Path:
    """A ROS 2 mcap bag (one LaserScan topic, one message) whose data section starts with a record of
    opcode ``op`` (3 schema, 4 channel) declaring ``declared`` bytes, of which it holds a few; the footer's
    summary offset cleared, so the reader scans the data section."""
    import struct

    bag = _ros2_bag_of_topics(path, 1, "mcap")
    mcap = next(bag.glob("*.mcap"))
    data = mcap.read_bytes()
    end_header = 8 + 1 + 8 + struct.unpack_from("<Q", data, 9)[0]
    record = bytes([op]) + struct.pack("<Q", declared) + struct.pack("<HH", 9, 1) + b"\0" * 16
    footer = data[-37:-28] + struct.pack("<Q", 0) + data[-20:]
    mcap.write_bytes(data[:end_header] + record + data[end_header:-37] + footer)
    return bag


@pytest.mark.parametrize(("op", "kind"), [(3, "schema"), (4, "channel")])
def test_an_mcap_schema_or_channel_record_of_absurd_length_is_refused_unread(tmp_path, capsys, op, kind) -> None:
    """A review: an mcap file's schema and channel records were counted once read (MAX_CONNECTIONS_TOTAL_BYTES
    together), but rosbags reads each whole first, bounded only by the file's size: a 300 MB schema record
    held `lmsbench info` at 928 MB; one declaring 1 TiB in a 1.5 KB file was `cannot open as a ROS bag:
    MemoryError`. A schema or channel record declaring more than MAX_CONNECTIONS_TOTAL_BYTES is refused
    from its length, before it is read, naming the storage file and the record."""
    from experiments.cli import main

    bag = _mcap_with_declared_record(tmp_path / "b", op, 2**40)
    assert main(["info", str(bag)]) == 2
    err = capsys.readouterr().err
    at = err.index("record at byte ")
    start = int(err[at + len("record at byte "):].split(" ")[0].replace(",", ""))
    assert (bag / "b.mcap").read_bytes()[start] == op  # the record it names
    assert err == (f"lmsbench info: error: {bag}: its storage file b.mcap's {kind} record at byte {start:,} declares "
                   "1,099,511,627,776 bytes, more than the 4,194,304 a ROS 2 bag's topics and message definitions may "
                   "hold together (lms200.bag.MAX_CONNECTIONS_TOTAL_BYTES): an absurd message definition, or damage; "
                   "not read\n"), err
    ok = _ros2_bag_of_topics(tmp_path / "ok", 1, "mcap")  # the same bag without it reads
    assert [r.scan.stamp for r in read_log(ok, topic="/scan0")] == [10.0]


def _mcap_chunk(declared: int, payload: bytes, compression: str = "zstd", record_length: int | None = None) -> bytes:
    """An mcap chunk record declaring ``declared`` bytes uncompressed, holding ``payload`` (already compressed)."""
    import struct

    body = (struct.pack("<QQQI", 0, 0, declared, 0) + struct.pack("<I", len(compression)) + compression.encode()
            + struct.pack("<Q", len(payload)) + payload)
    return bytes([6]) + struct.pack("<Q", len(body) if record_length is None else record_length) + body


def _mcap_with_record(path: Path, record: bytes) -> Path:
    """A ROS 2 mcap bag (one LaserScan topic, one message) with ``record`` first in its data section and the
    footer's summary offset cleared (the reader scans the data section)."""
    import struct

    bag = _ros2_bag_of_topics(path, 1, "mcap")
    mcap = next(bag.glob("*.mcap"))
    data = mcap.read_bytes()
    end_header = 8 + 1 + 8 + struct.unpack_from("<Q", data, 9)[0]
    footer = data[-37:-28] + struct.pack("<Q", 0) + data[-20:]
    mcap.write_bytes(data[:end_header] + record + data[end_header:-37] + footer)
    return bag


def _zstd_frames(data: bytes, frames: int = 1):
    from rosbags.rosbag2 import storage_mcap

    return storage_mcap.zstd.compress(data) * frames


def test_mcap_records_and_chunks_of_absurd_declared_length_are_refused_unread(tmp_path, capsys) -> None:
    """A review: an mcap file's header, chunk and other records were read whole, bounded only by the file's
    size, and its chunks decompressed whole before their declared size was compared: a header or chunk record
    declaring 1 TiB in a 5 KB file was `cannot open as a ROS bag: MemoryError:`, a 300 MB chunk record held
    `lmsbench info` at 648 MB, 37 KB of zstd declaring 1 GiB uncompressed at 2.1 GB (exit 0), and declaring
    1 KiB at 2.1 GB before "Chunk size mismatch". Each is refused from what it declares, naming the storage
    file, a chunk decompressed to one byte past what it declares at most."""
    import struct
    import tracemalloc

    from experiments.cli import main

    header = _ros2_bag_of_topics(tmp_path / "h", 1, "mcap")
    data = bytearray((header / "h.mcap").read_bytes())
    data[9:17] = struct.pack("<Q", 2**40)
    (header / "h.mcap").write_bytes(bytes(data))
    end = (f", more than the {134_283_264:,} a ROS 2 bag's mcap record may hold (lms200.bag.MAX_MCAP_RECORD_BYTES): "
           "damage, or no bag of laser scans; not read\n")
    assert main(["info", str(header)]) == 2
    assert capsys.readouterr().err == (f"lmsbench info: error: {header}: its storage file h.mcap's header record at byte 8 "
                                       f"declares 1,099,511,627,776 bytes{end}")
    chunk = _mcap_with_record(tmp_path / "c", _mcap_chunk(2**30, b"", record_length=2**40))
    assert main(["info", str(chunk)]) == 2
    err = capsys.readouterr().err
    start = int(err.split("chunk record at byte ")[1].split(" ")[0].replace(",", ""))
    assert (chunk / "c.mcap").read_bytes()[start] == 6
    assert err == (f"lmsbench info: error: {chunk}: its storage file c.mcap's chunk record at byte {start:,} declares "
                   f"1,099,511,627,776 bytes{end}")
    huge = _mcap_with_record(tmp_path / "u", _mcap_chunk(2**30, _zstd_frames(bytes(MiB))))
    assert main(["info", str(huge)]) == 2
    assert capsys.readouterr().err == (
        f"lmsbench info: error: {huge}: its storage file u.mcap's chunk declares 1,073,741,824 bytes uncompressed (zstd), "
        f"more than the {128 * MiB:,} a chunk may decompress to (lms200.bag.MAX_DECOMPRESSED_BYTES): damage, or no "
        "bag of laser scans; not read\n")
    bomb = _mcap_with_record(tmp_path / "b", _mcap_chunk(1024, _zstd_frames(bytes(MiB), 64)))  # 64 frames of 1 MiB
    tracemalloc.start()
    try:
        with pytest.raises(BagTooLargeError) as exc:
            list(read_log(bomb))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert str(exc.value) == (f"{bomb}: its storage file b.mcap's zstd chunk decompresses to more than the 1,024 bytes it "
                              "declares: damage, or a compression bomb; not read")
    assert peak < 16 * MiB, peak  # old: the 64 MiB decompressed whole


@pytest.mark.parametrize("compression", ["zstd", "lz4", ""])
def test_mcap_chunks_within_their_declared_size_read_as_before(tmp_path, compression) -> None:
    """The bounded decompression reads a chunk as rosbags does: zstd of several frames, lz4, none."""
    import struct

    import lz4.frame

    inner = bytes([0x80]) + struct.pack("<Q", 3000) + bytes(range(250)) * 12  # a record the reader skips
    payload = {"zstd": lambda: _zstd_frames(inner[:1000]) + _zstd_frames(inner[1000:]),
               "lz4": lambda: lz4.frame.compress(inner), "": lambda: inner}[compression]()
    bag = _mcap_with_record(tmp_path / "ok", _mcap_chunk(len(inner), payload, compression))
    assert [r.scan.stamp for r in read_log(bag, topic="/scan0")] == [10.0]
    bad = _mcap_with_record(tmp_path / "short", _mcap_chunk(len(inner) + 1, payload, compression))
    with pytest.raises(LmsbenchError, match=r"short: .*Chunk size mismatch: expected 3010 bytes, got 3009"):
        list(read_log(bad, topic="/scan0"))


def test_an_indexed_mcap_chunk_that_decompresses_past_its_declared_size_is_refused_naming_the_file(
        tmp_path, monkeypatch) -> None:
    """The same bound where the chunk is read through the file's chunk index, as the messages are iterated
    (msgsrc): 1 GiB of zeros behind two zstd-compressed scans held `lmsbench info` at 2.05 GB before "Chunk size
    mismatch: expected 3669 bytes, got 1048579669"; refused now, naming the storage file, 64 MiB here."""
    import tracemalloc

    from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer, storage_mcap
    from rosbags.typesys import Stores, get_typestore

    zstd, zeros = storage_mcap.zstd, storage_mcap.zstd.compress(bytes(MiB))

    class Bomb:
        def __getattr__(self, name):
            return getattr(zstd, name)

        @staticmethod
        def compress(data: bytes) -> bytes:
            return zstd.compress(data) + zeros * 64

    ts = get_typestore(Stores.ROS2_HUMBLE)
    writer = Writer(tmp_path / "b", version=8, storage_plugin=StoragePlugin.MCAP)
    writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
    with monkeypatch.context() as m:
        m.setattr(storage_mcap, "zstd", Bomb())
        with writer as w:
            conn = w.add_connection("/scan0", "sensor_msgs/msg/LaserScan", typestore=ts)
            for t in (10, 11):
                w.write(conn, t * 10**9, ts.serialize_cdr(_laser_scan(ts), "sensor_msgs/msg/LaserScan"))
    tracemalloc.start()
    try:
        with pytest.raises(BagTooLargeError) as exc:
            list(read_log(tmp_path / "b"))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert re.fullmatch(rf"{tmp_path / 'b'}: topic /scan0 after message 0: its storage file b\.mcap's zstd chunk "
                        r"decompresses to more than the [\d,]+ bytes it declares: damage, or a compression bomb; not read",
                        str(exc.value)), exc.value
    assert peak < 16 * MiB, peak


def test_an_mcap_record_whose_length_runs_past_the_file_is_refused_not_the_scan_ended(tmp_path) -> None:
    """A record between two chunks whose length was damaged (1 TiB) was skipped by a seek past the file's end,
    and the scan stopped there as at the data's end: 1 of the bag's 3 scans read, exit 0. It is refused."""
    import struct

    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)

    def mcap(name: str, stamps: tuple[int, ...]) -> tuple[Path, bytes]:
        with Writer(tmp_path / name, version=8, storage_plugin=StoragePlugin.MCAP) as w:
            conn = w.add_connection("/scan0", "sensor_msgs/msg/LaserScan", typestore=ts)
            for t in stamps:
                w.write(conn, t * 10**9, ts.serialize_cdr(_laser_scan(ts), "sensor_msgs/msg/LaserScan"))
        file = tmp_path / name / f"{name}.mcap"
        return file, file.read_bytes()

    def first_chunk(data: bytes) -> tuple[int, bytes]:
        at = 8 + 1 + 8 + struct.unpack_from("<Q", data, 9)[0]
        return at, data[at: at + 9 + struct.unpack_from("<Q", data, at + 1)[0]]

    _, a = mcap("a", (10,))
    file, b = mcap("b", (11, 12))
    at, chunk_b = first_chunk(b)
    footer = b[-37:-28] + struct.pack("<Q", 0) + b[-20:]  # no summary: the data section is scanned
    damaged = bytes([0x80]) + struct.pack("<Q", 2**40) + bytes(16)
    file.write_bytes(b[:at] + first_chunk(a)[1] + damaged + chunk_b + b[at + len(chunk_b):-37] + footer)
    start = at + len(first_chunk(a)[1]) + 9
    with pytest.raises(LmsbenchError, match=rf"b: cannot open as a ROS bag: AnyReaderError: its storage file b\.mcap's "
                                            rf"record data at byte {start:,} declares 1,099,511,627,776 bytes, past the "
                                            r"end of the file that holds it \([\d,]+ bytes on\): damage; not read$"):
        list(read_log(tmp_path / "b"))
    file.write_bytes(b[:at] + first_chunk(a)[1] + chunk_b + b[at + len(chunk_b):-37] + footer)  # undamaged: 3 scans
    assert len(list(read_log(tmp_path / "b"))) == 3


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_rosbags_used_directly_after_an_lmsbench_read_keeps_its_own_behaviour(tmp_path, monkeypatch, storage) -> None:
    """A review: lms200.bag replaces rosbags functions for the whole process (mcap read_sized / read_exact /
    skip_exact / decompress, the storage readers' _open, McapReader.messages, AnyReader's definition parsers),
    and they applied lmsbench's bounds to every rosbags user after one lmsbench read: a bag over a bound that
    rosbags itself reads was refused by rosbags too (BagTooLargeError from AnyReader). They apply only inside
    lmsbench's own reads."""
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    from lms200 import bag as lbag

    b = _ros2_bag_of_topics(tmp_path / "b", 1, storage)
    monkeypatch.setattr(lbag, "MAX_CONNECTION_BYTES", 10)  # the LaserScan definition is over it
    monkeypatch.setattr(lbag, "MAX_MCAP_RECORD_BYTES", 100)  # and the mcap file's records
    with pytest.raises(BagTooLargeError, match="MAX_CONNECTION_BYTES|MAX_MCAP_RECORD_BYTES"):
        list(read_log(b, topic="/scan0"))
    with AnyReader([b], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        assert [(c.topic, t) for c, t, _ in reader.messages()] == [("/scan0", 10 * 10**9)]
    monkeypatch.undo()
    assert [r.scan.stamp for r in read_log(b, topic="/scan0")] == [10.0]  # lmsbench reads it within its bounds


@pytest.mark.parametrize(("change", "said"), [
    ("missing", "it has no rosbags.rosbag2.storage_mcap.read_exact"),
    ("other parameters", "its rosbags.rosbag2.storage_mcap.skip_exact takes (bio, size, whence), not (bio, size)"),
])
def test_an_mcap_bag_is_refused_where_rosbags_lacks_the_functions_its_bounds_replace(tmp_path, monkeypatch, capsys,
                                                                                    change, said) -> None:
    """A review: pyproject allowed rosbags>=0.10, but 0.10.0 .. 0.11.5 have no mcap read_exact / skip_exact /
    decompress: their bounds were silently left out and an mcap bag read unbounded (exit 0). The floor is the
    first rosbags with them (0.11.6), and a rosbags whose functions are missing or take other parameters has its
    mcap bags refused in one line; a sqlite3 bag still reads."""
    from importlib.metadata import version

    from rosbags.rosbag2 import storage_mcap

    from experiments.cli import main
    from lms200.bag import ROSBAGS_MCAP_SINCE, BagError

    pyproject = (Path(__file__).parents[1] / "pyproject.toml").read_text()
    assert f'"rosbags>={ROSBAGS_MCAP_SINCE}"' in pyproject and ROSBAGS_MCAP_SINCE == "0.11.6"
    b = _ros2_bag_of_topics(tmp_path / "b", 1, "mcap")
    if change == "missing":
        monkeypatch.delattr(storage_mcap, "read_exact")
    else:
        monkeypatch.setattr(storage_mcap, "skip_exact", lambda bio, size, whence: None)
    expected = (f"{b}: an mcap bag cannot be read with the installed rosbags {version('rosbags')}: {said} "
                f"(lmsbench needs rosbags>=0.11.6 to bound its reads)")
    with pytest.raises(BagError) as err:
        list(read_log(b, topic="/scan0"))
    assert str(err.value) == expected
    assert main(["info", str(b)]) == 2
    assert capsys.readouterr().err == f"lmsbench info: error: {expected}\n"
    sq = _ros2_bag_of_topics(tmp_path / "sq", 1, "sqlite3")
    assert [r.scan.stamp for r in read_log(sq, topic="/scan0")] == [10.0]
    monkeypatch.undo()
    assert [r.scan.stamp for r in read_log(b, topic="/scan0")] == [10.0]


def test_a_connection_of_a_type_not_read_whose_md5sum_disagrees_with_its_definition_costs_no_bag(tmp_path, capsys) -> None:
    """Found by fuzzing the bag readers (round 8): a /tf connection with an empty message definition (as
    goroslib and rosnodejs record, md5 computed d41d8cd9...) refused the whole bag, its LaserScan topic
    too: "cannot open as a ROS bag: AnyReaderError: Message type 'tf2_msgs/msg/TFMessage' hash mismatch".
    Definitions of types lmsbench does not read are no longer parsed; a LaserScan's is still checked."""
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    from experiments.cli import main

    ts = get_typestore(Stores.ROS1_NOETIC)
    raw = ts.serialize_ros1(_laser_scan(ts, seq=0), "sensor_msgs/msg/LaserScan")
    bags = {}
    for name, scan_md5 in (("tf.bag", None), ("scan.bag", "0123456789abcdef0123456789abcdef")):
        bags[name] = tmp_path / name
        with Writer(bags[name]) as w:
            msgdef, md5 = ts.generate_msgdef("sensor_msgs/msg/LaserScan")
            c = w.add_connection("/scan", "sensor_msgs/msg/LaserScan", msgdef=msgdef, md5sum=scan_md5 or md5)
            tf = w.add_connection("/tf", "tf2_msgs/msg/TFMessage", msgdef="", md5sum="94810edda583a504dfda3829e70d7eec")
            w.write(c, 10 * 10**9, raw)
            w.write(tf, 10 * 10**9, bytes(4))
    assert [r.scan.stamp for r in read_log(bags["tf.bag"])] == [10.0]  # old: BagError, hash mismatch
    assert main(["info", str(bags["scan.bag"])]) == 2
    assert ("cannot open as a ROS bag: AnyReaderError: Message type 'sensor_msgs/msg/LaserScan' hash mismatch"
            in capsys.readouterr().err)


def test_a_ros2_topic_of_a_type_not_read_whose_hash_disagrees_costs_no_bag(tmp_path) -> None:
    """Found by fuzzing the bag readers (round 9): the same in a ROS 2 bag, whose connections rosbags'
    own reader checked, each against its type_description_hash: a /tf topic whose hash disagreed with its
    definition refused the whole bag ("AnyReaderError: Message type 'tf2_msgs/msg/TFMessage' hash
    mismatch"). A LaserScan topic whose hash disagrees is still refused so."""
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    bad = "RIHS01_" + "0" * 64
    for name, scan_hash, tf_hash in (("tf", None, bad), ("scan", bad, None)):
        with Writer(tmp_path / name, version=8) as w:
            typ = "sensor_msgs/msg/LaserScan"
            c = w.add_connection("/scan", typ, typestore=ts, msgdef=ts.generate_msgdef(typ, ros_version=2)[0],
                                 rihs01=scan_hash or ts.hash_rihs01(typ))
            tf = "tf2_msgs/msg/TFMessage"
            w.add_connection("/tf", tf, typestore=ts, msgdef=ts.generate_msgdef(tf, ros_version=2)[0],
                             rihs01=tf_hash or ts.hash_rihs01(tf))
            w.write(c, 10 * 10**9, ts.serialize_cdr(_laser_scan(ts), typ))
    assert [r.scan.stamp for r in read_log(tmp_path / "tf")] == [10.0]  # old: BagError, hash mismatch
    with pytest.raises(BagError, match="cannot open as a ROS bag: AnyReaderError: Message type "
                                       "'sensor_msgs/msg/LaserScan' hash mismatch"):
        list(read_log(tmp_path / "scan"))
