"""The checks of a maneuver goal and where it starts (swim_bringup.maneuver), against the shipped libraries' graphs."""
import math
import re

import numpy as np
import pytest

from swim_bringup.maneuver import (
    MODE_GOAL,
    MODE_SEQUENCE,
    ManeuverGoal,
    ManeuverGoalError,
    NotAtRest,
    RestBounds,
    VehicleState,
    rest_state_of,
    start_state,
)
from swim_controller.supervisor import Tolerances

BOUNDS = RestBounds(angular_speed_rad_s=0.1, linear_speed_m_s=0.02)
LANE_TOLERANCE_M = 0.025
FREE = ("alpha", "R", "phi", "theta")
CONSTRAINED = ("alpha", "phi", "theta")


@pytest.fixture(scope="module")
def graph():
    """The ideal library's states and each primitive's start state, as planner_node's list_primitives gives them."""
    from swim_model import load_rig
    from swim_planner.graph import build_graph, summarize
    from swim_planner.library import PrimitiveLibrary
    from swim_planner.paths import default_library_path
    library = PrimitiveLibrary.load(default_library_path("ideal"), load_rig(None), "ideal")
    built = build_graph(library)
    return sorted(built.nodes), {s.primitive_id: s.start_state for s in summarize(library, built)}


def vehicle(names, q, qdot=None) -> VehicleState:
    q = np.asarray(q, dtype=float)
    return VehicleState(names, q, np.zeros_like(q) if qdot is None else np.asarray(qdot, dtype=float))


@pytest.mark.parametrize("goal, reason", [
    (ManeuverGoal(MODE_SEQUENCE), "neither a sequence"),
    (ManeuverGoal(MODE_GOAL), "neither a sequence"),
    (ManeuverGoal(7, ("a",)), "unknown mode 7"),
    (ManeuverGoal(MODE_SEQUENCE, ("a", "b"), (1,)), "1 repeat_counts for 2 primitive_ids"),
    (ManeuverGoal(MODE_GOAL, goal_state="constrained/rest", goal_alpha_rad=math.nan), "goal_alpha_rad must be finite"),
    (ManeuverGoal(MODE_SEQUENCE, ("a",), tolerances=Tolerances(goal_alpha_rad=-1.0)), "goal_alpha_rad must be"),
    (ManeuverGoal(MODE_SEQUENCE, ("a",), tolerances=Tolerances(path_r_m=math.inf)), "path_r_m must be"),
])
def test_a_goal_that_names_no_maneuver_is_refused_with_its_reason(goal, reason):
    with pytest.raises(ManeuverGoalError, match=reason):
        goal.validate()


def test_repeats_default_to_one_each():
    assert ManeuverGoal(MODE_SEQUENCE, ("a", "b")).repeats == (1, 1)
    assert ManeuverGoal(MODE_SEQUENCE, ("a", "b"), (3, 2)).repeats == (3, 2)


@pytest.mark.parametrize("radius_m, state", [(0.43, "free/rest/R0.43"), (0.446, "free/rest/R0.43"),
                                             (0.4549, "free/rest/R0.43"), (0.4551, "free/rest/R0.48"),
                                             (0.50, "free/rest/R0.48")])
def test_the_free_vehicle_is_on_the_lane_nearest_its_r(graph, radius_m, state):
    states, _ = graph
    assert rest_state_of(vehicle(FREE, [9.6, radius_m, 0.0, 0.0]), states, LANE_TOLERANCE_M) == state


@pytest.mark.parametrize("radius_m", [0.40, 0.51, 0.70])
def test_an_r_on_no_lane_is_refused(graph, radius_m):
    states, _ = graph
    with pytest.raises(ManeuverGoalError, match="on no lane"):
        rest_state_of(vehicle(FREE, [0.0, radius_m, 0.0, 0.0]), states, LANE_TOLERANCE_M)


def test_the_constrained_vehicle_rests_in_its_one_state(graph):
    states, _ = graph
    assert rest_state_of(vehicle(CONSTRAINED, [3.0, 0.0, 0.0]), states, LANE_TOLERANCE_M) == "constrained/rest"
    with pytest.raises(ManeuverGoalError, match="no constrained states"):
        rest_state_of(vehicle(CONSTRAINED, [3.0, 0.0, 0.0]), [s for s in states if s.startswith("free")], 0.025)


@pytest.mark.parametrize("joint, speed", [(0, 0.1), (0, -0.2), (1, 0.02), (2, -0.1), (3, 1.5)])
def test_a_vehicle_moving_at_a_bound_or_faster_is_not_at_rest(graph, joint, speed):
    states, starts = graph
    qdot = np.zeros(4)
    qdot[joint] = speed
    goal = ManeuverGoal(MODE_GOAL, goal_state="free/rest/R0.48", goal_alpha_rad=6.3)
    with pytest.raises(NotAtRest, match=re.escape(f"{FREE[joint]} {speed:+.3g}")):
        start_state(goal, vehicle(FREE, [0.0, 0.43, 0.0, 0.0], qdot), states, starts, BOUNDS, LANE_TOLERANCE_M)


def test_speeds_under_the_bounds_are_rest(graph):
    states, starts = graph
    qdot = [0.099, -0.0199, 0.0999, -0.099]
    goal = ManeuverGoal(MODE_GOAL, goal_state="free/rest/R0.48", goal_alpha_rad=6.3)
    assert start_state(goal, vehicle(FREE, [9.6, 0.446, 0.0, 0.0], qdot), states, starts, BOUNDS,
                       LANE_TOLERANCE_M) == "free/rest/R0.43"


def test_a_sequence_starts_in_the_vehicles_state(graph):
    states, starts = graph
    on_first_lane = vehicle(FREE, [0.0, 0.43, 0.0, 0.0])
    paper = ManeuverGoal(MODE_SEQUENCE, ("free/accelerate/R0.43/E0.05", "free/cruise/R0.43/E0.05"))
    assert start_state(paper, on_first_lane, states, starts, BOUNDS, LANE_TOLERANCE_M) == "free/rest/R0.43"
    for ids, reason in ((("free/accelerate/R0.48/E0.05",), "starts in 'free/rest/R0.48'"),
                        (("free/cruise/R0.43/E0.05",), "starts in 'free/cruise/R0.43/E0.05'"),
                        (("constrained/accelerate/E0.05",), "starts in 'constrained/rest'")):
        with pytest.raises(ManeuverGoalError, match=reason):
            start_state(ManeuverGoal(MODE_SEQUENCE, ids), on_first_lane, states, starts, BOUNDS, LANE_TOLERANCE_M)
    # an id the library does not have is the planner's to refuse, with its own reason
    assert start_state(ManeuverGoal(MODE_SEQUENCE, ("no/such",)), on_first_lane, states, starts, BOUNDS,
                       LANE_TOLERANCE_M) == "free/rest/R0.43"


@pytest.mark.parametrize("bounds", [RestBounds(0.0, 0.02), RestBounds(0.1, math.nan), RestBounds(-1.0, 0.02)])
def test_rest_bounds_must_be_positive(bounds):
    with pytest.raises(ValueError, match="rest bound"):
        bounds.validate()
