"""ROS bags as robotics users record them: the IMU topic as the recording, a motion-capture
or odometry topic as the reference, from a ROS 1 bag, a ROS 2 bag's folder or its file alone
(testbenches.bags)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from testbenches.cli import main
from testbenches.fit.recording import RecordingError, open_recording

pytest.importorskip("rosbags", reason="the rosbags package reads ROS bags (testbench extra)")

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "tilt_motion.csv"
TRUTH = REPO / "examples" / "tilt_motion_truth.csv"
EPOCH_NS = 1_700_000_000_000_000_000


def _quaternions(truth: np.ndarray) -> np.ndarray:
    """w, x, y, z of the truth's roll, pitch, yaw (Z-Y-X)."""
    roll, pitch, yaw = truth[:, 1] / 2, truth[:, 2] / 2, truth[:, 3] / 2
    cr, sr, cp, sp, cy, sy = (np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch),
                              np.cos(yaw), np.sin(yaw))
    return np.column_stack([cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
                            cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy])


def _messages(ts, imu_topics=("/imu/data",), pose="geometry_msgs/msg/PoseStamped",
              stamped=True):
    """(receive time [ns], topic, type, message) of the example's samples on each IMU topic and
    of its truth as a pose topic, in the order a bag holds them."""
    t_ = ts.types
    data = np.loadtxt(EXAMPLE, delimiter=",", skiprows=1)
    truth = np.loadtxt(TRUTH, delimiter=",", skiprows=1)
    q = _quaternions(truth)

    def header(ns, frame):
        fields = t_["std_msgs/msg/Header"].__dataclass_fields__
        stamp = t_["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
        return t_["std_msgs/msg/Header"](stamp=stamp, frame_id=frame,
                                         **({"seq": 0} if "seq" in fields else {}))

    def vector(v):
        return t_["geometry_msgs/msg/Vector3"](x=float(v[0]), y=float(v[1]), z=float(v[2]))

    def quat(w, x, y, z):
        return t_["geometry_msgs/msg/Quaternion"](x=float(x), y=float(y), z=float(z), w=float(w))

    out = []
    for k, topic in enumerate(imu_topics):
        for row in data:
            ns = EPOCH_NS + round(row[0] * 1e9)
            msg = t_["sensor_msgs/msg/Imu"](
                header=header(ns if stamped else 0, "imu"), orientation=quat(1, 0, 0, 0),
                orientation_covariance=np.array([-1.0] + [0.0] * 8),
                angular_velocity=vector(row[4:7] * (1 + k)),
                angular_velocity_covariance=np.zeros(9),
                linear_acceleration=vector(row[1:4]), linear_acceleration_covariance=np.zeros(9))
            out.append((ns + 300_000, topic, "sensor_msgs/msg/Imu", msg))
    for row, (w, x, y, z) in zip(truth, q, strict=True):
        ns = EPOCH_NS + round(row[0] * 1e9)
        if pose == "geometry_msgs/msg/PoseStamped":
            point = t_["geometry_msgs/msg/Point"](x=0.0, y=0.0, z=0.0)
            msg = t_[pose](header=header(ns, "world"),
                           pose=t_["geometry_msgs/msg/Pose"](position=point,
                                                             orientation=quat(w, x, y, z)))
        else:  # TransformStamped, as vicon_bridge publishes it
            msg = t_[pose](header=header(ns, "world"), child_frame_id="imu",
                           transform=t_["geometry_msgs/msg/Transform"](
                               translation=vector((0, 0, 0)), rotation=quat(w, x, y, z)))
        out.append((ns + 100_000, "/mocap/body", pose, msg))
    return sorted(out, key=lambda m: m[0])


def write_bag(path: Path, kind: str = "ros2", compression: str = "none", **how) -> Path:
    """A bag of the example (ROS 1 .bag, or ROS 2 in SQLite or MCAP) with rosbags' writers;
    a ROS 1 bag's chunks compressed as given (in chunks of 64 kB), an MCAP file's with zstd
    where compression is "zstd"."""
    from rosbags.rosbag1 import Writer as Writer1
    from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin
    from rosbags.rosbag2 import Writer as Writer2
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC if kind == "ros1" else Stores.ROS2_HUMBLE)
    writer = (Writer1(path) if kind == "ros1" else
              Writer2(path, version=9, storage_plugin=StoragePlugin.MCAP if kind == "mcap"
                      else StoragePlugin.SQLITE3))
    if kind == "ros1" and compression != "none":
        writer.set_compression(Writer1.CompressionFormat[compression.upper()])
        writer.chunk_threshold = 64 * 1024
    elif compression != "none":
        writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
    serialize = ts.serialize_ros1 if kind == "ros1" else ts.serialize_cdr
    with writer:
        connections = {}
        for ns, topic, msgtype, msg in _messages(ts, **how):
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, msgtype, typestore=ts)
            writer.write(connections[topic], ns, serialize(msg, msgtype))
    return path


def _kf(tmp_path: Path, capsys, recording: Path, *options: str) -> tuple[int, str]:
    status = main(["estimate", str(recording), "--estimator", "kf", *options, "--out",
                   str(tmp_path / "out"), "--no-plots"])
    said = capsys.readouterr()
    return status, said.out + said.err


@pytest.mark.parametrize(("kind", "given"), [("ros1", "run.bag"), ("ros2", "run"),
                                             ("mcap", "run/run.mcap")])
def test_a_ros_bag_is_a_recording_and_its_pose_topic_a_reference(tmp_path, capsys, kind,
                                                                 given):
    """The IMU topic timed by its messages' stamps, its units the message's, scored against
    the bag's motion-capture pose topic: what the example's CSV and truth give."""
    write_bag(tmp_path / ("run.bag" if kind == "ros1" else "run"), kind)
    bag = tmp_path / given
    status, said = _kf(tmp_path, capsys, bag, "--reference", str(bag))
    assert status == 0, said
    assert "topic /imu/data (sensor_msgs/msg/Imu, 1000 messages)" in said
    assert "time='header/stamp'" in said and "gyro in rad/s (from the header" in said
    plain = _kf(tmp_path, capsys, EXAMPLE, "--reference", str(TRUTH))[1]
    rmse = [float(next(r for r in s.splitlines() if r.startswith("kf ")).split()[2])
            for s in (said, plain)]
    assert rmse[0] == pytest.approx(rmse[1], abs=1e-4)


def test_a_bags_topics_are_chosen_by_name_where_it_has_several(tmp_path, capsys):
    """Two IMU topics: refused naming both, --topic takes one (its own samples); a topic of
    another type, or --topic for a file that is no bag, is refused; a TransformStamped
    reference serves as a PoseStamped does."""
    bag = write_bag(tmp_path / "two", imu_topics=("/imu/data", "/imu/data_raw"),
                    pose="geometry_msgs/msg/TransformStamped")
    with pytest.raises(RecordingError, match=r"2 topics hold an IMU's \(sensor_msgs/Imu\) "
                       r"messages \(/imu/data, /imu/data_raw\): give one \(--topic NAME\)"):
        open_recording(bag)
    raw, _ = open_recording(bag, topic="/imu/data_raw").load()
    data = np.loadtxt(EXAMPLE, delimiter=",", skiprows=1)
    np.testing.assert_allclose(raw.gyro, data[:, 4:7] * 2)
    with pytest.raises(RecordingError, match=r"'/mocap/body' holds "
                       r"geometry_msgs/msg/TransformStamped, not an IMU's"):
        open_recording(bag, topic="/mocap/body")
    with pytest.raises(RecordingError, match="this is no ROS bag"):
        open_recording(EXAMPLE, topic="/imu/data")
    status, said = _kf(tmp_path, capsys, bag, "--topic", "/imu/data", "--reference", str(bag))
    assert status == 0, said
    assert "reference: 999 of 1000 samples scored" in said


def test_a_driver_that_leaves_the_stamp_empty_is_timed_by_the_bag(tmp_path):
    """A driver that publishes without a stamp (all zero): the stamp repeats, so the time the
    bag received each message is taken, and said."""
    source = open_recording(write_bag(tmp_path / "unstamped", stamped=False))
    assert "'header/stamp' does not rise from row to row, 'receive_time' does" in source.choices
    rec, _ = source.load()
    np.testing.assert_allclose(rec.dt[1:], 0.01, atol=1e-6)


@pytest.mark.parametrize("kind", ["ros1", "ros2", "mcap"])
def test_imu_messages_read_off_their_bytes_are_the_deserialized_ones(tmp_path, kind,
                                                                     monkeypatch):
    """The Imu rows read off the messages' bytes (no message object built) equal the
    deserialized messages' to the bit, in both serializations; a layout that does not match
    what deserializing gives is not used (the read falls back, the same rows)."""
    from rosbags.highlevel import AnyReader

    from testbenches import bags

    bag_path = write_bag(tmp_path / ("run.bag" if kind == "ros1" else "run"), kind)
    with AnyReader([bag_path]) as bag:
        block = [m for m in bag.messages() if m[0].msgtype == "sensor_msgs/msg/Imu"]
        fast = bags._imu_rows(bag, block, {})
        slow = np.array([[get(bag.deserialize(raw, c.msgtype)) for _, _, get in
                          bags._fields("imu", c.msgtype)] + [t * 1e-9] for c, t, raw in block])
    assert fast is not None
    np.testing.assert_array_equal(fast, slow)
    real = bags._imu_layout
    monkeypatch.setattr(bags, "_imu_layout",  # one double early
                        lambda raw, cdr: (real(raw, cdr)[0], real(raw, cdr)[1] - 8))
    with AnyReader([bag_path]) as bag:
        assert bags._imu_rows(bag, block, {}) is None
    rec, _ = open_recording(bag_path).load()
    np.testing.assert_array_equal(rec.acc, slow[:, 1:4])


def _killed(raw: bytes) -> bytes:
    """A ROS 1 bag as `rosbag record` leaves it when killed: the bag header's index position
    0, its open chunk's sizes the placeholders (0) written when the chunk began, and no index
    (the bag's records up to where the chunk's data ends)."""
    def record(at: int) -> tuple[dict[str, tuple[int, bytes]], int, int]:
        n = int.from_bytes(raw[at:at + 4], "little")
        fields, k = {}, at + 4
        while k < at + 4 + n:
            m = int.from_bytes(raw[k:k + 4], "little")
            name, _, value = raw[k + 4:k + 4 + m].partition(b"=")
            fields[name.decode()] = (k + 4 + len(name) + 1, value)
            k += 4 + m
        return fields, at + 4 + n, int.from_bytes(raw[at + 4 + n:at + 8 + n], "little")

    out = bytearray(raw)
    header, data_at, size = record(len(b"#ROSBAG V2.0\n"))
    out[header["index_pos"][0]:header["index_pos"][0] + 8] = bytes(8)
    chunk, chunk_data, chunk_size = record(data_at + 4 + size)
    assert chunk["compression"][1] == b"none"
    out[chunk["size"][0]:chunk["size"][0] + 4] = bytes(4)
    out[chunk_data:chunk_data + 4] = bytes(4)
    return bytes(out[:chunk_data + 4 + chunk_size])


@pytest.mark.parametrize("kind,compression", [("ros1", "none"), ("ros1", "bz2"),
                                              ("ros1", "lz4"), ("ros1", "killed"),
                                              ("mcap", "none"), ("mcap", "zstd")])
def test_a_bag_whose_recording_stopped_is_read_up_to_where_it_stops(tmp_path, capsys, kind,
                                                                    compression):
    """A recorder killed or powered off leaves a ROS 1 bag without its index and an MCAP file
    without its summary and end, its last record cut: read record by record, every whole
    message before the cut the whole bag's, and said."""
    bag = write_bag(tmp_path / ("whole.bag" if kind == "ros1" else "whole"), kind,
                    compression="none" if compression == "killed" else compression)
    data = bag if kind == "ros1" else next(bag.glob("*.mcap"))
    raw = data.read_bytes()
    cut = tmp_path / ("cut.bag" if kind == "ros1" else "cut.mcap")
    cut.write_bytes(_killed(raw) if compression == "killed" else raw[:len(raw) * 2 // 3])
    whole, _ = open_recording(bag).load()
    rec, _ = open_recording(cut).load()
    assert 0.3 * len(whole.acc) < len(rec.acc) < len(whole.acc) * (
        1 if compression != "killed" else 1.001)
    for got, want in ((rec.acc, whole.acc), (rec.gyro, whole.gyro), (rec.dt, whole.dt)):
        np.testing.assert_array_equal(got, want[:len(got)])
    status, said = _kf(tmp_path, capsys, cut, "--reference", str(cut))
    assert status == 0, said
    lacks = "its index" if kind == "ros1" else "its summary and end"
    assert f"read record by record, {lacks} never written" in said
    if compression != "killed":
        assert "it ends inside a record (from byte" in said
    assert re.search(r"kf\s+0\s+0\.[0-9]+", said), said


@pytest.mark.parametrize("metadata", [True, False])
def test_a_ros2_bag_folder_whose_mcap_was_cut_is_read_from_its_one_mcap_file(tmp_path,
                                                                            metadata):
    """rosbag2 writes metadata.yaml when it closes the bag: a recorder stopped leaves the folder
    with its MCAP file cut, and with or without a metadata.yaml of an earlier close."""
    bag = write_bag(tmp_path / "run", "mcap")
    mcap = next(bag.glob("*.mcap"))
    raw = mcap.read_bytes()
    whole, _ = open_recording(bag).load()
    mcap.write_bytes(raw[:len(raw) // 2])
    if not metadata:
        (bag / "metadata.yaml").unlink()
    rec, _ = open_recording(bag).load()
    assert 0.3 * len(whole.acc) < len(rec.acc) < len(whole.acc)
    np.testing.assert_array_equal(rec.acc, whole.acc[:len(rec.acc)])


@pytest.mark.parametrize("kind,says", [
    ("ros1", r"not a readable ROS bag \(.*\): a recording stopped before the bag's index was "
             r"written; `rosbag reindex cut\.bag` rebuilds it; read record by record, no whole "
             r"message"),
    ("mcap", r"not a readable ROS bag \(.*\): an MCAP recording stopped before its end was "
             r"written; `mcap recover FILE -o FIXED\.mcap`.*; read record by record, no whole "
             r"message"),
])
def test_a_bag_cut_before_its_first_message_is_refused_saying_how_it_is_repaired(tmp_path,
                                                                                 kind, says):
    """Cut before any whole message, nothing is left to read: refused, with the tool that
    repairs each kind."""
    bag = write_bag(tmp_path / ("whole.bag" if kind == "ros1" else "whole"), kind)
    data = bag if kind == "ros1" else next(bag.glob("*.mcap"))
    raw = data.read_bytes()
    cut = tmp_path / ("cut.bag" if kind == "ros1" else "cut.mcap")
    cut.write_bytes(raw[:raw.index(b"/imu/data") + 20])
    with pytest.raises(RecordingError, match=says):
        open_recording(cut)


@pytest.mark.parametrize("kind", ["ros1", "mcap"])
def test_a_bags_blocks_are_made_of_batches_of_messages_each_block_whole(tmp_path, monkeypatch,
                                                                       kind):
    """Messages are made rows a batch at a time (their bytes are ten times their rows): every
    block but the last has the rows asked for, and the blocks are the whole table."""
    from testbenches import bags

    bag = write_bag(tmp_path / ("run.bag" if kind == "ros1" else "run"), kind)
    monkeypatch.setattr(bags, "MESSAGE_BATCH", 7)
    source = bags.open_bag(bag)
    columns = list(range(len(source.header)))
    whole = source.read(columns)
    assert len(whole) == 1000
    for rows in (5, 7, 20, 1000, 10**6):
        blocks = list(source.blocks(columns, rows))
        assert {len(b) for b in blocks[:-1]} <= {rows}
        np.testing.assert_array_equal(np.concatenate(blocks), whole)


def test_a_bag_whose_bytes_changed_is_read_or_refused_saying_where(tmp_path):
    """A bag changed since it was written (found by changing bytes of bags at random: 18 of
    100 were tracebacks from rosbags, its decompressors or SQLite): one message that does not
    deserialize is a sample without numbers, said; a record that hides what follows it, or
    more such messages than GARBLED_SHARE, refuses the bag naming where."""
    import sqlite3

    folder = write_bag(tmp_path / "run", "ros2")
    db = next(folder.glob("*.db3"))
    with sqlite3.connect(db) as con:
        ids = [r[0] for r in con.execute("SELECT messages.id FROM messages JOIN topics ON "
                                         "topics.id = messages.topic_id WHERE topics.name = "
                                         "'/imu/data' ORDER BY timestamp")]
        con.execute("UPDATE messages SET data = substr(data, 1, 40) WHERE id = ?", (ids[499],))
    source = open_recording(db)
    rec, _ = source.load()
    assert len(rec.dt) == 1000 and np.isnan(rec.acc[499]).all()
    assert np.isfinite(rec.acc[np.arange(1000) != 499]).all()
    assert ("1 message(s) of /imu/data do not deserialize (their bytes changed), taken as "
            "samples without a number (the first: message 500: ") in "; ".join(source.found)
    with sqlite3.connect(db) as con:
        for i in ids[100:120]:
            con.execute("UPDATE messages SET data = substr(data, 1, 40) WHERE id = ?", (i,))
    with pytest.raises(RecordingError, match=r"3 of 103 messages of /imu/data do not "
                       r"deserialize \(more than 1% of them; the first: message 101: .*\): the "
                       r"bag is damaged"):
        open_recording(db).load()

    bag = write_bag(tmp_path / "run.bag", "ros1")
    raw = bag.read_bytes()
    from rosbags.rosbag1 import Reader

    with Reader(bag) as reader:
        imu = [c for c in reader.connections if c.topic == "/imu/data"]
        messages = [m for _, _, m in reader.messages(connections=imu)]
    changed = bytearray(raw)
    at = raw.find(messages[600])  # its record says it is shorter: it does not deserialize
    changed[at - 4:at] = (len(messages[600]) - 9).to_bytes(4, "little")
    at = raw.find(messages[700])  # its record's header says it is longer than it is
    assert int.from_bytes(raw[at - 46:at - 42], "little") == 38  # op, conn, time
    changed[at - 46:at - 42] = (1 << 30).to_bytes(4, "little")
    bag.write_bytes(bytes(changed))
    with pytest.raises(RecordingError, match=r"run.bag: damaged after message 700 of /imu/data: "
                       r"it does not read on from there \(.*\); copy or record it again"):
        open_recording(bag).load()
