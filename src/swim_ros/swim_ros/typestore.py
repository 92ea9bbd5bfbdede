"""The message types every swim tool reads and writes by name (bags, the Foxglove server).

ROS 2 Jazzy's, plus swim_interfaces' from the installed .msg files, in rosbags' typestore; and a type's full definition
in the form rosbag2 puts into an MCAP file and Foxglove reads (``ros2msg``).
"""
from __future__ import annotations

import functools
from pathlib import Path

from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore


def swim_typestore() -> Typestore:
    """ROS 2 Jazzy's types plus swim_interfaces' messages, from the installed .msg files."""
    from ament_index_python.packages import get_package_share_directory
    store = get_typestore(Stores.ROS2_JAZZY)
    message_dir = Path(get_package_share_directory("swim_interfaces")) / "msg"
    for path in sorted(message_dir.glob("*.msg")):
        store.register(get_types_from_msg(path.read_text(), f"swim_interfaces/msg/{path.stem}"))
    return store


@functools.lru_cache(maxsize=None)
def message_definition(msgtype: str) -> str:
    """The definition of msgtype (e.g. ``sensor_msgs/msg/JointState``) with every type it uses, as rosbag2 writes it.

    In an MCAP schema of encoding ``ros2msg``: the type's fields, then per dependency a line of 80 ``=``, ``MSG:
    <package>/<type>`` and its fields. KeyError for a type the typestore does not know.
    """
    store = swim_typestore()
    if msgtype not in store.fielddefs:
        raise KeyError(f"unknown message type {msgtype!r}")
    definition, _ = store.generate_msgdef(msgtype, ros_version=2)
    return definition
