"""The Fast DDS transport of swim's processes that send plans: a shared-memory segment large enough for a plan.

Fast DDS's default shared-memory segment (512 KiB) cuts a 4.6 MB plan into fragments, and the round trip of a
maneuver request grows from about 35 ms to about 110 ms (bench/bench_planner_latency.py). The profile
``config/fastdds_large_messages.xml`` of this package keeps Fast DDS's default transports and enlarges the segment.

A Fast DDS writer sends from its own segment and a reader reads from the writer's, so only a process that sends
plans needs the profile (planner_node). Fast DDS reads the variable in this process and every process it starts:
set it only in a process that starts no nodes of its own (the run client, which starts them, does not). Fast DDS
writes the whole segment into /dev/shm when the participant starts, so the profile is used only where /dev/shm has
room for it (``FREE_SHM_FACTOR``): a container's /dev/shm is often 64 MiB, and a participant whose segment does not
fit there loses its messages. A user's own profile, or another RMW, is left alone.
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
#: where Fast DDS keeps its shared-memory segments and ports on Linux
SHM_DIR = Path("/dev/shm")
#: /dev/shm must have this many times the segment free: the segment itself, and as much again for the other
#: participants of a run (their default 512 KiB segments and ports) and for a second process that sends plans
FREE_SHM_FACTOR = 2.0
_NAMESPACE = {"p": "http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles"}


@dataclass(frozen=True)
class TransportChoice:
    """What use_large_message_transport decided.

    The profile set (None: Fast DDS's defaults or the user's), why (a sentence for the process's log), and whether that
    is worth a warning (the profile did not fit).
    """

    profile: Optional[Path]
    reason: str
    warning: bool = False


def large_message_profile() -> Path:
    """The installed Fast DDS profile file of swim_ros."""
    from ament_index_python.packages import get_package_share_directory
    return Path(get_package_share_directory("swim_ros")) / "config" / "fastdds_large_messages.xml"


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
    if os.environ.get("RMW_IMPLEMENTATION", FASTDDS_RMW) != FASTDDS_RMW:
        return TransportChoice(None, "another RMW than Fast DDS: its own transport")
    if any(os.environ.get(variable) for variable in PROFILE_VARIABLES):
        return TransportChoice(None, "the Fast DDS profile the user chose")
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
