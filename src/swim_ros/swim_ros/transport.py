"""The Fast DDS transport of swim's processes: a shared-memory segment large enough for a plan in one piece.

Fast DDS's default shared-memory segment (512 KiB) cuts a 4.6 MB plan into fragments, and the round trip of a
maneuver request grows from about 40 ms to about 110 ms (bench/bench_planner_latency.py). The profile
``config/fastdds_large_messages.xml`` of this package keeps Fast DDS's default transports and enlarges the segment.
A Fast DDS writer sends from its own segment, so the profile matters in the processes that send large messages
(planner_node); every swim node uses it. A user's own profile, or another RMW, is left alone.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Optional

#: the environment variables Fast DDS reads its XML profiles from (the second is the newer spelling)
PROFILE_VARIABLES = ("FASTRTPS_DEFAULT_PROFILES_FILE", "FASTDDS_DEFAULT_PROFILES_FILE")
FASTDDS_RMW = "rmw_fastrtps_cpp"


def large_message_profile() -> Path:
    """The installed Fast DDS profile file of swim_ros."""
    from ament_index_python.packages import get_package_share_directory
    return Path(get_package_share_directory("swim_ros")) / "config" / "fastdds_large_messages.xml"


def use_large_message_transport() -> Optional[Path]:
    """Point Fast DDS at swim's profile; call before rclpy.init (the first participant reads it).

    Returns the profile used, or None where it is left alone: another RMW than Fast DDS, or a profile the user
    chose through FASTRTPS_DEFAULT_PROFILES_FILE or FASTDDS_DEFAULT_PROFILES_FILE."""
    if os.environ.get("RMW_IMPLEMENTATION", FASTDDS_RMW) != FASTDDS_RMW:
        return None
    if any(os.environ.get(variable) for variable in PROFILE_VARIABLES):
        return None
    profile = large_message_profile()
    os.environ[PROFILE_VARIABLES[0]] = str(profile)
    return profile
