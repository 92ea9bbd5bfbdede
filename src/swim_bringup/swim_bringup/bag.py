"""Bags of a run, written and read with rosbags (rosbag2 MCAP, readable by `ros2 bag info` on a full install).

Messages are stored as the CDR bytes rclpy received (no re-encoding); the bag's connections carry the full
message definitions, ours included (from swim_interfaces' installed .msg files), so any rosbag2 reader can
decode them. A bag is written in chunks (MCAP); flush() ends the chunk under way and puts it on disk, so a
recorder killed before close() leaves a bag whose written chunks read_messages still reads (without the summary
and metadata.yaml that close() writes).
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Iterator, Sequence

from rosbags.interfaces import Qos
from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

#: the run's topics and their types (the demo records all of them)
RUN_TOPICS = {
    "joint_states": "sensor_msgs/msg/JointState",
    "joint_commands": "sensor_msgs/msg/JointState",
    "tracking_state": "swim_interfaces/msg/TrackingState",
    "plan": "swim_interfaces/msg/PlannedTrajectory",
    "wake_statistics": "swim_interfaces/msg/WakeStatistics",   # only when the simulator's wake is on
    "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray",      # bridge_node's loop, watchdog and faults
    "robot_description": "std_msgs/msg/String",                 # swim_viz's rig_state_publisher: the URDF
    "/tf": "tf2_msgs/msg/TFMessage",                            # ... the rig's moving frames
    "/tf_static": "tf2_msgs/msg/TFMessage",                     # ... and its fixed ones
    "markers": "visualization_msgs/msg/MarkerArray",            # swim_viz's marker_node: planned, travelled path
}
#: the latched topics (transient local, depth 1): a recorder that subscribes late still gets their last message
LATCHED_TOPICS = ("plan", "robot_description", "/tf_static")


class BagError(RuntimeError):
    """A bag that cannot be read or written as asked (an unknown message type, a folder without a bag)."""


def swim_typestore() -> Typestore:
    """ROS 2 Jazzy's types plus swim_interfaces' messages, from the installed .msg files."""
    from ament_index_python.packages import get_package_share_directory
    store = get_typestore(Stores.ROS2_JAZZY)
    message_dir = Path(get_package_share_directory("swim_interfaces")) / "msg"
    for path in sorted(message_dir.glob("*.msg")):
        store.register(get_types_from_msg(path.read_text(), f"swim_interfaces/msg/{path.stem}"))
    return store


class BagWriter:
    """An MCAP rosbag2 bag of raw CDR messages, one connection per topic."""

    def __init__(self, path: Path, topics: dict[str, str] = RUN_TOPICS) -> None:
        self.store = swim_typestore()
        self._writer: Writer | None = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
        self._writer.open()
        self._connections: dict[str, Any] = {}
        self.counts: dict[str, int] = {}
        for topic, msgtype in topics.items():
            self.add_topic(topic, msgtype)

    def add_topic(self, topic: str, msgtype: str, offered_qos: Sequence[Qos] = ()) -> None:
        """A connection for topic, of type msgtype (e.g. 'sensor_msgs/msg/JointState'), with the QoS profiles its
        publishers offer (for metadata.yaml and a player). BagError for a type the type store does not know."""
        assert self._writer is not None, "BagWriter.add_topic after close()"
        if msgtype not in self.store.fielddefs:
            raise BagError(f"unknown message type {msgtype} (topic {topic}): not a ROS 2 Jazzy type nor ours")
        self._connections[topic] = self._writer.add_connection(topic, msgtype, typestore=self.store,
                                                               offered_qos_profiles=offered_qos)
        self.counts[topic] = 0

    def write(self, topic: str, timestamp_ns: int, cdr: bytes) -> None:
        assert self._writer is not None, "BagWriter.write after close()"
        self._writer.write(self._connections[topic], timestamp_ns, cdr)
        self.counts[topic] += 1

    def flush(self) -> None:
        """End the chunk under way, if any, and put everything written on disk: a recorder killed after this
        leaves a bag that reads up to here."""
        assert self._writer is not None, "BagWriter.flush after close()"
        storage: Any = self._writer.storage   # rosbags' MCAP storage: chunks of up to 1 MiB, on its own file
        if storage.chunk.bio.tell():
            storage.close_chunk()
        storage.bio.flush()

    def close(self) -> None:
        """Finish the bag (its summary and metadata.yaml); safe to call twice."""
        if self._writer is not None:
            self._writer.close()
            self._writer = None


def read_messages(path: Path, topics: tuple[str, ...]) -> Iterator[tuple[str, int, Any]]:
    """(topic, log time ns, decoded message: the typestore's class of its type) for the topics asked, in log-time
    order; of a bag cut before close() (no metadata.yaml), the messages of its complete chunks in the order
    written."""
    store = swim_typestore()
    if not (Path(path) / "metadata.yaml").is_file():
        for topic, timestamp, msgtype, raw in read_cut_bag(Path(path), topics):
            yield topic, timestamp, store.deserialize_cdr(raw, msgtype)
        return
    with Reader(path) as reader:
        connections = [c for c in reader.connections if c.topic in topics]
        for connection, timestamp, raw in reader.messages(connections=connections):
            yield connection.topic, timestamp, store.deserialize_cdr(raw, connection.msgtype)


def read_cut_bag(path: Path, topics: tuple[str, ...]) -> Iterator[tuple[str, int, str, bytes]]:
    """(topic, log time ns, type name, CDR bytes) of the messages in the complete chunks of a bag folder's MCAP
    file that has no summary (its recorder was killed), read linearly with the mcap library (Foxglove's reader)
    up to the first incomplete record."""
    from mcap.exceptions import EndOfFile
    from mcap.records import Channel, Message, Schema
    from mcap.stream_reader import StreamReader
    files = sorted(Path(path).glob("*.mcap"))
    if len(files) != 1:
        raise BagError(f"{path}: no metadata.yaml and {len(files)} MCAP files (expected one)")
    schemas: dict[int, str] = {}
    channels: dict[int, tuple[str, str]] = {}
    with open(files[0], "rb") as stream:
        try:
            for record in StreamReader(stream, skip_magic=False, validate_crcs=False).records:
                if isinstance(record, Schema):
                    schemas[record.id] = record.name
                elif isinstance(record, Channel):
                    channels[record.id] = (record.topic, schemas[record.schema_id])
                elif isinstance(record, Message) and channels[record.channel_id][0] in topics:
                    topic, msgtype = channels[record.channel_id]
                    yield topic, record.log_time, msgtype, record.data
        except EndOfFile:
            return
