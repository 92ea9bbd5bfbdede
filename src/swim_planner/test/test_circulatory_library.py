"""The shipped circulatory library (`swim-primitives build --flow circulatory`): complete, converged, within its
limits and the angle-of-attack bound at every stored sample, joined lag states included, consistent with the
circulatory model; the paper's maneuvers planned with it travel as far as the paper's rig did; and the tracker,
in closed loop on the circulatory model, ends on the plan (one process, no DDS, no disturbance, ideal sensors).
"""
import math

import numpy as np
import pytest

from swim_controller.testing.closed_loop import simulate
from swim_controller.tracker import CascadeTracker, model_io_linearization, model_lag_rate
from swim_model import load_rig
from swim_planner.catalog import (
    CIRCULATORY_CONSTRAINED_DECELERATE_FOIL_RATE_RAD_S,
    CIRCULATORY_CONSTRAINED_DECELERATE_REST_WINDOW_S,
    CIRCULATORY_FREE_DECELERATE_S,
    CIRCULATORY_LONGER_S,
    PAPER_CONSTRAINED,
    PAPER_LANE_KEEPING,
    circulatory_specs,
    cruise_id,
)
from swim_planner.errors import ManeuverError
from swim_planner.graph import build_graph, plan_to_goal, rest_node
from swim_planner.maneuver import JUNCTION_TOLERANCE, concatenate, expand_sequence
from swim_planner.primitives import (
    CONVERGED_STATUSES,
    PlanningLimits,
    PrimitiveType,
    cruise_mean_speed_m_s,
    cruise_strouhal_number,
    rest_boundary_state,
)
from swim_planner.testing.consistency import REPLAY_TOLERANCE, replay_open_loop

LIMITS = PlanningLimits.of(load_rig())
ALL_SPECS = circulatory_specs(load_rig())
SPECS = ALL_SPECS
IDS = [s.primitive_id for s in SPECS]
FREE_DECELERATES = [s.primitive_id for s in ALL_SPECS if not s.constrained
                    and s.primitive_type is PrimitiveType.DECELERATE]
CONSTRAINED_DECELERATES = [s.primitive_id for s in ALL_SPECS if s.constrained
                           and s.primitive_type is PrimitiveType.DECELERATE]
ANGLE_OF_ATTACK_P95_LIMIT_RAD = math.radians(30.0)   # the 95th percentile of |angle of attack| over the samples
STROUHAL_BAND = (0.1, 0.8)                           # efficient swimmers and foils: 0.2-0.4; the band asked for
#: a lane change between two lane keepings at E = 0.05 (paper Sec. 7.3: outward)
LANE_CHANGE = (["free/accelerate/R0.43/E0.05", "free/cruise/R0.43/E0.05", "free/lane_change/R0.43-R0.48/E0.05",
                "free/cruise/R0.48/E0.05", "free/decelerate/R0.48/E0.05"], [1, 2, 1, 2, 1])
#: the paper's constrained maneuver covered about 3 m at the lane radius in 30 s (Fig. 19), its free lane keeping
#: about 5 rad of hub angle in 20 s (Fig. 25); the bounds asked of the circulatory library
PAPER_CONSTRAINED_TRAVEL_M = 2.5
PAPER_LANE_KEEPING_HUB_ANGLE_RAD = 4.0
#: how close the closed loop ends to its plan without disturbance or sensor noise: 1 mrad of alpha, 1 mm of R
FINAL_ALPHA_ERROR_RAD = 1e-3
FINAL_R_ERROR_M = 1e-3
FINAL_LANE_ERROR_M = 5e-3   # a free maneuver ends at rest this close to its last lane (the plan ends on it)
BOUND_TOLERANCE_RAD = 1e-5   # the bound holds in velocity form to IPOPT's tolerance: at a foil speed of a few mm/s
                             # that is 1e-6 to 1e-5 rad of angle


def test_every_circulatory_spec_is_in_the_library(circulatory_library):
    assert circulatory_library.ids() == sorted(s.primitive_id for s in ALL_SPECS)


def test_every_solved_circulatory_primitive_is_there_converged_with_gains_and_lag(circulatory_library):
    assert circulatory_library.ids() == sorted(IDS)
    assert circulatory_library.flow_model == "circulatory"
    for primitive_id in IDS:
        entry = circulatory_library.entry(primitive_id)
        assert entry["solver_status"] in CONVERGED_STATUSES and entry["has_gains"], primitive_id
        primitive = circulatory_library.get(primitive_id)
        assert primitive.lag.shape == (len(primitive.time_s), 2)
        assert primitive.spec == next(s for s in SPECS if s.primitive_id == primitive_id)


@pytest.mark.parametrize("primitive_id", IDS)
def test_limits_torques_and_angle_of_attack(circulatory_library, model_for, primitive_id):
    primitive = circulatory_library.get(primitive_id)
    model = model_for(primitive.spec, "circulatory")
    assert np.all(np.abs(primitive.torque) <= LIMITS.torque_fraction * model.torque_limits() * (1 + 1e-6))
    assert np.all(np.abs(primitive.q[:, -2]) <= LIMITS.heave_range_rad + 1e-6)
    assert np.all(np.abs(primitive.q[:, -1]) <= LIMITS.pitch_range_rad + 1e-6)
    # the torques are what the circulatory model needs for the motion (eq. 15 with the flow), at every 7th sample
    for k in range(0, len(primitive.time_s), 7):
        _, tau = model.shape_dynamics(primitive.q[k], primitive.qdot[k], primitive.foil_acceleration[k],
                                      primitive.lag[k])
        np.testing.assert_allclose(primitive.torque[k], tau, atol=1e-9)
    angles = np.abs([model.angle_of_attack(a, b) for a, b in zip(primitive.q, primitive.qdot)])
    assert np.percentile(angles[_outside_own_rest_window(primitive)], 95) <= ANGLE_OF_ATTACK_P95_LIMIT_RAD


def _outside_own_rest_window(primitive) -> np.ndarray:
    """The samples outside a window next to rest that the spec widens (PrimitiveSpec.rest_window_s); all samples
    of a primitive that keeps PlanningLimits' window."""
    if primitive.spec.rest_window_s is None:
        return np.ones(len(primitive.time_s), dtype=bool)
    return primitive.time_s[-1] - primitive.time_s >= primitive.spec.rest_window_s - 1e-9


@pytest.mark.xfail(strict=True, reason="the constrained decelerates turn back to rest over 0.5 s, broadside: "
                                       "8.7-11.8 % of their samples past 30 deg (docs/experiments.md)")
@pytest.mark.parametrize("primitive_id", CONSTRAINED_DECELERATES)
def test_angle_of_attack_95th_percentile_over_all_samples_of_a_widened_rest_window(circulatory_library, model_for,
                                                                                    primitive_id):
    primitive = circulatory_library.get(primitive_id)
    model = model_for(primitive.spec, "circulatory")
    angles = np.abs([model.angle_of_attack(a, b) for a, b in zip(primitive.q, primitive.qdot)])
    assert np.percentile(angles, 95) <= ANGLE_OF_ATTACK_P95_LIMIT_RAD


@pytest.mark.parametrize("primitive_id", CONSTRAINED_DECELERATES)
def test_constrained_decelerates_turn_back_to_rest_slowly_and_keep_the_bound_before(circulatory_library, model_for,
                                                                                     primitive_id):
    """A constrained decelerate keeps the angle-of-attack bound at every sample outside its own window next to rest
    (CIRCULATORY_CONSTRAINED_DECELERATE_REST_WINDOW_S), turns the foil back to rest inside it with the heave and
    pitch rates within CIRCULATORY_CONSTRAINED_DECELERATE_FOIL_RATE_RAD_S, and ends at rest."""
    primitive = circulatory_library.get(primitive_id)
    spec = primitive.spec
    assert spec.rest_window_s == CIRCULATORY_CONSTRAINED_DECELERATE_REST_WINDOW_S
    assert spec.rest_window_foil_rate_limit_rad_s == CIRCULATORY_CONSTRAINED_DECELERATE_FOIL_RATE_RAD_S
    model = model_for(spec, "circulatory")
    angles = np.abs([model.angle_of_attack(a, b) for a, b in zip(primitive.q, primitive.qdot)])
    inside = primitive.time_s[-1] - primitive.time_s < CIRCULATORY_CONSTRAINED_DECELERATE_REST_WINDOW_S - 1e-9
    assert angles[~inside].max() <= LIMITS.angle_of_attack_limit_rad + BOUND_TOLERANCE_RAD
    assert np.abs(primitive.qdot[inside][:, 1:]).max() <= CIRCULATORY_CONSTRAINED_DECELERATE_FOIL_RATE_RAD_S + 1e-6
    np.testing.assert_allclose(primitive.qdot[-1], 0.0, atol=JUNCTION_TOLERANCE)
    np.testing.assert_allclose(primitive.q[-1, 1:], 0.0, atol=JUNCTION_TOLERANCE)


@pytest.mark.parametrize("primitive_id", [i for i in IDS if i.startswith("constrained/")])
def test_open_loop_replay_of_the_constrained_primitives(circulatory_library, model_for, primitive_id):
    primitive = circulatory_library.get(primitive_id)
    cycle = primitive.time_s <= primitive.spec.solved_duration_s + 1e-9
    result = replay_open_loop(model_for(primitive.spec, "circulatory"), primitive.time_s[cycle], primitive.q[cycle],
                              primitive.qdot[cycle], primitive.foil_acceleration[cycle], lag=primitive.lag[cycle])
    assert result.max_position_error <= REPLAY_TOLERANCE


def test_the_graph_joins_every_primitive_and_has_the_third_energy_level(circulatory_library):
    """Every junction matches (q, qdot and lag states; at a rest node q and qdot, where a free decelerate leaves the
    lag states its braking left and an accelerate starts in still water): nothing is dropped; the graph keeps every
    primitive, the third level's cruise with its accelerate, decelerate and cruise-to-cruise edges."""
    graph = build_graph(circulatory_library)
    assert graph.mismatches == []
    assert sorted(e.primitive_id for e in graph.edges) == sorted(IDS)
    top = max(s.energy_j for s in SPECS if s.energy_j is not None)
    tops = [s for s in SPECS if s.primitive_type is PrimitiveType.CRUISE and s.energy_j == top]
    assert len(tops) == 3
    for cruise in tops:
        joined = {e.primitive_id.split("/")[1] for e in graph.edges if cruise.primitive_id in (e.source, e.target)}
        assert {"accelerate", "decelerate", "cruise_to_cruise", "cruise"} <= joined, cruise.primitive_id


@pytest.mark.parametrize("primitive_id", FREE_DECELERATES)
def test_free_decelerates_stop_within_the_bound_and_rest_with_a_frozen_forceless_wake(circulatory_library, model_for,
                                                                                     primitive_id):
    """A free decelerate lasts CIRCULATORY_FREE_DECELERATE_S (or its CIRCULATORY_LONGER_S), keeps the
    angle-of-attack bound at every sample outside the window next to rest, and ends at rest: (q, qdot) of
    rest_boundary_state, and lag states that at zero motion put no force on the vehicle."""
    primitive = circulatory_library.get(primitive_id)
    spec = primitive.spec
    assert spec.duration_s == CIRCULATORY_LONGER_S.get(primitive_id, CIRCULATORY_FREE_DECELERATE_S)
    assert spec.end_lag_free
    model = model_for(spec, "circulatory")
    angles = np.abs([model.angle_of_attack(a, b) for a, b in zip(primitive.q, primitive.qdot)])
    bounded = primitive.time_s[-1] - primitive.time_s >= LIMITS.angle_of_attack_free_from_rest_s - 1e-9
    assert angles[bounded].max() <= LIMITS.angle_of_attack_limit_rad + BOUND_TOLERANCE_RAD
    rest_q, rest_qdot, _ = rest_boundary_state(model, spec.end_lane_radius_m)
    q_end, qdot_end, lag_end = primitive.end_boundary_state
    np.testing.assert_allclose(q_end[1:], rest_q[1:], atol=JUNCTION_TOLERANCE)
    np.testing.assert_allclose(qdot_end, rest_qdot, atol=JUNCTION_TOLERANCE)
    _, generalized = model.flow_force(q_end, rest_qdot, lag_end)
    np.testing.assert_allclose(generalized, 0.0, atol=1e-9)


def test_a_stop_and_restart_in_a_free_lane_is_refused_not_spliced(circulatory_library, rig):
    """The decelerate rests with its wake's lag states, the accelerate starts in still water: concatenating the two
    names the gap instead of making a plan whose lag states jump."""
    stop, restart = "free/decelerate/R0.43/E0.05", "free/accelerate/R0.43/E0.05"
    gap = np.abs(circulatory_library.get(stop).lag[-1] - circulatory_library.get(restart).lag[0]).max()
    assert gap > JUNCTION_TOLERANCE
    with pytest.raises(ManeuverError, match="does not end where"):
        _plan(circulatory_library, rig, ([stop, restart], [1, 1]))


def test_the_free_graph_plans_the_lane_keeping_and_the_lane_change(circulatory_library, rig):
    graph = build_graph(circulatory_library)
    inner, outer = rest_node(False, rig.lane_1_radius_m), rest_node(False, rig.lane_2_radius_m)
    keeping = plan_to_goal(graph, inner, inner, PAPER_LANE_KEEPING_HUB_ANGLE_RAD)
    assert [i.split("/")[1] for i, _ in (keeping[0], keeping[-1])] == ["accelerate", "decelerate"]
    change = plan_to_goal(graph, inner, outer)
    assert [i.split("/")[1] for i, _ in change] == ["accelerate", "lane_change", "decelerate"]
    for sequence in (keeping, change):
        plan = concatenate(circulatory_library, rig, sequence, 1.0)
        np.testing.assert_allclose(plan.qdot[-1], 0.0, atol=JUNCTION_TOLERANCE)


def test_cruises_record_their_mean_speed_and_faster_levels_are_faster(circulatory_library):
    levels = sorted({s.energy_j for s in SPECS if s.energy_j is not None})
    for constrained, lane in ((True, None), (False, 0.43), (False, 0.48)):
        speeds = []
        for energy_j in levels:
            primitive_id = cruise_id(constrained, energy_j, lane)
            entry = circulatory_library.entry(primitive_id)
            assert entry["mean_speed_m_s"] == cruise_mean_speed_m_s(circulatory_library.get(primitive_id))
            speeds.append(entry["mean_speed_m_s"])
        assert speeds == sorted(speeds) and speeds[0] > 0.0, (constrained, lane, speeds)


def _plan(library, rig, ids_and_counts):
    ids, counts = ids_and_counts
    return concatenate(library, rig, expand_sequence(ids, counts), 1.0)


def test_the_papers_constrained_maneuver_travels_as_far_as_the_papers_rig(circulatory_library, rig):
    constrained = _plan(circulatory_library, rig, PAPER_CONSTRAINED)
    assert (constrained.q[-1, 0] - constrained.q[0, 0]) * rig.constrained_lane_radius_m >= PAPER_CONSTRAINED_TRAVEL_M
    assert constrained.flow_model == "circulatory"


def test_the_papers_lane_keeping_travels_as_far_as_the_papers_rig(circulatory_library, rig):
    lane_keeping = _plan(circulatory_library, rig, PAPER_LANE_KEEPING)
    assert lane_keeping.q[-1, 0] - lane_keeping.q[0, 0] >= PAPER_LANE_KEEPING_HUB_ANGLE_RAD


def test_lane_keeping_without_its_decelerate_travels_as_far_as_the_papers_rig(circulatory_library, rig):
    """The paper's lane keeping up to its decelerate (accelerate and 14 cruises, 18 of its 20 s)."""
    lane_keeping = _plan(circulatory_library, rig, (PAPER_LANE_KEEPING[0][:2], PAPER_LANE_KEEPING[1][:2]))
    assert lane_keeping.q[-1, 0] - lane_keeping.q[0, 0] >= PAPER_LANE_KEEPING_HUB_ANGLE_RAD


_CLOSED_LOOP_RUNS: dict = {}


def _closed_loop(library, model_for, rig, maneuver):
    """The plan of ``maneuver`` and the tracker's run on the circulatory model (one per maneuver in this module)."""
    key = (tuple(maneuver[0]), tuple(maneuver[1]))
    if key not in _CLOSED_LOOP_RUNS:
        reference = _plan(library, rig, maneuver)
        model = model_for(library.spec(maneuver[0][0]), "circulatory")
        tracker = CascadeTracker(model_io_linearization(model), model.torque_limits(), sliding_mode_enabled=False,
                                 lag_rate=model_lag_rate(model))
        _CLOSED_LOOP_RUNS[key] = reference, simulate(model, tracker, reference)
    return _CLOSED_LOOP_RUNS[key]


@pytest.mark.parametrize("maneuver", [PAPER_CONSTRAINED, PAPER_LANE_KEEPING,
                                      (PAPER_LANE_KEEPING[0][:2], PAPER_LANE_KEEPING[1][:2]), LANE_CHANGE],
                         ids=["constrained", "lane_keeping", "lane_keeping_to_its_last_cruise", "lane_change"])
def test_closed_loop_on_the_circulatory_model_ends_on_the_plan(circulatory_library, model_for, rig, maneuver):
    reference, run = _closed_loop(circulatory_library, model_for, rig, maneuver)
    assert abs(run.error[-1, 0]) <= FINAL_ALPHA_ERROR_RAD
    if not reference.constrained:
        assert abs(run.error[-1, 1]) <= FINAL_R_ERROR_M


@pytest.mark.parametrize("maneuver", [PAPER_LANE_KEEPING, LANE_CHANGE], ids=["lane_keeping", "lane_change"])
def test_free_maneuvers_in_closed_loop_stop_on_their_lane(circulatory_library, model_for, rig, maneuver):
    """A free maneuver ends at rest within FINAL_LANE_ERROR_M of its last lane, across (R) and along it (the hub
    angle's error at the lane radius), with no torque saturated."""
    reference, run = _closed_loop(circulatory_library, model_for, rig, maneuver)
    lane_m = circulatory_library.spec(maneuver[0][-1]).end_lane_radius_m
    assert abs(run.q[-1, 1] - lane_m) <= FINAL_LANE_ERROR_M
    assert abs(run.error[-1, 0]) * lane_m <= FINAL_LANE_ERROR_M
    assert not run.saturated.any()


@pytest.mark.parametrize("primitive_id", [s.primitive_id for s in SPECS if s.primitive_type is PrimitiveType.CRUISE])
def test_every_cruise_strouhal_number_is_a_swimmers(circulatory_library, rig, primitive_id):
    strouhal = cruise_strouhal_number(circulatory_library.get(primitive_id), rig.heave_link_length_m)
    assert STROUHAL_BAND[0] <= strouhal <= STROUHAL_BAND[1]
