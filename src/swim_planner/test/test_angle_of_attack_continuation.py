"""The solver's angle-of-attack continuation (primitive_solver.solve_primitive with
PrimitiveSpec.angle_of_attack_continuation_rad) and a decelerate that ends at rest with its lag states free
(PrimitiveSpec.end_lag_free): the steps it solves, the bad settings it refuses, the same solution as a direct solve
where the direct solve succeeds, and a free end lag that is the only thing freed at rest; and the coarser grid solved
first (PrimitiveSpec.coarse_intervals), which ends where the direct solve on the fine grid does; and a decelerate's
own window next to rest with the foil's rates bounded in it (PrimitiveSpec.rest_window_s,
rest_window_foil_rate_limit_rad_s).

The transitions are solved between the shipped circulatory library's cruises (their boundary states, lag included),
as a library build joins them.
"""
import dataclasses
import math

import numpy as np
import pytest

from swim_model import VehicleModel, load_rig
from swim_planner.catalog import circulatory_specs, default_specs
from swim_planner.library import PrimitiveLibrary
from swim_planner.primitive_solver import angle_of_attack_bounded, continuation_bounds, primitive_nlp, solve_primitive
from swim_planner.primitives import PlanningLimits, PrimitiveType, rest_boundary_state

LIMITS = PlanningLimits.of(load_rig())
#: the direct solve and the continuation end at the same optimum to IPOPT's tolerance (1e-8) scaled by the
#: problem (measured: J 4e-9, q 3e-7, qdot 9e-6, lag 3e-8, u 4e-4): J, the states (rad, m, rad/s, m/s) and the
#: foil accelerations (up to 300 rad/s^2) to 1e-5 of their range
SAME_INDEX_J = 1e-7
SAME_STATE = 1e-4
SAME_INPUT_RAD_S2 = 3e-3
#: a transition of the constrained graph whose direct solve succeeds with the bound active (its largest |AoA| is
#: the bound): the continuation has something to tighten
BOUND_ACTIVE = "constrained/cruise_to_cruise/E0.10-E0.20"


def _spec(rig, primitive_id, specs=circulatory_specs):
    return next(s for s in specs(rig) if s.primitive_id == primitive_id)


def _model(rig, spec, flow="circulatory"):
    return VehicleModel(rig, constrained=spec.constrained, lane_radius_m=spec.lane_radius_m, flow=flow)


def test_without_a_continuation_one_solve_with_the_limit(rig):
    spec = _spec(rig, BOUND_ACTIVE)
    assert continuation_bounds(_model(rig, spec), spec, LIMITS) == [LIMITS.angle_of_attack_limit_rad]
    ideal = _spec(rig, "constrained/decelerate/E0.05", default_specs)
    assert continuation_bounds(_model(rig, ideal, "ideal"), ideal, LIMITS) == [LIMITS.angle_of_attack_limit_rad]


def test_a_continuation_starts_unbounded_and_ends_at_the_limit(rig):
    looser = (math.radians(40.0), math.radians(25.0))
    spec = dataclasses.replace(_spec(rig, BOUND_ACTIVE), angle_of_attack_continuation_rad=looser)
    assert continuation_bounds(_model(rig, spec), spec, LIMITS) == [None, *looser, LIMITS.angle_of_attack_limit_rad]


@pytest.mark.parametrize("looser_deg", [(25.0, 40.0), (40.0, 40.0), (90.0,), (20.0,), (15.0,), (math.nan,)],
                         ids=["ascending", "repeated", "right_angle", "at_the_limit", "below_the_limit", "nan"])
def test_a_continuation_that_does_not_descend_to_the_limit_is_refused(rig, looser_deg):
    spec = dataclasses.replace(_spec(rig, BOUND_ACTIVE),
                               angle_of_attack_continuation_rad=tuple(math.radians(a) for a in looser_deg))
    with pytest.raises(ValueError, match="angle_of_attack_continuation_rad"):
        continuation_bounds(_model(rig, spec), spec, LIMITS)


def test_a_continuation_with_the_ideal_flow_is_refused(rig):
    spec = dataclasses.replace(_spec(rig, "constrained/decelerate/E0.05", default_specs),
                               angle_of_attack_continuation_rad=(math.radians(30.0),))
    with pytest.raises(ValueError, match="circulatory flow"):
        continuation_bounds(_model(rig, spec, "ideal"), spec, LIMITS)


def test_a_spec_read_back_from_json_equals_the_one_written(rig):
    """A library's manifest stores the continuation as a JSON list."""
    spec = _spec(rig, "free/decelerate/R0.43/E0.05")
    assert spec.angle_of_attack_continuation_rad
    data = dataclasses.asdict(spec)
    data["angle_of_attack_continuation_rad"] = list(data["angle_of_attack_continuation_rad"])
    assert dataclasses.replace(spec, **data) == spec


@pytest.mark.parametrize("primitive_id, flow", [("constrained/cruise_to_cruise/E0.10-E0.05", "circulatory"),
                                                 ("free/decelerate/R0.43/E0.05", "ideal")],
                         ids=["not_a_decelerate", "ideal_flow"])
def test_a_free_end_lag_outside_a_circulatory_decelerate_is_refused(rig, circulatory_library, primitive_id, flow):
    spec = dataclasses.replace(_spec(rig, primitive_id, default_specs), end_lag_free=True)
    model = _model(rig, spec, flow)
    lag = (np.zeros(model.n_lag),) if flow == "circulatory" else ()
    start = tuple(circulatory_library.get(spec.start_from).end_boundary_state[:2]) + lag
    end = None if spec.end_at is None else tuple(circulatory_library.get(spec.end_at).start_boundary_state[:2]) + lag
    with pytest.raises(ValueError, match="end_lag_free"):
        primitive_nlp(model, spec, LIMITS, start, end)


def _solved(rig, library, spec):
    start = library.get(spec.start_from).end_boundary_state if spec.start_from else None
    end = library.get(spec.end_at).start_boundary_state if spec.end_at else None
    guess = library.get(spec.start_from or spec.end_at)
    return solve_primitive(_model(rig, spec), spec, LIMITS, start, end, guess, library.solver)


def test_the_continuation_ends_at_the_direct_solution_where_the_direct_solve_succeeds(rig, circulatory_library):
    spec = _spec(rig, BOUND_ACTIVE)
    direct = _solved(rig, circulatory_library, spec)
    model = _model(rig, spec)
    angles = np.abs([model.angle_of_attack(a, b) for a, b in zip(direct.q, direct.qdot)])
    assert angles.max() == pytest.approx(LIMITS.angle_of_attack_limit_rad, abs=1e-5)   # the bound is active
    continued = _solved(rig, circulatory_library,
                        dataclasses.replace(spec, angle_of_attack_continuation_rad=(math.radians(30.0),)))
    assert continued.iterations > direct.iterations           # the sum over its three steps
    assert continued.index_j == pytest.approx(direct.index_j, abs=SAME_INDEX_J)
    for ours, theirs in ((continued.q, direct.q), (continued.qdot, direct.qdot), (continued.lag, direct.lag)):
        np.testing.assert_allclose(ours, theirs, atol=SAME_STATE)
    np.testing.assert_allclose(continued.foil_acceleration, direct.foil_acceleration, atol=SAME_INPUT_RAD_S2)


def test_a_free_end_lag_frees_only_the_lag_and_rest_is_exact_in_motion(rig, circulatory_library):
    """The constrained E = 0.05 decelerate solved with its end lag free: it ends at rest, (q, qdot) of
    rest_boundary_state to IPOPT's tolerance, and at that rest its lag states are frozen and carry no force (the
    model's flow force and lag rate at zero motion, whatever the lag)."""
    spec = dataclasses.replace(_spec(rig, "constrained/decelerate/E0.05"), end_lag_free=True)
    assert spec.primitive_type is PrimitiveType.DECELERATE
    model = _model(rig, spec)
    primitive = _solved(rig, circulatory_library, spec)
    rest_q, rest_qdot, _ = rest_boundary_state(model, spec.end_lane_radius_m)
    q_end, qdot_end, lag_end = primitive.end_boundary_state
    np.testing.assert_allclose(q_end[1:], rest_q[1:], atol=1e-8)
    np.testing.assert_allclose(qdot_end, rest_qdot, atol=1e-8)
    assert np.all(np.isfinite(lag_end))
    force, generalized = model.flow_force(q_end, np.zeros(model.nq), lag_end)
    np.testing.assert_allclose(force, 0.0, atol=1e-9)
    np.testing.assert_allclose(generalized, 0.0, atol=1e-9)
    # frozen: the lag rate (|u| / b) b_i (Q - z_i) at zero motion, where the model's |u| is its speed regularization
    flow = model.circulatory_flow
    rest_speed_rates = flow.params.speed_regularization_m_s / flow.semichord_m * np.array(
        [flow.params.wagner_slow_rate, flow.params.wagner_fast_rate])
    np.testing.assert_allclose(model.lag_rate(q_end, np.zeros(model.nq), lag_end), -rest_speed_rates * lag_end,
                               rtol=1e-6, atol=1e-15)


@pytest.mark.parametrize("looser_deg", [(), (30.0,)], ids=["alone", "with_a_continuation"])
def test_a_coarser_grid_first_ends_at_the_direct_solution_on_the_fine_grid(rig, circulatory_library, looser_deg):
    """Mesh refinement (PrimitiveSpec.coarse_intervals): the NLP (and its continuation) on half the intervals, then
    the spec's grid once from that solution interpolated, ends where the direct solve on the spec's grid does."""
    spec = _spec(rig, BOUND_ACTIVE)
    direct = _solved(rig, circulatory_library, spec)
    refined_spec = dataclasses.replace(spec, coarse_intervals=spec.intervals // 2,
                                       angle_of_attack_continuation_rad=tuple(math.radians(a) for a in looser_deg))
    refined = _solved(rig, circulatory_library, refined_spec)
    assert refined.spec == refined_spec
    assert refined.iterations > direct.iterations       # the sum over both grids (measured: 64 and 121 against 38)
    assert len(refined.time_s) == 2 * spec.intervals + 1
    np.testing.assert_allclose(refined.time_s, direct.time_s, atol=1e-12)
    assert refined.index_j == pytest.approx(direct.index_j, abs=SAME_INDEX_J)
    for ours, theirs in ((refined.q, direct.q), (refined.qdot, direct.qdot), (refined.lag, direct.lag)):
        np.testing.assert_allclose(ours, theirs, atol=SAME_STATE)
    np.testing.assert_allclose(refined.foil_acceleration, direct.foil_acceleration, atol=SAME_INPUT_RAD_S2)


@pytest.mark.parametrize("coarse", [0, -4, 40, 41], ids=["zero", "negative", "equal", "finer"])
def test_a_coarser_grid_that_is_not_coarser_is_refused(rig, coarse):
    spec = _spec(rig, BOUND_ACTIVE)
    assert spec.intervals == 40
    with pytest.raises(ValueError, match="coarse_intervals"):
        dataclasses.replace(spec, coarse_intervals=coarse)


def test_a_coarser_grid_for_a_repeated_cruise_cycle_is_refused(rig):
    spec = _spec(rig, "constrained/cruise/E0.05")
    assert spec.cycles > 1
    with pytest.raises(ValueError, match="cruise's repeated cycle"):
        dataclasses.replace(spec, coarse_intervals=spec.intervals // 2)


#: a window next to rest and a rate bound in it (PrimitiveSpec.rest_window_s, rest_window_foil_rate_limit_rad_s):
#: the setting docs/experiments.md measured on the constrained decelerates
REST_WINDOW_S = 0.5
REST_WINDOW_RATE_RAD_S = 4.0


def test_a_rest_window_bounds_the_foil_rates_there_and_the_angle_of_attack_before(rig, circulatory_library,
                                                                                    tmp_path):
    """The constrained E = 0.10 decelerate solved with a 0.5 s window next to rest and the foil's rates bounded in
    it: the angle-of-attack bound holds at every sample 0.5 s or more from rest, the heave and pitch rates stay
    within 4 rad/s inside (where the same decelerate solved without them turns the foil back to rest at more than
    twice that), it ends at rest, and a library stores the spec and reads it back."""
    spec = dataclasses.replace(_spec(rig, "constrained/decelerate/E0.10"), rest_window_s=REST_WINDOW_S,
                               rest_window_foil_rate_limit_rad_s=REST_WINDOW_RATE_RAD_S)
    primitive = _solved(rig, circulatory_library, spec)
    plain = _solved(rig, circulatory_library, dataclasses.replace(spec, rest_window_s=None,
                                                                   rest_window_foil_rate_limit_rad_s=None))
    model = _model(rig, spec)
    assert primitive.spec == spec
    inside = primitive.time_s[-1] - primitive.time_s < REST_WINDOW_S - 1e-9
    assert inside.sum() == round(REST_WINDOW_S / (spec.duration_s / (2 * spec.intervals)))
    np.testing.assert_array_equal(angle_of_attack_bounded(spec, LIMITS), ~inside)
    angles = np.abs([model.angle_of_attack(a, b) for a, b in zip(primitive.q, primitive.qdot)])
    assert angles[~inside].max() <= LIMITS.angle_of_attack_limit_rad + 1e-5
    rates = np.abs(primitive.qdot[inside][:, model.nq - 2:])
    assert rates.max() <= REST_WINDOW_RATE_RAD_S + 1e-6
    assert np.abs(plain.qdot[inside][:, model.nq - 2:]).max() > 2.0 * REST_WINDOW_RATE_RAD_S
    rest_q, rest_qdot, _ = rest_boundary_state(model, spec.end_lane_radius_m)
    np.testing.assert_allclose(primitive.q[-1, 1:], rest_q[1:], atol=1e-8)
    np.testing.assert_allclose(primitive.qdot[-1], rest_qdot, atol=1e-8)
    library = PrimitiveLibrary.create_or_open(tmp_path / "library", rig, flow_model="circulatory")
    library.add(primitive)
    assert PrimitiveLibrary.load(tmp_path / "library", rig, "circulatory").spec(spec.primitive_id) == spec


@pytest.mark.parametrize("field, value", [("rest_window_s", 0.0), ("rest_window_s", -0.5),
                                          ("rest_window_s", math.nan), ("rest_window_foil_rate_limit_rad_s", math.inf),
                                          ("rest_window_foil_rate_limit_rad_s", True),
                                          ("rest_window_foil_rate_limit_rad_s", "4")])
def test_a_bad_rest_window_setting_is_refused(rig, field, value):
    with pytest.raises(ValueError, match=field):
        dataclasses.replace(_spec(rig, "constrained/decelerate/E0.05"), **{field: value})


@pytest.mark.parametrize("field", ["rest_window_s", "rest_window_foil_rate_limit_rad_s"])
def test_a_rest_window_setting_on_a_cruise_is_refused(rig, field):
    with pytest.raises(ValueError, match="an accelerate's or a decelerate's"):
        dataclasses.replace(_spec(rig, "constrained/cruise/E0.05"), **{field: 0.5})


@pytest.mark.parametrize("field", ["rest_window_s", "rest_window_foil_rate_limit_rad_s"])
def test_a_rest_window_setting_with_the_ideal_flow_is_refused(rig, circulatory_library, field):
    spec = dataclasses.replace(_spec(rig, "constrained/decelerate/E0.05", default_specs), **{field: 0.5})
    model = _model(rig, spec, "ideal")
    start = tuple(circulatory_library.get(spec.start_from).end_boundary_state[:2])
    with pytest.raises(ValueError, match="circulatory flow"):
        primitive_nlp(model, spec, LIMITS, start, None)
