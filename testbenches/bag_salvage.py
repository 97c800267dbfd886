"""A ROS bag whose recording stopped before its end was written, read record by record up to
where it stops.

A ROS 1 bag's index (its connections and where each chunk's messages are) is written when
`rosbag record` closes it, and an MCAP file's summary and closing magic when its writer
closes: a recorder killed, a robot powered off or a disk filled leaves a bag without them,
which rosbags (like rosbag and the mcap library) refuses to open. What it holds is read here
in file order: each connection (ROS 1) or schema and channel (MCAP) where it is written, before
its first message, and each message whole, up to the first record the file ends inside. A
ROS 1 chunk is read in place where it is uncompressed (`rosbag record` writes its records
straight to the file and its size only when the chunk is closed) and decompressed as far as
it goes where it is compressed (bz2, lz4), as MCAP's chunks are (lz4, zstd).

`SalvagedBag` answers as much of rosbags' AnyReader as testbenches.bags uses: `connections`
(topic, type, message count), `messages(connections)` and `deserialize`, with the types the
bag's own message definitions give.
"""

from __future__ import annotations

import bz2
import struct
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, BinaryIO

ROS1_MAGIC = b"#ROSBAG V2.0\n"
MCAP_MAGIC = b"\x89MCAP0\r\n"

# ROS 1 record ops (the bag format 2.0) and MCAP record opcodes
ROS1_MESSAGE, ROS1_CHUNK, ROS1_CONNECTION = 2, 5, 7
MCAP_SCHEMA, MCAP_CHANNEL, MCAP_MESSAGE, MCAP_CHUNK, MCAP_DATA_END = 0x03, 0x04, 0x05, 0x06, 0x0F


class SalvageError(Exception):
    """The bag holds no message before where it stops, or is not laid out as its format says."""


@dataclass
class Connection:
    """A topic as the bag records it: its id in the bag, name, message type (as ROS 2 names it:
    sensor_msgs/msg/Imu), the message definition it carries and how many messages it has."""

    id: int
    topic: str
    msgtype: str
    msgdef: str
    idl: bool = False
    msgcount: int = 0


@dataclass
class _Scan:
    """What a pass over the file met: connections by id, and where and why it stopped."""

    connections: dict[int, Connection] = field(default_factory=dict)
    cut: int = -1
    """Where the record the file ends inside starts (byte offset), -1 where it ends after
    one."""


def _msgtype(name: str) -> str:
    """A message type as ROS 2 names it (sensor_msgs/Imu -> sensor_msgs/msg/Imu)."""
    parts = name.split("/")
    return name if len(parts) != 2 else f"{parts[0]}/msg/{parts[1]}"


class _Cut(Exception):
    """The file (or a chunk's decompressed bytes) ends inside a record."""


def _take(buf: memoryview, at: int, n: int) -> memoryview:
    if at + n > len(buf):
        raise _Cut
    return buf[at:at + n]


def _partial(decompress: Callable[[bytes], bytes], data: bytes) -> bytes:
    """What a streaming decompressor gives of data that may end before its stream does;
    SalvageError where the data is no such stream (changed bytes, not a cut)."""
    try:
        return decompress(data)
    except EOFError:
        return b""
    except Exception as err:  # bz2's OSError, lz4's RuntimeError, zstd's ZstdError
        raise SalvageError(f"a chunk does not decompress ({type(err).__name__}: {err}): the "
                           "bag is damaged besides") from None


def _decompressor(kind: str, compression: str) -> Callable[[bytes], bytes]:
    """A chunk's streaming decompressor, which gives what it can of a cut chunk."""
    if compression in ("", "none"):
        return bytes
    if compression == "bz2":
        return bz2.BZ2Decompressor().decompress
    if compression == "lz4":
        import lz4.frame
        return lz4.frame.LZ4FrameDecompressor().decompress
    if compression == "zstd":
        try:
            from compression import zstd  # type: ignore[import-not-found]
        except ImportError:
            from backports import zstd  # type: ignore[import-not-found,no-redef]
        return zstd.ZstdDecompressor().decompress
    raise SalvageError(f"its chunks are compressed as {compression!r}, which {kind} reading "
                       "does not know")


# ---------------------------------------------------------------------------------------- ROS 1

def _ros1_fields(header: memoryview) -> dict[str, bytes]:
    """A ROS 1 record header's fields (name=value, each after its 4-byte length)."""
    fields, at = {}, 0
    while at < len(header):
        n = int.from_bytes(_take(header, at, 4), "little")
        name, _, value = bytes(_take(header, at + 4, n)).partition(b"=")
        fields[name.decode("latin-1")] = value
        at += 4 + n
    return fields


def _ros1_walk(buf: memoryview, at: int, scan: _Scan,
               top: bool) -> Iterator[tuple[int, int, bytes]]:
    """(connection id, receive time [ns], raw message) of each whole message of a ROS 1 bag's
    records from `at` on, in file order; top: the file itself, whose chunks are gone into (an
    uncompressed one in place, as its records follow its header), else a chunk's decompressed
    records. scan gets the connections met and, at the top, where the file ends inside a
    record."""
    while at < len(buf):
        start = at
        try:
            n = int.from_bytes(_take(buf, at, 4), "little")
            fields = _ros1_fields(_take(buf, at + 4, n))
            size = int.from_bytes(_take(buf, at + 4 + n, 4), "little")
            op = fields["op"][0]
            at += 8 + n
            whole = at + size <= len(buf)
            if op == ROS1_CHUNK and top:
                compression = fields["compression"].decode()
                if compression == "none":
                    continue  # its size may be the placeholder of a chunk never closed
                raw = _partial(_decompressor("ROS 1", compression), bytes(buf[at:at + size]))
                yield from _ros1_walk(memoryview(raw), 0, scan, top=False)
                if not whole:
                    raise _Cut
            data = _take(buf, at, size)
            at += size
            if op == ROS1_CONNECTION:
                conn = int.from_bytes(fields["conn"], "little")
                if conn not in scan.connections:
                    about = _ros1_fields(data)
                    scan.connections[conn] = Connection(
                        conn, fields["topic"].decode(), _msgtype(about["type"].decode()),
                        about.get("message_definition", b"").decode())
            elif op == ROS1_MESSAGE:
                sec, nsec = struct.unpack("<II", fields["time"])
                yield (int.from_bytes(fields["conn"], "little"), sec * 1_000_000_000 + nsec,
                       bytes(data))
        except _Cut:
            if top:
                scan.cut = start
            return
        except (KeyError, IndexError, struct.error, UnicodeDecodeError) as err:
            raise SalvageError(f"a record at byte {start} is not laid out as a ROS 1 bag's "
                               f"({type(err).__name__}: {err})") from None


def _ros1_scan(buf: memoryview, scan: _Scan) -> Iterator[tuple[int, int, bytes]]:
    return _ros1_walk(buf, len(ROS1_MAGIC), scan, top=True)


# ----------------------------------------------------------------------------------------- MCAP

def _mcap_string(buf: memoryview, at: int) -> tuple[str, int]:
    n = int.from_bytes(_take(buf, at, 4), "little")
    return bytes(_take(buf, at + 4, n)).decode(), at + 4 + n


def _mcap_walk(buf: memoryview, at: int, scan: _Scan, schemas: dict[int, tuple[str, str, str]],
               top: bool) -> Iterator[tuple[int, int, bytes]]:
    """(channel id, log time [ns], raw message) of each whole message of an MCAP file's records
    from `at` on, in file order; top: the file itself, whose chunks are gone into, else a
    chunk's decompressed records. scan gets the channels met (with their schemas) and, at the
    top, where the file ends inside a record."""
    while at < len(buf):
        start = at
        try:
            op = buf[at]
            size = int.from_bytes(_take(buf, at + 1, 8), "little")
            at += 9
            whole = at + size <= len(buf)
            body = buf[at:at + size]
            at += size
            if op == MCAP_CHUNK and top:
                compression, k = _mcap_string(body, 28)
                records = int.from_bytes(_take(body, k, 8), "little")
                raw = _partial(_decompressor("MCAP", compression),
                               bytes(body[k + 8:k + 8 + records]))
                yield from _mcap_walk(memoryview(raw), 0, scan, schemas, top=False)
            if not whole:
                raise _Cut
            if op == MCAP_SCHEMA:
                sid = int.from_bytes(_take(body, 0, 2), "little")
                name, k = _mcap_string(body, 2)
                encoding, k = _mcap_string(body, k)
                text = int.from_bytes(_take(body, k, 4), "little")
                schemas[sid] = (name, encoding, bytes(_take(body, k + 4, text)).decode())
            elif op == MCAP_CHANNEL:
                cid, sid = struct.unpack_from("<HH", body, 0)
                topic, _ = _mcap_string(body, 4)
                if cid not in scan.connections and sid in schemas:
                    name, encoding, text = schemas[sid]
                    scan.connections[cid] = Connection(cid, topic, _msgtype(name), text,
                                                       idl=encoding == "ros2idl")
            elif op == MCAP_MESSAGE:
                cid, _, log_time, _ = struct.unpack_from("<HIQQ", body, 0)
                yield cid, log_time, bytes(body[22:])
            elif op == MCAP_DATA_END and top:
                return
        except _Cut:
            if top:
                scan.cut = start
            return
        except (IndexError, struct.error, UnicodeDecodeError) as err:
            raise SalvageError(f"a record at byte {start} is not laid out as an MCAP file's "
                               f"({type(err).__name__}: {err})") from None


def _mcap_scan(buf: memoryview, scan: _Scan) -> Iterator[tuple[int, int, bytes]]:
    return _mcap_walk(buf, len(MCAP_MAGIC), scan, {}, top=True)


# ------------------------------------------------------------------------------------- the bag

class SalvagedBag:
    """A cut ROS 1 bag or MCAP file, its records read in file order (see the module)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        with path.open("rb") as f:
            head = f.read(len(ROS1_MAGIC))
        if head.startswith(MCAP_MAGIC):
            self.is2, self._scan_of, self._lacks = True, _mcap_scan, "its summary and end"
        elif head == ROS1_MAGIC:
            self.is2, self._scan_of, self._lacks = False, _ros1_scan, "its index"
        else:
            raise SalvageError("neither a ROS 1 bag nor an MCAP file by its first bytes")
        self._file: BinaryIO | None = None
        self._buf: memoryview | None = None
        self.scan = _Scan()
        self.connections: list[Connection] = []
        self.typestore: Any = None

    def __enter__(self) -> SalvagedBag:
        import mmap
        self._file = self.path.open("rb")
        self._map = mmap.mmap(self._file.fileno(), 0, access=mmap.ACCESS_READ)
        self._buf = memoryview(self._map)
        try:
            scan = _Scan()
            counts: dict[int, int] = {}
            for conn, _, _ in self._scan_of(self._buf, scan):
                counts[conn] = counts.get(conn, 0) + 1
            self.scan = scan
            self.connections = [c for c in scan.connections.values() if counts.get(c.id)]
            for c in self.connections:
                c.msgcount = counts[c.id]
            if not self.connections:
                raise SalvageError("no whole message before where the file stops")
            self.typestore = _typestore(self.connections)
        except BaseException:
            self.__exit__()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        if self._buf is not None:
            try:
                self._buf.release()
                self._map.close()
            except BufferError:  # a view of it lives on in an error's traceback: closed with it
                pass
        if self._file is not None:
            self._file.close()
        self._buf = self._file = None

    def messages(self, connections: list[Connection]) -> Iterator[tuple[Connection, int, bytes]]:
        """(connection, time [ns], raw message) of the connections' messages, in file order."""
        assert self._buf is not None
        wanted = {c.id: c for c in connections}
        for conn, time, raw in self._scan_of(self._buf, _Scan()):
            if conn in wanted:
                yield wanted[conn], time, raw

    def deserialize(self, raw: bytes, msgtype: str) -> Any:
        """The message object of raw bytes (ROS 1's packed layout or ROS 2's CDR)."""
        if self.is2:
            return self.typestore.deserialize_cdr(raw, msgtype)
        return self.typestore.deserialize_ros1(raw, msgtype)

    def stopped(self) -> str:
        """How it was read and what was left out, for a user."""
        cut = self.scan.cut
        return (f"read record by record, {self._lacks} never written" + (
            f"; it ends inside a record (from byte {cut} of {self.path.stat().st_size}: cut "
            "mid-write), every whole message before the cut read" if cut >= 0 else ""))


def _typestore(connections: list[Connection]) -> Any:
    """A rosbags typestore with the types the bag's own message definitions give."""
    from rosbags.typesys import Stores, get_types_from_idl, get_types_from_msg, get_typestore

    types: dict[str, Any] = {}
    for c in connections:
        if not c.msgdef:
            continue
        if c.idl:
            types.update(get_types_from_idl(c.msgdef))
        else:
            types.update(get_types_from_msg(c.msgdef, c.msgtype))
    store = get_typestore(Stores.EMPTY)
    store.register(types)
    return store
