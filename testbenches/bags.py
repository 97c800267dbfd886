"""A ROS bag as a table: one topic's messages, one row each, read with the rosbags package.

ROS 1 bags (`.bag`) and ROS 2 bags (a folder with its `metadata.yaml` or one `.mcap` file, or
its `.db3` or `.mcap` file alone) are told by their first bytes or by that folder. A recording
is the bag's `sensor_msgs/Imu` topic (the only one, or the one `--topic` names): its columns
are the message's fields as ROS names them (`header/stamp`, `angular_velocity/x`,
`linear_acceleration/x`, with the units the message definition gives them: s, rad/s, m/s2) and
`receive_time`, when the bag received it, which serves where a driver leaves the stamp empty. A
reference is the bag's pose topic (`geometry_msgs/PoseStamped`, `PoseWithCovarianceStamped`,
`TransformStamped`, `QuaternionStamped` or `nav_msgs/Odometry`: a motion-capture system's or an
odometry's), its quaternion's columns named as the message nests them (`pose/orientation/w`).
Times are seconds since 1970, as the stamps count them, so that a recording and its reference
from one bag or from two recorded together are matched by their clock. A bag whose recording
stopped before it was closed is read by testbenches.bag_salvage.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from .reader import GARBLED_SHARE
from .table import TableError, TableSource

ROS1_MAGIC = b"#ROSBAG V2.0"
MCAP_MAGIC = b"\x89MCAP0\r\n"
SQLITE_MAGIC = b"SQLite format 3\x00"

IMU_TYPES = ("sensor_msgs/msg/Imu",)
POSE_TYPES: dict[str, str] = {
    "geometry_msgs/msg/PoseStamped": "pose/orientation",
    "geometry_msgs/msg/PoseWithCovarianceStamped": "pose/pose/orientation",
    "geometry_msgs/msg/TransformStamped": "transform/rotation",
    "geometry_msgs/msg/QuaternionStamped": "quaternion",
    "nav_msgs/msg/Odometry": "pose/pose/orientation",
}
"""The message types a reference is read from, and where each nests its quaternion."""
WANTS = {"imu": "an IMU's (sensor_msgs/Imu)",
         "pose": "a pose's (geometry_msgs/PoseStamped, PoseWithCovarianceStamped, "
                 "TransformStamped, QuaternionStamped or nav_msgs/Odometry)"}


def is_bag(path: Path) -> bool:
    """Whether the path is a ROS bag: a ROS 1 bag, a ROS 2 bag's folder, or its .db3 or .mcap
    file."""
    if path.is_dir():
        return (path / "metadata.yaml").is_file() or _lone_mcap(path) is not None
    if not path.is_file():
        return False
    with path.open("rb") as f:
        magic = f.read(16)
    return (magic.startswith((ROS1_MAGIC, MCAP_MAGIC))
            or (magic.startswith(SQLITE_MAGIC) and path.suffix.lower() == ".db3"))


def _fields(want: str, msgtype: str) -> list[tuple[str, str | None, Callable[[Any], float]]]:
    """(column name, unit, the value of a message) of a topic's columns."""
    def stamp(m: Any) -> float:
        return float(m.header.stamp.sec) + float(m.header.stamp.nanosec) * 1e-9

    if want == "imu":
        return [("header/stamp", "s", stamp),
                *((f"linear_acceleration/{a}", "m/s2",
                   lambda m, a=a: float(getattr(m.linear_acceleration, a))) for a in "xyz"),
                *((f"angular_velocity/{a}", "rad/s",
                   lambda m, a=a: float(getattr(m.angular_velocity, a))) for a in "xyz")]
    path = POSE_TYPES[msgtype].split("/")

    def quaternion(m: Any) -> Any:
        for name in path:
            m = getattr(m, name)
        return m

    return [("header/stamp", "s", stamp),
            *((f"{POSE_TYPES[msgtype]}/{c}", None,
               lambda m, c=c: float(getattr(quaternion(m), c))) for c in "wxyz")]


MESSAGE_BATCH = 16384
"""Messages held as bytes at once: each a few hundred bytes and a Python object, where its row
is 64 bytes, so a block is made of such batches' rows (its bytes would be ten times its rows)."""
IMU_DOUBLES = 37
"""An Imu message's doubles after its header: orientation (4), its covariance (9),
angular_velocity (3), its covariance (9), linear_acceleration (3), its covariance (9)."""
ANGULAR, LINEAR = 13, 25
"""The index of angular_velocity's and of linear_acceleration's first double among them."""


def _imu_layout(raw: bytes, cdr: bool) -> tuple[int, int] | None:
    """(the offset of the stamp's seconds, of the first double) in an Imu message as a ROS 2 bag
    (CDR, little-endian: a 4-byte encapsulation, then the fields aligned to their size from
    there) or a ROS 1 bag (packed, its header's seq first) holds it; None where the message is
    not laid out so (big-endian CDR, another length)."""
    if len(raw) < 16 or (cdr and raw[:2] != b"\x00\x01"):
        return None
    name = int.from_bytes(raw[12:16], "little")  # frame_id's length (CDR: with its NUL)
    first = 16 + name
    if cdr:
        first += (-(first - 4)) % 8
    return (4, first) if first + 8 * IMU_DOUBLES == len(raw) else None


def _imu_rows(bag: Any, block: list[tuple[Any, int, bytes]],
              layouts: dict[int, tuple[int, int] | None]) -> np.ndarray | None:
    """A block of Imu messages as rows (open_bag's columns) read off their bytes with numpy, no
    message object built for each; None where a message's layout is not the one known. Each
    length of message met is checked once against the message deserialized (`layouts`: its
    layout, None where that differs)."""
    cdr = bool(getattr(bag, "is2", False))
    raws = [raw for _, _, raw in block]
    out = np.empty((len(block), 8))
    lengths = np.array([len(raw) for raw in raws])
    for length in np.unique(lengths):
        at = np.flatnonzero(lengths == length)
        if int(length) not in layouts:
            layouts[int(length)] = _checked(bag, block[at[0]], cdr)
        layout = layouts[int(length)]
        if layout is None:
            return None
        stamp, first = layout
        buf = np.frombuffer(b"".join(raws[i] for i in at), dtype=np.uint8).reshape(len(at), -1)
        sec = buf[:, stamp:stamp + 4].copy().view("<i4" if cdr else "<u4")[:, 0]
        nanosec = buf[:, stamp + 4:stamp + 8].copy().view("<u4")[:, 0]
        doubles = buf[:, first:first + 8 * IMU_DOUBLES].copy().view("<f8")
        out[at, 0] = sec + nanosec * 1e-9
        out[at, 1:4] = doubles[:, LINEAR:LINEAR + 3]
        out[at, 4:7] = doubles[:, ANGULAR:ANGULAR + 3]
    out[:, 7] = np.array([received for _, received, _ in block]) * 1e-9
    return out


def _checked(bag: Any, message: tuple[Any, int, bytes], cdr: bool) -> tuple[int, int] | None:
    """The layout of a message (_imu_layout) where the values read off it by that layout are
    the deserialized message's, else None."""
    connection, _, raw = message
    layout = _imu_layout(raw, cdr)
    if layout is None or not 0 <= layout[1] <= len(raw) - 8 * IMU_DOUBLES:
        return None
    stamp, first = layout
    try:
        m = bag.deserialize(raw, connection.msgtype)
    except Exception:  # a message whose bytes were changed: rows_of says so
        return None
    doubles = np.frombuffer(raw, dtype="<f8", count=IMU_DOUBLES, offset=first)
    sec = int.from_bytes(raw[stamp:stamp + 4], "little", signed=cdr)
    nanosec = int.from_bytes(raw[stamp + 4:stamp + 8], "little")
    same = (sec == m.header.stamp.sec and nanosec == m.header.stamp.nanosec
            and list(doubles[LINEAR:LINEAR + 3]) == [m.linear_acceleration.x,
                                                      m.linear_acceleration.y,
                                                      m.linear_acceleration.z]
            and list(doubles[ANGULAR:ANGULAR + 3]) == [m.angular_velocity.x,
                                                        m.angular_velocity.y,
                                                        m.angular_velocity.z])
    return layout if same else None


def _lone_mcap(folder: Path) -> Path | None:
    """A ROS 2 bag folder's one MCAP file (a recorder stopped before writing metadata.yaml
    leaves it alone); None where it has none or several."""
    found = sorted(folder.glob("*.mcap"))
    return found[0] if len(found) == 1 else None


def _repair(path: Path, err: Exception) -> str:
    """How a bag whose recording stopped before its end is repaired, where its error shows it
    (a ROS 1 bag's index or an MCAP file's summary is written last); "" for another error."""
    text = str(err)
    if "index" in text.lower() and path.suffix == ".bag":
        return (": a recording stopped before the bag's index was written; `rosbag reindex "
                f"{path.name}` rebuilds it")
    if "end magic" in text.lower():
        return (": an MCAP recording stopped before its end was written; `mcap recover FILE "
                "-o FIXED.mcap` (the mcap command) keeps what it holds")
    return ""


def _opener(path: Path) -> tuple[Callable[[], Any], dict[str, list[Any]], str]:
    """How the bag is opened (rosbags' AnyReader; bag_salvage's reader where the recording
    stopped before the bag's index or end was written), its topics' [type, message count] and
    what a user should know of how it was read; TableError where it cannot be read."""
    from rosbags.highlevel import AnyReader

    from .bag_salvage import SalvagedBag, SalvageError

    def topics(bag: Any) -> dict[str, list[Any]]:
        counts: dict[str, list[Any]] = {}
        for c in bag.connections:
            counts.setdefault(c.topic, [c.msgtype, 0])[1] += c.msgcount
        return counts

    if path.is_dir() and not (path / "metadata.yaml").is_file():
        path = _lone_mcap(path) or path
    try:
        with AnyReader([path]) as bag:
            return (lambda: AnyReader([path])), topics(bag), ""
    except Exception as err:  # rosbags raises its own per format: any is an unreadable bag
        refused = f"{path}: not a readable ROS bag ({err})"
        repair = _repair(path, err)
        data = _lone_mcap(path) if path.is_dir() else path
        if not repair or data is None:
            raise TableError(refused + repair) from None
    try:
        with SalvagedBag(data) as salvaged:
            return (lambda: SalvagedBag(data)), topics(salvaged), salvaged.stopped()
    except SalvageError as why:
        raise TableError(f"{refused}{repair}; read record by record, {why}") from None


def _why(err: Exception) -> str:
    """An error of a damaged bag as its type and its text (an AssertionError has none)."""
    return f"{type(err).__name__}: {err}" if str(err) else type(err).__name__


def _messages(path: Path, bag: Any, connections: list[Any], topic: str
              ) -> Iterator[tuple[Any, int, bytes]]:
    """The topic's messages as the bag gives them; TableError naming the last whole one where
    the bag's bytes do not read on (rosbags, its decompressors and SQLite raise errors of their
    own for a bag changed since it was written)."""
    n = 0
    try:
        for message in bag.messages(connections=connections):
            yield message
            n += 1
    except Exception as err:  # any of rosbags', zstd's, lz4's, bz2's, apsw's: a damaged bag
        where = f"after message {n} of {topic}" if n else f"before its first message of {topic}"
        raise TableError(f"{path}: damaged {where}: it does not read on from there ({_why(err)}); "
                         "copy or record it again") from None


class _Unread:
    """A read's messages that do not deserialize (their bytes changed since they were
    written): samples without numbers, said, where they are at most GARBLED_SHARE of the
    messages, as a text file's lines that are no row are; refused where more."""

    def __init__(self, path: Path, topic: str, found: list[str]) -> None:
        self.path, self.topic, self.found = path, topic, found
        self.count, self.first = 0, ""

    def add(self, index: int, err: Exception) -> None:
        self.count += 1
        self.first = self.first or f"message {index + 1}: {_why(err)}"
        if self.count > 1 + GARBLED_SHARE * (index + 1):
            raise self._refusal(index + 1)

    def finish(self, messages: int, counted: int) -> None:
        """At the end of the read of `messages` of the `counted` the bag's index counts (a
        damaged record can hide the messages after it in its chunk): refused where more than
        GARBLED_SHARE are unread or do not deserialize, else said."""
        if self.count > GARBLED_SHARE * max(messages, 1):
            raise self._refusal(messages)
        lost = counted - messages
        if lost > GARBLED_SHARE * max(counted, 1):
            raise TableError(f"{self.path}: {messages} of the {counted} messages of "
                             f"{self.topic} its index counts read: the bag is damaged; copy or "
                             "record it again")
        if lost > 0:
            self.found.append(f"{lost} of the {counted} messages of {self.topic} its index "
                              "counts not read (the bag is damaged)")
        if self.count:
            self.found.append(f"{self.count} message(s) of {self.topic} do not deserialize "
                              "(their bytes changed), taken as samples without a number (the "
                              f"first: {self.first})")

    def _refusal(self, messages: int) -> TableError:
        return TableError(f"{self.path}: {self.count} of {messages} messages of {self.topic} "
                          f"do not deserialize (more than {GARBLED_SHARE:.0%} of them; the "
                          f"first: {self.first}): the bag is damaged; copy or record it again")


def open_bag(path: Path, want: str = "imu", topic: str | None = None) -> TableSource:
    """The bag's table of `want` ("imu": the recording's, "pose": a reference's) from the topic
    named, else from the only topic of such a type; TableError where the bag cannot be read,
    holds no such topic or several (naming them), or the topic named is none of them. A bag
    whose recording stopped before its index or end was written is read up to where it stops
    (testbenches.bag_salvage), and its note says so."""
    try:
        import rosbags.highlevel  # noqa: F401
    except ImportError:
        raise TableError(f"{path}: a ROS bag, which takes the rosbags package to read (pip "
                         "install rosbags); or export the topic as CSV (rostopic echo -p, "
                         "PlotJuggler)") from None
    types = IMU_TYPES if want == "imu" else tuple(POSE_TYPES)
    opener, counts, how = _opener(path)
    fits = sorted(t for t, (kind, _) in counts.items() if kind in types)
    listed = ", ".join(f"{t} ({k})" for t, (k, _) in sorted(counts.items()))
    if topic is not None:
        if topic not in counts:
            raise TableError(f"{path}: no topic {topic!r}; the bag has {listed}")
        if topic not in fits:
            raise TableError(f"{path}: the topic {topic!r} holds {counts[topic][0]}, not "
                             f"{WANTS[want]} messages")
    elif len(fits) != 1:
        raise TableError(f"{path}: " + (f"{len(fits)} topics hold {WANTS[want]} messages ("
                                        f"{', '.join(fits)}): give one (--topic NAME)" if fits
                                        else f"no topic holds {WANTS[want]} messages; the bag "
                                        f"has {listed}"))
    chosen = topic or fits[0]
    msgtype, n = counts[chosen]
    fields = _fields(want, msgtype)
    header = [name for name, _, _ in fields] + ["receive_time"]
    units: list[str | None] = [unit for _, unit, _ in fields] + ["s"]

    def read(columns: list[int], rows: int) -> Iterator[np.ndarray]:
        values = [get for _, _, get in fields]
        layouts: dict[int, tuple[int, int] | None] = {}  # raw length -> _ImuLayout's, checked

        bad = _Unread(path, chosen, found)

        def rows_of(bag: Any, block: list[tuple[Any, int, bytes]], before: int) -> np.ndarray:
            if want == "imu":
                fast = _imu_rows(bag, block, layouts)
                if fast is not None:
                    return fast
            out = np.full((len(block), len(values) + 1), np.nan)
            for k, (c, received, raw) in enumerate(block):
                try:
                    message = bag.deserialize(raw, c.msgtype)
                    out[k, :-1] = [get(message) for get in values]
                except Exception as err:  # its bytes changed: a sample without numbers
                    bad.add(before + k, err)
                out[k, -1] = received * 1e-9
            return out

        with opener() as bag:
            connections = [c for c in bag.connections if c.topic == chosen]
            batch: list[tuple[Any, int, bytes]] = []  # messages, as bytes until made rows
            done: list[np.ndarray] = []  # their rows, until a block's are
            held = 0
            count = 0
            for message in _messages(path, bag, connections, chosen):
                batch.append(message)
                if len(batch) == min(rows - held, MESSAGE_BATCH):
                    done.append(rows_of(bag, batch, count)[:, columns])
                    held += len(batch)
                    count += len(batch)
                    batch = []
                    if held == rows:
                        yield np.concatenate(done)
                        done, held = [], 0
            if batch:
                done.append(rows_of(bag, batch, count)[:, columns])
                count += len(batch)
            bad.finish(count, n)
            if done:
                yield np.concatenate(done)

    found: list[str] = []
    return TableSource(path, header, list(header), units, "ROS bag", n, read,
                       lambda row: f"message {row + 1} of {chosen}",
                       note=f"topic {chosen} ({msgtype}, {n} messages)"
                       + (f"; {how}" if how else ""), found=found)
