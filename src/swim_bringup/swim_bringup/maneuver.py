"""What a maneuver goal asks for, and where the vehicle is: the checks and the start of a perform_maneuver goal.

No ROS here: maneuver_node (and swim-maneuver) turn messages into these types and back. A goal names a primitive
sequence or a goal state of the planner's lane/energy graph (swim_planner.graph); the plan starts where the vehicle
is, at its alpha, on the lane nearest its R, and a maneuver that starts from rest is flown only by a vehicle at rest.
"""
from __future__ import annotations

import dataclasses
import math
import re
from typing import Optional, Sequence

import numpy as np
import numpy.typing as npt

from swim_controller.supervisor import Tolerances

Array = npt.NDArray[np.float64]

#: RequestManeuver's and PerformManeuver's modes
MODE_SEQUENCE, MODE_GOAL = 0, 1
#: the graph's rest states (swim_planner.graph.rest_node): the constrained vehicle's, and the free vehicle's per lane
CONSTRAINED_REST_STATE = "constrained/rest"
FREE_REST_STATE = re.compile(r"^free/rest/R(?P<lane_radius_m>\d+(?:\.\d+)?)$")


class ManeuverGoalError(ValueError):
    """A goal that cannot be started as asked: the reason, for the operator."""


class NotAtRest(ManeuverGoalError):
    """The vehicle moves faster than the rest bounds (it may come to rest a moment later)."""


@dataclasses.dataclass(frozen=True)
class RestBounds:
    """The joint speeds under which the vehicle counts as at rest.

    Every angular joint (alpha, phi, theta) under angular_speed_rad_s, the platform's R under linear_speed_m_s.
    """

    angular_speed_rad_s: float
    linear_speed_m_s: float

    def validate(self) -> None:
        """ValueError unless every bound is finite and positive."""
        for name, value in dataclasses.asdict(self).items():
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"rest bound {name} must be finite and > 0, got {value!r}")


@dataclasses.dataclass(frozen=True)
class VehicleState:
    """The vehicle as the latest joint_states gives it: joint names (alpha, [R,] phi, theta), q and qdot (SI)."""

    joint_names: tuple[str, ...]
    q: Array
    qdot: Array

    @property
    def constrained(self) -> bool:
        """Whether the vehicle is the constrained one (its joints have no R)."""
        return "R" not in self.joint_names

    @property
    def alpha_rad(self) -> float:
        """The hub angle alpha, rad."""
        return float(self.q[self.joint_names.index("alpha")])

    @property
    def lane_radius_m(self) -> Optional[float]:
        """The platform's R, m; None for the constrained vehicle (its joint_states carry no R)."""
        return None if self.constrained else float(self.q[self.joint_names.index("R")])

    def speeds_over(self, bounds: RestBounds) -> list[str]:
        """The joints moving faster than bounds, each as 'name speed > bound unit'; empty at rest."""
        over = []
        for name, speed in zip(self.joint_names, self.qdot):
            bound, unit = (bounds.linear_speed_m_s, "m/s") if name == "R" else (bounds.angular_speed_rad_s, "rad/s")
            if abs(speed) >= bound:
                over.append(f"{name} {speed:+.3g} {unit} (bound {bound:g})")
        return over


@dataclasses.dataclass(frozen=True)
class ManeuverGoal:
    """An operator's maneuver request.

    An operator's request: a sequence (primitive_ids with repeat_counts) or a goal state at least goal_alpha_rad
    from the start; the time scale (0: the planner's default) and the tracker's tolerances.
    """

    mode: int
    primitive_ids: tuple[str, ...] = ()
    repeat_counts: tuple[int, ...] = ()
    goal_state: str = ""
    goal_alpha_rad: float = 0.0
    time_scale: float = 0.0
    tolerances: Tolerances = Tolerances()

    def validate(self) -> None:
        """Check the goal's fields.

        ManeuverGoalError unless the goal names a sequence or a goal state, with its fields consistent. The time
        scale and the ids are the planner's to judge (it names what it refuses).
        """
        if self.mode == MODE_SEQUENCE:
            if not self.primitive_ids:
                raise ManeuverGoalError("the goal gives neither a sequence (mode 0 with primitive_ids) nor a goal "
                                        "state (mode 1 with goal_state)")
            if self.repeat_counts and len(self.repeat_counts) != len(self.primitive_ids):
                raise ManeuverGoalError(f"{len(self.repeat_counts)} repeat_counts for {len(self.primitive_ids)} "
                                        f"primitive_ids (give one each, or none for 1 each)")
        elif self.mode == MODE_GOAL:
            if not self.goal_state:
                raise ManeuverGoalError("the goal gives neither a sequence (mode 0 with primitive_ids) nor a goal "
                                        "state (mode 1 with goal_state)")
            if not math.isfinite(self.goal_alpha_rad):
                raise ManeuverGoalError(f"goal_alpha_rad must be finite, got {self.goal_alpha_rad!r}")
        else:
            raise ManeuverGoalError(f"unknown mode {self.mode}: 0 for a sequence, 1 for a goal state")
        try:
            self.tolerances.validate()
        except ValueError as err:
            raise ManeuverGoalError(str(err)) from err

    @property
    def repeats(self) -> tuple[int, ...]:
        """The repeat counts, 1 each where the goal gave none."""
        return self.repeat_counts or (1,) * len(self.primitive_ids)


def rest_state_of(vehicle: VehicleState, states: Sequence[str], lane_tolerance_m: float) -> str:
    """The graph's rest state the vehicle is in.

    The constrained vehicle's, or the free vehicle's on the lane nearest its R; ManeuverGoalError when the graph has
    none or R is farther than lane_tolerance_m from every lane.
    """
    if vehicle.constrained:
        if CONSTRAINED_REST_STATE not in states:
            raise ManeuverGoalError("the vehicle is the constrained one (joint_states without R) and the planner's "
                                    "graph has no constrained states")
        return CONSTRAINED_REST_STATE
    lanes = {state: float(match["lane_radius_m"]) for state in states if (match := FREE_REST_STATE.match(state))}
    if not lanes:
        raise ManeuverGoalError("the vehicle is the free one (joint_states with R) and the planner's graph has no "
                                "free rest states")
    radius_m = vehicle.lane_radius_m
    assert radius_m is not None   # the free vehicle's
    nearest = min(lanes, key=lambda state: abs(lanes[state] - radius_m))
    if abs(lanes[nearest] - radius_m) > lane_tolerance_m:
        raise ManeuverGoalError(f"the vehicle is on no lane: R = {radius_m:.4f} m, the nearest lane is "
                                f"{lanes[nearest]:g} m ({nearest}), farther than {lane_tolerance_m:g} m")
    return nearest


def start_state(goal: ManeuverGoal, vehicle: VehicleState, states: Sequence[str],
                start_states: dict[str, str], bounds: RestBounds, lane_tolerance_m: float) -> str:
    """The graph state a from-rest maneuver starts in, after the checks.

    The checks: the goal is valid, the vehicle at rest (every joint speed under bounds: NotAtRest otherwise), and a
    sequence's first primitive (start_states: id -> its start state) starts in the vehicle's rest state.
    ManeuverGoalError with the reason otherwise; ids the planner does not know are left for it to refuse.
    """
    goal.validate()
    rest = rest_state_of(vehicle, states, lane_tolerance_m)
    moving = vehicle.speeds_over(bounds)
    if moving:
        raise NotAtRest(f"the vehicle is not at rest ({', '.join(moving)}): a maneuver starts from rest")
    if goal.mode == MODE_SEQUENCE:
        first = goal.primitive_ids[0]
        first_start = start_states.get(first)
        if first_start is not None and first_start != rest:
            raise ManeuverGoalError(f"'{first}' starts in '{first_start}', and the vehicle is in '{rest}'")
    return rest
