"""Units accepted in parameter files (rig.yaml, the bridge's bridge.yaml), and their conversion to SI.

Each rig parameter has a dimension; its value in the file may be given in any unit of that
dimension listed here and is converted to the SI unit on load. A unit of another dimension is an
error (a length written in kg is a mistake, not something to convert).
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

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
    "angular_speed": {"rad/s": 1.0, "rpm": 2.0 * math.pi / 60.0},
    "speed": {"m/s": 1.0},
}

#: sign rules of a parameter file's entries
POSITIVE, NON_NEGATIVE, SIGNED = "positive", "non-negative", "signed"


class EntryError(ValueError):
    """A parameter file's entry that cannot be used; the message says where and why."""


def entry_to_si(entry: Any, dimension: str, sign_rule: str, where: str,
                units: Mapping[str, Mapping[str, float]] = UNITS) -> float:
    """One entry of a parameter file (rig.yaml, bridge.yaml) in the SI unit of its dimension.

    Parameters
    ----------
    entry : mapping
        ``value``, ``unit`` and exactly one of ``source`` (where the number comes from) or ``assumed`` (why it was
        chosen).
    dimension : str
        A key of ``units`` (``"length"``, ``"torque"``, ...).
    sign_rule : str
        POSITIVE, NON_NEGATIVE or SIGNED.
    where : str
        Names the entry in messages (file and key).
    units : mapping, optional
        Each dimension's accepted units and their factors to SI (the first listed is the SI unit).

    Returns
    -------
    float
        The value in SI.

    Raises
    ------
    EntryError
        For a missing field, a unit of another dimension, a non-finite value or a sign the rule forbids.
    """
    if not isinstance(entry, Mapping) or "value" not in entry or "unit" not in entry:
        raise EntryError(f"{where} must be a mapping with 'value' and 'unit'")
    if ("source" in entry) == ("assumed" in entry):
        raise EntryError(f"{where} must say exactly one of 'source' (paper) or 'assumed' (why)")
    unit, table = str(entry["unit"]), units[dimension]
    if unit not in table:
        raise EntryError(f"{where} has unit '{unit}', which is not a {dimension.replace('_', ' ')} unit; "
                         f"use one of {', '.join(table)} (SI: {next(iter(table))})")
    value = entry["value"]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise EntryError(f"{where} has value {value!r}; expected a finite number")
    si_value = float(value) * table[unit]
    if sign_rule == POSITIVE and not si_value > 0.0:
        raise EntryError(f"{where} is {value} {unit}; it must be positive")
    if sign_rule == NON_NEGATIVE and si_value < 0.0:
        raise EntryError(f"{where} is {value} {unit}; it must not be negative")
    return si_value
