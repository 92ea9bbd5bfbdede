"""What foxglove_node sends to a live Foxglove client and what it accepts from one, without ROS.

- ``RateGate``: a stream's bound; a message that comes sooner than 1/rate after the last one sent is dropped, never
  queued, so a slow client or a fast topic costs the loop nothing.
- ``parse_maneuver_request``: a maneuver service call's JSON, checked field by field, as the fields of a
  swim_interfaces/PerformManeuver goal; ``ManeuverRequestError`` names what is wrong, and nothing is sent.
- ``fault_changes``: the bridge's latched faults before and after a /diagnostics message, as log lines.
- ``path_entity`` and ``wake_entity``: the planned and travelled paths (swim_viz.markers' lines) and the wake's
  vortices as Foxglove scene entities, in the tank frame.
"""
from __future__ import annotations

import dataclasses
import json
import math
from typing import Any, Mapping, Optional, Sequence

import numpy as np
import numpy.typing as npt
from foxglove.messages import (
    Color,
    LinePrimitive,
    LinePrimitiveLineType,
    Point3,
    Pose,
    Quaternion,
    SceneEntity,
    SpherePrimitive,
    Timestamp,
    Vector3,
)

#: the latched-fault names a bridge reports when none is latched (swim_hw_bridge.safety)
NO_FAULT = "NONE"


class RateGate:
    """Lets a message through when at least 1/max_rate_hz has passed since the last one let through.

    Times are in s on any monotonic clock; max_rate_hz 0 lets every message through.
    """

    def __init__(self, max_rate_hz: float) -> None:
        if not (math.isfinite(max_rate_hz) and max_rate_hz >= 0.0):
            raise ValueError(f"a rate bound must be finite and at least 0 Hz, got {max_rate_hz!r}")
        self.interval_s = 1.0 / max_rate_hz if max_rate_hz > 0.0 else 0.0
        self._last_s = -math.inf
        self.passed = 0
        self.dropped = 0

    def due(self, now_s: float) -> bool:
        """Whether a message at now_s (s) goes through; counts it as passed or dropped."""
        if now_s - self._last_s >= self.interval_s:
            self._last_s = now_s
            self.passed += 1
            return True
        self.dropped += 1
        return False


class ManeuverRequestError(ValueError):
    """A maneuver call that cannot become a goal: what is wrong with it."""


#: PerformManeuver's modes by the names a call gives them (swim_interfaces/action/PerformManeuver.action)
MANEUVER_MODES = {"sequence": 0, "goal": 1}
#: the optional non-negative numbers of a call, with their goal field names (0: the action's default)
MANEUVER_NUMBERS = ("time_scale", "path_tolerance_alpha_rad", "path_tolerance_r_m", "goal_tolerance_alpha_rad",
                    "goal_tolerance_r_m")

#: the JSON schema of a maneuver call, as the app shows it: a sequence of library primitives, or a goal state
MANEUVER_REQUEST_SCHEMA: dict[str, Any] = {
    "title": "swim maneuver",
    "type": "object",
    "additionalProperties": False,
    "properties": {
        "mode": {"enum": list(MANEUVER_MODES), "description": "a primitive sequence, or a goal state of the graph"},
        "primitive_ids": {"type": "array", "items": {"type": "string"},
                          "description": "sequence: library ids, in order"},
        "repeat_counts": {"type": "array", "items": {"type": "integer", "minimum": 1},
                          "description": "sequence: one per id (omitted: 1 each)"},
        "goal_state": {"type": "string", "description": "goal: the graph node to end at, e.g. free/rest/R0.48"},
        "goal_alpha_rad": {"type": "number", "description": "goal: at least this displacement, rad"},
        **{name: {"type": "number", "minimum": 0, "description": "0 or omitted: the action's default"}
           for name in MANEUVER_NUMBERS},
    },
    "required": ["mode"],
}


def _number(request: Mapping[str, Any], name: str, minimum: Optional[float]) -> float:
    value = request.get(name, 0.0)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ManeuverRequestError(f"{name} must be a finite number, got {value!r}")
    if minimum is not None and value < minimum:
        raise ManeuverRequestError(f"{name} must be at least {minimum}, got {value!r}")
    return float(value)


def parse_maneuver_request(payload: bytes) -> dict[str, Any]:
    """A maneuver call's JSON payload (MANEUVER_REQUEST_SCHEMA) as PerformManeuver goal fields.

    The planner and the maneuver action check the rest (known primitives, a vehicle at rest) when the goal arrives.
    """
    try:
        request = json.loads(payload)
    except (UnicodeDecodeError, json.JSONDecodeError) as err:
        raise ManeuverRequestError(f"the request is not JSON: {err}") from None
    if not isinstance(request, dict):
        raise ManeuverRequestError(f"the request must be a JSON object, got {type(request).__name__}")
    known: set[str] = set(MANEUVER_REQUEST_SCHEMA["properties"])
    unknown = sorted(set(request) - known)
    if unknown:
        raise ManeuverRequestError(f"unknown fields {unknown}; known: {sorted(known)}")
    mode = request.get("mode")
    if mode not in MANEUVER_MODES:
        raise ManeuverRequestError(f"mode must be one of {list(MANEUVER_MODES)}, got {mode!r}")
    goal: dict[str, Any] = {"mode": MANEUVER_MODES[mode]}
    if mode == "sequence":
        ids, counts = request.get("primitive_ids"), request.get("repeat_counts", [])
        if not isinstance(ids, list) or not ids or not all(isinstance(i, str) and i for i in ids):
            raise ManeuverRequestError("a sequence needs primitive_ids: a non-empty list of library ids")
        if not isinstance(counts, list) or not all(isinstance(c, int) and not isinstance(c, bool) and c >= 1
                                                   for c in counts):
            raise ManeuverRequestError(f"repeat_counts must be a list of integers >= 1, got {counts!r}")
        if counts and len(counts) != len(ids):
            raise ManeuverRequestError(f"{len(counts)} repeat_counts for {len(ids)} primitive_ids")
        goal.update(primitive_ids=ids, repeat_counts=counts)
    else:
        state = request.get("goal_state")
        if not isinstance(state, str) or not state:
            raise ManeuverRequestError("a goal needs goal_state: a node of the planner's graph")
        goal.update(goal_state=state, goal_alpha_rad=_number(request, "goal_alpha_rad", None))
    goal.update({name: _number(request, name, 0.0) for name in MANEUVER_NUMBERS})
    return goal


@dataclasses.dataclass(frozen=True)
class LogLine:
    """One line for the app's log panel: its level (info, warning, error) and text."""

    level: str
    text: str


def fault_changes(previous: str, current: str, source: str = "bridge") -> list[LogLine]:
    """The faults latched and cleared between two reports of a bridge's faults, as log lines.

    A report is '|'-separated fault names, NO_FAULT for none.
    """
    def names(faults: str) -> set[str]:
        return {name for name in faults.split("|") if name and name != NO_FAULT}
    before, after = names(previous), names(current)
    lines = [LogLine("error", f"{source}: {name} latched, motors off") for name in sorted(after - before)]
    if before and not after:
        lines.append(LogLine("info", f"{source}: faults cleared ({'|'.join(sorted(before))})"))
    return lines


def _timestamp(stamp_ns: int) -> Timestamp:
    return Timestamp(sec=stamp_ns // 1_000_000_000, nsec=stamp_ns % 1_000_000_000)


def path_entity(entity_id: str, frame_id: str, points_m: npt.ArrayLike, rgba: Sequence[float], width_m: float,
                stamp_ns: int) -> SceneEntity:
    """A polyline (points (N, 3), m) as a scene entity of one line strip, drawn in frame_id."""
    points = np.asarray(points_m, dtype=float).reshape(-1, 3)
    line = LinePrimitive(type=LinePrimitiveLineType.LineStrip, pose=_identity_pose(), thickness=width_m,
                         scale_invariant=False, points=[Point3(x=p[0], y=p[1], z=p[2]) for p in points],
                         color=Color(r=rgba[0], g=rgba[1], b=rgba[2], a=rgba[3]))
    return SceneEntity(timestamp=_timestamp(stamp_ns), frame_id=frame_id, id=entity_id, lines=[line])


#: the wake's vortices: a sphere per vortex, its diameter growing with |circulation| from the smallest to the
#: largest drawn (sizes seen at the tank's scale of about 1 m), red counter-clockwise, blue clockwise
VORTEX_DIAMETER_RANGE_M = (0.004, 0.02)
#: the circulation drawn at the largest diameter, m^2/s: a strong trailing-edge vortex of a cruise
VORTEX_FULL_SCALE_CIRCULATION_M2_S = 2e-3
COUNTER_CLOCKWISE_RGBA = (0.85, 0.2, 0.2, 0.8)
CLOCKWISE_RGBA = (0.2, 0.35, 0.85, 0.8)
#: the wake lies in the plane of the rails, at the tank frame's z = 0
WAKE_PLANE_Z_M = 0.0


def wake_entity(entity_id: str, frame_id: str, x_m: npt.ArrayLike, y_m: npt.ArrayLike,
                circulations_m2_s: npt.ArrayLike, stamp_ns: int) -> SceneEntity:
    """The wake's free vortices as a scene entity of spheres.

    Positions are in frame_id, m; circulations in m^2/s, counter-clockwise positive.
    """
    x, y, gamma = (np.asarray(v, dtype=float) for v in (x_m, y_m, circulations_m2_s))
    if not (x.shape == y.shape == gamma.shape):
        raise ValueError(f"the wake's arrays differ in length: {x.shape}, {y.shape}, {gamma.shape}")
    small, large = VORTEX_DIAMETER_RANGE_M
    spheres = []
    for xi, yi, gi in zip(x, y, gamma):
        if not (math.isfinite(xi) and math.isfinite(yi) and math.isfinite(gi)):
            continue
        diameter_m = small + (large - small) * min(abs(gi) / VORTEX_FULL_SCALE_CIRCULATION_M2_S, 1.0)
        rgba = COUNTER_CLOCKWISE_RGBA if gi >= 0.0 else CLOCKWISE_RGBA
        spheres.append(SpherePrimitive(pose=Pose(position=Vector3(x=xi, y=yi, z=WAKE_PLANE_Z_M),
                                                 orientation=Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)),
                                       size=Vector3(x=diameter_m, y=diameter_m, z=diameter_m),
                                       color=Color(r=rgba[0], g=rgba[1], b=rgba[2], a=rgba[3])))
    return SceneEntity(timestamp=_timestamp(stamp_ns), frame_id=frame_id, id=entity_id, spheres=spheres)


def _identity_pose() -> Pose:
    return Pose(position=Vector3(x=0.0, y=0.0, z=0.0), orientation=Quaternion(x=0.0, y=0.0, z=0.0, w=1.0))
