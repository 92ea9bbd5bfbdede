"""Units accepted in rig files, and their conversion to SI.

Each rig parameter has a dimension; its value in the file may be given in any unit of that
dimension listed here and is converted to the SI unit on load. A unit of another dimension is an
error (a length written in kg is a mistake, not something to convert).
"""
from __future__ import annotations

import math

OUNCE_FORCE_INCH_N_M = 0.00706155181422604  # 1 ozf*in = 0.0283495231 kg * 9.80665 m/s^2 * 0.0254 m

#: dimension -> {unit spelling: factor to the SI unit}
UNITS: dict[str, dict[str, float]] = {
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "in": 0.0254},
    "mass": {"kg": 1.0, "g": 1e-3},
    "inertia": {"kg*m^2": 1.0, "g*cm^2": 1e-7},
    "density": {"kg/m^3": 1.0},
    "torque": {"N*m": 1.0, "mN*m": 1e-3, "oz*in": OUNCE_FORCE_INCH_N_M},
    "angle": {"rad": 1.0, "deg": math.pi / 180.0},
    "time": {"s": 1.0, "ms": 1e-3},
    "ratio": {"1": 1.0},
    "lines_per_rev": {"lines/rev": 1.0},
    "lines_per_length": {"lines/m": 1.0, "lines/in": 1.0 / 0.0254},
}

SI_UNIT: dict[str, str] = {dim: next(iter(table)) for dim, table in UNITS.items()}


def to_si(value: float, unit: str, dimension: str) -> float:
    """Convert ``value`` given in ``unit`` to the SI unit of ``dimension``.

    Raises KeyError when ``unit`` is not a unit of ``dimension``.
    """
    return float(value) * UNITS[dimension][unit]
