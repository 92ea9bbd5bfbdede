"""Between ROS message fields and numpy: float64[] arrays, stamps, joint states and torque commands.

Decoders refuse wrong names, wrong lengths and non-finite values with a MessageError saying what is wrong;
callers count and drop such a message, never use it.
"""
from __future__ import annotations

import array
import math
from typing import Optional, Sequence

import numpy as np
import numpy.typing as npt
from builtin_interfaces.msg import Time

#: the motor-driven joints of the rig, in the order of a torque pair: heave (phi), then pitch (theta)
ACTUATED_JOINTS = ("phi", "theta")


class MessageError(ValueError):
    """A message that cannot be used: wrong names or lengths, or a non-finite value."""


def float_array(values: npt.ArrayLike) -> array.array:
    """values, flattened, as array('d').

    A message's float64[] field takes it without checking each element (a list of 200,000 floats costs rosidl's setter
    about 40 ms).
    """
    converted = array.array("d")
    converted.frombytes(np.ascontiguousarray(values, dtype=np.float64).tobytes())
    return converted


def stamp_of(time_s: float) -> Time:
    """A builtin_interfaces/Time from seconds, rounded to the nanosecond (so stamps compare exactly)."""
    nanoseconds = int(round(time_s * 1e9))
    return Time(sec=nanoseconds // 1_000_000_000, nanosec=nanoseconds % 1_000_000_000)


def seconds_of(stamp: Time) -> float:
    """A builtin_interfaces/Time in seconds (0.0 for the zero stamp, which means "not stamped")."""
    return stamp.sec + 1e-9 * stamp.nanosec


def joint_state_arrays(names: Sequence[str], positions: Sequence[float], velocities: Sequence[float],
                       joint_names: Sequence[str]) -> tuple[np.ndarray, Optional[np.ndarray]]:
    """(q, qdot) in joint_names' order from a sensor_msgs/JointState's name, position and velocity (any order).

    qdot None when the message has no velocities. Raises MessageError.
    """
    names, joint_names = list(names), list(joint_names)
    if sorted(names) != sorted(joint_names) or len(set(names)) != len(names):
        raise MessageError(f"joint names {names}, expected {joint_names} (any order)")
    if len(positions) != len(names):
        raise MessageError(f"{len(positions)} positions for {len(names)} joints")
    if len(velocities) not in (0, len(names)):
        raise MessageError(f"{len(velocities)} velocities for {len(names)} joints (0 or one each)")
    order = [names.index(joint) for joint in joint_names]
    q = np.asarray(positions, dtype=float)[order]
    if not np.all(np.isfinite(q)):
        raise MessageError(f"non-finite position: {q}")
    if len(velocities) == 0:
        return q, None
    qdot = np.asarray(velocities, dtype=float)[order]
    if not np.all(np.isfinite(qdot)):
        raise MessageError(f"non-finite velocity: {qdot}")
    return q, qdot


def torque_from_command(names: Sequence[str], efforts: Sequence[float]) -> tuple[float, float]:
    """(heave, pitch) joint torques, N m, from a joint_commands message's names and efforts.

    Names exactly ACTUATED_JOINTS once each (any order), one finite effort per name. Raises MessageError.
    """
    names = list(names)
    if sorted(names) != sorted(ACTUATED_JOINTS):
        raise MessageError(f"joint names must be {list(ACTUATED_JOINTS)} (any order), got {names}")
    if len(efforts) != len(names):
        raise MessageError(f"{len(names)} names but {len(efforts)} efforts")
    torque = dict(zip(names, (float(e) for e in efforts)))
    if not all(math.isfinite(v) for v in torque.values()):
        raise MessageError(f"efforts must be finite, got {list(efforts)}")
    return torque[ACTUATED_JOINTS[0]], torque[ACTUATED_JOINTS[1]]
