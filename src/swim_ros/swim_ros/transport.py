"""The Fast DDS transports of swim's processes: large messages, or UDP only for a real-time loop.

Large messages. Fast DDS's default shared-memory segment (512 KiB) cuts a 4.6 MB plan into fragments, and the round
trip of a maneuver request grows from about 35 ms to about 110 ms (bench/bench_planner_latency.py). The profile
``config/fastdds_large_messages.xml`` of this package keeps Fast DDS's default transports and enlarges the segment.
A Fast DDS writer sends from its own segment and a reader reads from the writer's, so only a process that sends
plans needs the profile (planner_node, maneuver_node). Fast DDS writes the whole segment into /dev/shm when the
participant starts, so the profile is used only where /dev/shm has room for it (``FREE_SHM_FACTOR``): a container's
/dev/shm is often 64 MiB, and a participant whose segment does not fit there loses its messages.

Real time. A Fast DDS writer opens a reader's shared-memory port the first time it sends to that reader's process,
and checks the port's health as it opens it. A port that has received nothing for a while fails the first look by a
race with Fast DDS's health watchdog, and the writer then sleeps a third of the health timeout (333 ms) holding
itself: the next publish waits as long, in rclpy with the interpreter lock held. A viewer or a recorder that starts
reading a running rig can so stop the bridge's or the tracker's loop for 333 ms (docs/realtime.md, "A publish held
for 333 ms"). The profile ``config/fastdds_real_time.xml`` keeps such a process (bridge_node, tracker_node) on UDP
only, where a send never waits for the reader.

Fast DDS reads the variable in this process and every process it starts: set it only in a process that starts no
nodes of its own (the run client, which starts them, does not). A user's own profile, or another RMW, is left alone.
"""
from __future__ import annotations

import os
import shutil
import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

#: the environment variables Fast DDS reads its XML profiles from (the second is the newer spelling)
PROFILE_VARIABLES = ("FASTRTPS_DEFAULT_PROFILES_FILE", "FASTDDS_DEFAULT_PROFILES_FILE")
FASTDDS_RMW = "rmw_fastrtps_cpp"
#: where rcl reads how far discovery reaches (LOCALHOST, SUBNET, OFF, SYSTEM_DEFAULT)
DISCOVERY_RANGE_VARIABLE = "ROS_AUTOMATIC_DISCOVERY_RANGE"
#: where Fast DDS keeps its shared-memory segments and ports on Linux
SHM_DIR = Path("/dev/shm")
#: /dev/shm must have this many times the segment free: the segment itself, and as much again for the other
#: participants of a run (their default 512 KiB segments and ports) and for a second process that sends plans
FREE_SHM_FACTOR = 2.0
_NAMESPACE = {"p": "http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles"}


@dataclass(frozen=True)
class TransportChoice:
    """What use_large_message_transport or use_real_time_transport decided.

    The profile set (None: Fast DDS's defaults or the user's), why (a sentence for the process's log), and whether that
    is worth a warning (the profile did not fit, or could not carry the user's discovery).
    """

    profile: Optional[Path]
    reason: str
    warning: bool = False


def large_message_profile() -> Path:
    """The installed Fast DDS profile file of swim_ros."""
    from ament_index_python.packages import get_package_share_directory
    return Path(get_package_share_directory("swim_ros")) / "config" / "fastdds_large_messages.xml"


def real_time_profile(localhost: bool = False) -> Path:
    """The installed Fast DDS profile file of swim_ros for a process with a real-time loop (UDPv4 only).

    localhost: the variant that keeps discovery on this host, as ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST does.
    """
    from ament_index_python.packages import get_package_share_directory
    name = "fastdds_real_time_localhost.xml" if localhost else "fastdds_real_time.xml"
    return Path(get_package_share_directory("swim_ros")) / "config" / name


def segment_bytes(profile: Path) -> int:
    """The shared-memory segment size the profile sets, bytes (its SHM transport's segment_size)."""
    root = ElementTree.parse(profile).getroot()
    for descriptor in root.iterfind("p:transport_descriptors/p:transport_descriptor", _NAMESPACE):
        if descriptor.findtext("p:type", namespaces=_NAMESPACE) == "SHM":
            return int(descriptor.findtext("p:segment_size", namespaces=_NAMESPACE) or 0)
    raise ValueError(f"{profile} has no SHM transport")


def free_shm_bytes(shm_dir: Path = SHM_DIR) -> Optional[int]:
    """Bytes free in shm_dir, or None where there is no such directory."""
    try:
        return shutil.disk_usage(shm_dir).free
    except OSError:
        return None


def choose_transport(segment_size_bytes: int, free_bytes: Optional[int]) -> bool:
    """Whether a segment of segment_size_bytes fits a /dev/shm with free_bytes free.

    free_bytes None means no /dev/shm, as on other systems than Linux, where Fast DDS keeps its segments elsewhere: it
    fits.
    """
    return free_bytes is None or free_bytes >= FREE_SHM_FACTOR * segment_size_bytes


def use_large_message_transport(shm_dir: Path = SHM_DIR) -> TransportChoice:
    """Point Fast DDS at swim's profile if it fits; call before rclpy.init (the first participant reads it).

    Left alone: another RMW than Fast DDS, a profile the user chose through FASTRTPS_DEFAULT_PROFILES_FILE or
    FASTDDS_DEFAULT_PROFILES_FILE, and a /dev/shm (shm_dir) too small for the segment (FREE_SHM_FACTOR).
    """
    left = _left_alone()
    if left is not None:
        return left
    profile = large_message_profile()
    size, free = segment_bytes(profile), free_shm_bytes(shm_dir)
    mib = 1 << 20
    if not choose_transport(size, free):
        return TransportChoice(None, f"{shm_dir} has {(free or 0) / mib:.0f} MiB free, too little for a "
                                     f"{size / mib:.0f} MiB shared-memory segment: Fast DDS's default "
                                     f"transport, a plan crosses in fragments (slower)", warning=True)
    os.environ[PROFILE_VARIABLES[0]] = str(profile)
    return TransportChoice(profile, f"Fast DDS profile {profile}: a {size / mib:.0f} MiB shared-memory "
                                    f"segment, a plan crosses in one piece")


def use_real_time_transport() -> TransportChoice:
    """Point Fast DDS at swim's real-time profile (UDPv4 only); call before rclpy.init.

    With ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST rmw_fastrtps adds shared memory to any profile, so the range is set
    to SYSTEM_DEFAULT and the profile that keeps discovery on this host is used instead. Left alone: another RMW than
    Fast DDS, a profile the user chose through FASTRTPS_DEFAULT_PROFILES_FILE or FASTDDS_DEFAULT_PROFILES_FILE,
    discovery off, and static peers or ROS_LOCALHOST_ONLY (which the profile would not carry): these keep shared
    memory, with a warning.
    """
    left = _left_alone()
    if left is not None:
        return left
    discovery_range = os.environ.get(DISCOVERY_RANGE_VARIABLE, "")
    if discovery_range == "OFF":
        return TransportChoice(None, "discovery off: Fast DDS's default transport")
    if os.environ.get("ROS_STATIC_PEERS") or os.environ.get("ROS_LOCALHOST_ONLY") == "1":
        return TransportChoice(None, "ROS_STATIC_PEERS or ROS_LOCALHOST_ONLY set: Fast DDS's default transport, "
                                     "whose shared memory can hold a publish of the loop's for 333 ms", warning=True)
    localhost = discovery_range == "LOCALHOST"
    profile = real_time_profile(localhost)
    if localhost:
        os.environ[DISCOVERY_RANGE_VARIABLE] = "SYSTEM_DEFAULT"   # the profile keeps discovery on this host
    os.environ[PROFILE_VARIABLES[0]] = str(profile)
    return TransportChoice(profile, f"Fast DDS profile {profile}: UDP only, so that no reader's shared-memory port "
                                    "can hold a publish of the loop's")


def _left_alone() -> Optional[TransportChoice]:
    """The choice to leave Fast DDS as it is (another RMW, a profile the user chose), or None."""
    if os.environ.get("RMW_IMPLEMENTATION", FASTDDS_RMW) != FASTDDS_RMW:
        return TransportChoice(None, "another RMW than Fast DDS: its own transport")
    if any(os.environ.get(variable) for variable in PROFILE_VARIABLES):
        return TransportChoice(None, "the Fast DDS profile the user chose")
    return None
