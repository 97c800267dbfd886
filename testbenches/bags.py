"""A ROS bag as a table: one topic's messages, one row each, read with the rosbags package.

ROS 1 bags (`.bag`) and ROS 2 bags (a folder with its `metadata.yaml`, or its `.db3` or
`.mcap` file alone) are told by their first bytes or by that folder. A recording is the bag's
`sensor_msgs/Imu` topic (the only one, or the one `--topic` names): its columns are the
message's fields as ROS names them (`header/stamp`, `angular_velocity/x`,
`linear_acceleration/x`, with the units the message definition gives them: s, rad/s, m/s2) and
`receive_time`, when the bag received it, which serves where a driver leaves the stamp empty. A
reference is the bag's pose topic (`geometry_msgs/PoseStamped`, `PoseWithCovarianceStamped`,
`TransformStamped`, `QuaternionStamped` or `nav_msgs/Odometry`: a motion-capture system's or an
odometry's), its quaternion's columns named as the message nests them (`pose/orientation/w`).
Times are seconds since 1970, as the stamps count them, so that a recording and its reference
from one bag or from two recorded together are matched by their clock.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from .reader import TableError, TableSource

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
        return (path / "metadata.yaml").is_file()
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


def open_bag(path: Path, want: str = "imu", topic: str | None = None) -> TableSource:
    """The bag's table of `want` ("imu": the recording's, "pose": a reference's) from the topic
    named, else from the only topic of such a type; TableError where the bag cannot be read,
    holds no such topic or several (naming them), or the topic named is none of them."""
    try:
        from rosbags.highlevel import AnyReader
    except ImportError:
        raise TableError(f"{path}: a ROS bag, which takes the rosbags package to read (pip "
                         "install rosbags); or export the topic as CSV (rostopic echo -p, "
                         "PlotJuggler)") from None
    types = IMU_TYPES if want == "imu" else tuple(POSE_TYPES)
    try:
        with AnyReader([path]) as bag:
            counts: dict[str, list[Any]] = {}
            for c in bag.connections:
                counts.setdefault(c.topic, [c.msgtype, 0])[1] += c.msgcount
    except Exception as err:  # rosbags raises its own per format: any is an unreadable bag
        raise TableError(f"{path}: not a readable ROS bag ({err})") from None
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
        block: list[list[float]] = []
        with AnyReader([path]) as bag:
            connections = [c for c in bag.connections if c.topic == chosen]
            for connection, received, raw in bag.messages(connections=connections):
                m = bag.deserialize(raw, connection.msgtype)
                block.append([get(m) for get in values] + [received * 1e-9])
                if len(block) == rows:
                    yield np.array(block)[:, columns]
                    block = []
        if block:
            yield np.array(block)[:, columns]

    return TableSource(path, header, list(header), units, "ROS bag", n, read,
                       lambda row: f"message {row + 1} of {chosen}",
                       note=f"topic {chosen} ({msgtype}, {n} messages)")
