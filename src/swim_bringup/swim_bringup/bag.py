"""Bags of a run, written and read with rosbags (rosbag2 MCAP, readable by `ros2 bag info` on a full install).

Messages are stored as the CDR bytes rclpy received (no re-encoding); the bag's connections carry the full
message definitions, ours included (from swim_interfaces' installed .msg files), so any rosbag2 reader can
decode them.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Iterator

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
}


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
        self._connections = {topic: self._writer.add_connection(topic, msgtype, typestore=self.store)
                             for topic, msgtype in topics.items()}
        self.counts = dict.fromkeys(topics, 0)

    def write(self, topic: str, timestamp_ns: int, cdr: bytes) -> None:
        assert self._writer is not None, "BagWriter.write after close()"
        self._writer.write(self._connections[topic], timestamp_ns, cdr)
        self.counts[topic] += 1

    def close(self) -> None:
        """Finish the bag (its summary and metadata.yaml); safe to call twice."""
        if self._writer is not None:
            self._writer.close()
            self._writer = None


def read_messages(path: Path, topics: tuple[str, ...]) -> Iterator[tuple[str, int, Any]]:
    """(topic, log time ns, decoded message: the typestore's class of its type) for the topics asked, in log-time
    order."""
    store = swim_typestore()
    with Reader(path) as reader:
        connections = [c for c in reader.connections if c.topic in topics]
        for connection, timestamp, raw in reader.messages(connections=connections):
            yield connection.topic, timestamp, store.deserialize_cdr(raw, connection.msgtype)
