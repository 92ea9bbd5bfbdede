"""Between ROS message fields and numpy: float64[] arrays and stamps."""
from __future__ import annotations

import array

import numpy as np
import numpy.typing as npt
from builtin_interfaces.msg import Time


def float_array(values: npt.ArrayLike) -> array.array:
    """values, flattened, as array('d'): a message's float64[] field takes it without checking each element
    (a list of 200,000 floats costs rosidl's setter about 40 ms)."""
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
