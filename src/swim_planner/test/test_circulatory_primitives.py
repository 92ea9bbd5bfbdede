"""Primitives solved with the circulatory flow (swim_planner.primitive_solver with VehicleModel(...,
flow="circulatory")): the constrained E = 0.05 cruise of the library's spec, its accelerate from rest and its
decelerate to rest, the cruise-to-cruise up to E = 0.10, and the free outward lane change at E = 0.05, each solved
from its cruises' boundary states (lag states included) as a library build joins them.

Checked independently of the solver: collocation defects recomputed from the model's numeric functions at the
stored samples, periodicity, the energy level, the angle-of-attack bound at the stored samples and between them,
an open-loop replay of the torques through the circulatory model, the boundary states. The paper's bands
(Figs. 3-4) and the Strouhal band are tested as stated; the ones this model and rig miss are strict xfails with
the measured value and its reason (docs/circulatory_primitives.md).
"""
import dataclasses
import math

import numpy as np
import pytest
from scipy.interpolate import CubicHermiteSpline

from swim_model import VehicleModel, load_rig
from swim_model.flow import angle_of_attack
from swim_planner.build import solve_from_guess_or_blend
from swim_planner.catalog import (
    CIRCULATORY_CONSTRAINED_DECELERATE_FOIL_RATE_RAD_S,
    CIRCULATORY_CONSTRAINED_DECELERATE_REST_WINDOW_S,
    CIRCULATORY_CONSTRAINED_MIN_STROUHAL,
    CIRCULATORY_ENERGY_LEVELS_J,
    CIRCULATORY_FREE_ACCELERATE_S,
    CIRCULATORY_FREE_DECELERATE_CONTINUATION_RAD,
    CIRCULATORY_FREE_DECELERATE_INTERVALS_PER_S,
    CIRCULATORY_FREE_DECELERATE_S,
    CIRCULATORY_FREE_MIN_STROUHAL,
    CIRCULATORY_LONGER_S,
    INTERVALS_PER_S,
    circulatory_specs,
    cruise_id,
    default_specs,
)
from swim_planner.primitive_solver import rest_window_s, solve_primitive
from swim_planner.primitives import (
    PlanningLimits,
    Primitive,
    PrimitiveType,
    cruise_mean_speed_m_s,
    cruise_strouhal_number,
    rest_boundary_state,
)
from swim_planner.testing.consistency import REPLAY_TOLERANCE, replay_open_loop

LIMITS = PlanningLimits.of(load_rig())
PAPER_CRUISE_SPEED_M_S = (0.12, 0.18)      # paper Fig. 3, the E = 0.05 cruise
PAPER_HEAVE_RAD = (-0.45, 0.75)            # paper Fig. 4 (with margin, as the issue states it)
PAPER_PITCH_RAD = 0.6                      # paper Fig. 4: |theta| within about 0.6 rad
STROUHAL_BAND = (0.1, 0.8)                 # efficient swimmers and foils: 0.2-0.4; the band asked for
ANGLE_OF_ATTACK_P95_LIMIT_RAD = math.radians(30.0)   # the 95th percentile of |angle of attack| over the samples
JOIN_TOLERANCE = 1e-6                      # a transition's boundary state against its cruise's
BOUND_TOLERANCE_RAD = 1e-5                 # the bound holds in velocity form to IPOPT's tolerance (1e-8): at a
                                           # foil speed of a few mm/s that is 1e-6 to 1e-5 rad of angle

#: what the module fixture solves, in dependency order (the free cruises only to join the lane change)
SOLVED = ("constrained/cruise/E0.05", "constrained/accelerate/E0.05", "constrained/decelerate/E0.05",
          "constrained/cruise/E0.10", "constrained/cruise_to_cruise/E0.05-E0.10", "free/cruise/R0.43/E0.05",
          "free/cruise/R0.48/E0.05", "free/lane_change/R0.43-R0.48/E0.05")
TRANSITIONS = [i for i in SOLVED if "/cruise/" not in i]


def _spec(rig, primitive_id):
    return next(s for s in circulatory_specs(rig) if s.primitive_id == primitive_id)


@pytest.fixture(scope="module")
def solved(rig):
    """{id: (model, primitive)} for SOLVED, each transition from its cruises' boundary states (q, qdot, lag) and
    with the cruise it joins as its guess, as a library build solves them."""
    out: dict[str, tuple[VehicleModel, Primitive]] = {}
    models: dict[tuple, VehicleModel] = {}
    for primitive_id in SOLVED:
        spec = _spec(rig, primitive_id)
        key = (spec.constrained, spec.lane_radius_m)
        if key not in models:
            models[key] = VehicleModel(rig, constrained=spec.constrained, lane_radius_m=spec.lane_radius_m,
                                       flow="circulatory")
        start = out[spec.start_from][1].end_boundary_state if spec.start_from else None
        end = out[spec.end_at][1].start_boundary_state if spec.end_at else None
        joined = spec.start_from or spec.end_at
        guess = out[joined][1] if joined else None
        out[primitive_id] = models[key], solve_from_guess_or_blend(models[key], spec, LIMITS, start, end, guess)
    return out


@pytest.fixture(scope="module")
def circulatory(solved):
    model, cruise = solved["constrained/cruise/E0.05"]
    return model, cruise, solved["constrained/accelerate/E0.05"][1]


def _one_cycle(primitive: Primitive) -> slice:
    return slice(0, 2 * primitive.spec.intervals + 1)


def _state_derivative(model: VehicleModel, primitive: Primitive, k: int) -> np.ndarray:
    q, qdot, z = primitive.q[k], primitive.qdot[k], primitive.lag[k]
    qddot, _ = model.shape_dynamics(q, qdot, primitive.foil_acceleration[k], z)
    return np.concatenate([qdot, qddot, model.lag_rate(q, qdot, z)])


def _collocation_defects(model: VehicleModel, primitive: Primitive) -> float:
    """Largest Hermite-Simpson defect (swim_planner.collocation) over the first solved horizon's intervals."""
    x = np.column_stack([primitive.q, primitive.qdot, primitive.lag])
    step = primitive.time_s[2] - primitive.time_s[0]
    worst = 0.0
    for k in range(primitive.spec.intervals):
        f0, fm, f1 = (_state_derivative(model, primitive, 2 * k + i) for i in range(3))
        x0, xm, x1 = x[2 * k], x[2 * k + 1], x[2 * k + 2]
        simpson = x1 - x0 - step / 6.0 * (f0 + 4.0 * fm + f1)
        hermite = xm - 0.5 * (x0 + x1) - step / 8.0 * (f0 - f1)
        worst = max(worst, float(np.abs(simpson).max()), float(np.abs(hermite).max()))
    return worst


def _angles_of_attack(model: VehicleModel, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
    velocity = np.array([model.foil_velocity_map(a) @ b for a, b in zip(q, qdot)])
    return angle_of_attack(velocity[:, 0], velocity[:, 1])


def test_cruise_satisfies_its_collocation_and_is_periodic_in_shape_rates_and_lag(circulatory):
    model, cruise, _ = circulatory
    assert cruise.lag is not None and cruise.lag.shape == (len(cruise.time_s), model.n_lag)
    assert _collocation_defects(model, cruise) < 1e-7
    cycle = _one_cycle(cruise)
    end = cycle.stop - 1
    np.testing.assert_allclose(cruise.q[end, 1:], cruise.q[0, 1:], atol=1e-8)
    np.testing.assert_allclose(cruise.qdot[end], cruise.qdot[0], atol=1e-8)
    np.testing.assert_allclose(cruise.lag[end], cruise.lag[0], atol=1e-8)
    # the energy level: the cycle's mean kinetic energy by Simpson's rule on the solved grid
    energy = np.array([model.kinetic_energy(a, b) for a, b in zip(cruise.q[cycle], cruise.qdot[cycle])])
    step = cruise.time_s[2] - cruise.time_s[0]
    mean_energy = step / 6.0 * (energy[0:-1:2] + 4.0 * energy[1::2] + energy[2::2]).sum() / cruise.time_s[end]
    assert abs(mean_energy - cruise.spec.energy_j) < 1e-7
    assert cruise.qdot[0, 0] >= LIMITS.min_alpha_rate_rad_s - 1e-9


def test_cruise_p_alpha_is_free_and_changes_by_the_flows_hub_torque(circulatory):
    """p_alpha is not held at 0; over the cycle it changes by the integral of Q_flow[0] (and returns)."""
    model, cruise, _ = circulatory
    cycle = _one_cycle(cruise)
    momentum = np.array([model.momentum(a, b)[0] for a, b in zip(cruise.q[cycle], cruise.qdot[cycle])])
    hub_torque = np.array([model.flow_force(a, b, z)[1][0] for a, b, z in
                           zip(cruise.q[cycle], cruise.qdot[cycle], cruise.lag[cycle])])
    step = cruise.time_s[2] - cruise.time_s[0]
    change = step / 6.0 * np.cumsum(hub_torque[0:-1:2] + 4.0 * hub_torque[1::2] + hub_torque[2::2])
    np.testing.assert_allclose(momentum[2::2] - momentum[0], change, atol=1e-6 * np.abs(momentum).max())
    assert abs(momentum[0]) > 100 * 1e-6 * np.abs(momentum).max()


def test_cruise_angle_of_attack_bound_holds_at_the_samples_and_between_them(circulatory):
    model, cruise, _ = circulatory
    assert np.abs(_angles_of_attack(model, cruise.q, cruise.qdot)).max() <= (LIMITS.angle_of_attack_limit_rad
                                                                              + BOUND_TOLERANCE_RAD)
    # between the samples: the cubic Hermite interpolant of the collocated trajectory at the quarter points
    cycle = _one_cycle(cruise)
    qddot = np.array([_state_derivative(model, cruise, k)[model.nq:2 * model.nq] for k in range(cycle.stop)])
    times = cruise.time_s[cycle]
    quarter = 0.5 * (times[1:] + times[:-1])
    q = CubicHermiteSpline(times, cruise.q[cycle], cruise.qdot[cycle])(quarter)
    qdot = CubicHermiteSpline(times, cruise.qdot[cycle], qddot)(quarter)
    assert np.abs(_angles_of_attack(model, q, qdot)).max() <= LIMITS.angle_of_attack_limit_rad + 1e-3


def test_open_loop_replay_of_the_cruise_and_the_accelerate_stays_close(circulatory):
    model, cruise, accelerate = circulatory
    cycle = _one_cycle(cruise)
    for primitive, part in ((cruise, cycle), (accelerate, slice(None))):
        result = replay_open_loop(model, primitive.time_s[part], primitive.q[part], primitive.qdot[part],
                                  primitive.foil_acceleration[part], lag=primitive.lag[part])
        assert result.max_position_error < REPLAY_TOLERANCE, primitive.spec.primitive_id


def test_replay_refuses_a_circulatory_model_without_lag_states(circulatory):
    model, cruise, _ = circulatory
    with pytest.raises(ValueError, match="lag states"):
        replay_open_loop(model, cruise.time_s, cruise.q, cruise.qdot, cruise.foil_acceleration)


def test_accelerate_starts_at_rest_in_still_water_and_ends_on_the_cruise(circulatory):
    model, cruise, accelerate = circulatory
    q_rest, qdot_rest, lag_rest = rest_boundary_state(model, accelerate.spec.lane_radius_m)
    assert model.circulatory_flow is not None
    np.testing.assert_array_equal(lag_rest, model.circulatory_flow.steady_lag(np.zeros(3)))
    np.testing.assert_allclose(accelerate.q[0], q_rest, atol=1e-10)
    np.testing.assert_allclose(accelerate.qdot[0], qdot_rest, atol=1e-10)
    np.testing.assert_allclose(accelerate.lag[0], lag_rest, atol=1e-10)
    q_end, qdot_end, lag_end = cruise.start_boundary_state
    np.testing.assert_allclose(accelerate.q[-1, 1:], q_end[1:], atol=1e-8)
    np.testing.assert_allclose(accelerate.qdot[-1], qdot_end, atol=1e-8)
    np.testing.assert_allclose(accelerate.lag[-1], lag_end, atol=1e-8)
    assert accelerate.q[-1, 0] > 0.0
    assert _collocation_defects(model, accelerate) < 1e-7


def test_a_circulatory_boundary_state_without_lag_states_is_refused(rig, circulatory):
    model, cruise, _ = circulatory
    spec = dataclasses.replace(_spec(rig, "constrained/accelerate/E0.05"), intervals=8)
    with pytest.raises(ValueError, match=r"\(q, qdot, lag\)"):
        solve_primitive(model, spec, end=cruise.start_state)


@pytest.mark.xfail(strict=True, reason="measured pitch -0.30 to +0.87 rad: a stroke at St 0.35 heaves the pitch axis "
                   "across the flow, and within the 20 deg angle-of-attack bound the foil's pitch follows the path "
                   "that stroke gives it")
def test_cruise_pitch_is_within_the_papers_range(circulatory):
    _, cruise, _ = circulatory
    assert np.abs(cruise.q[:, 2]).max() <= PAPER_PITCH_RAD


def test_cruise_mean_speed_is_the_papers(circulatory):
    _, cruise, _ = circulatory
    low, high = PAPER_CRUISE_SPEED_M_S
    assert low <= cruise_mean_speed_m_s(cruise) <= high


def test_cruise_heave_is_within_the_papers_range(circulatory):
    _, cruise, _ = circulatory
    low, high = PAPER_HEAVE_RAD
    assert low <= cruise.q[:, 1].min() and cruise.q[:, 1].max() <= high


@pytest.mark.parametrize("primitive_id", [i for i in SOLVED if "/cruise/" in i])
def test_cruise_strouhal_number_is_a_swimmers(rig, solved, primitive_id):
    _, cruise = solved[primitive_id]
    low, high = STROUHAL_BAND
    assert low <= cruise_strouhal_number(cruise, rig.heave_link_length_m) <= high


def _assert_strokes_at_its_floor(rig, cruise: Primitive) -> None:
    """The pitch axis's excursion across the lane (Lh sin(phi), less R for the free vehicle), recomputed from the
    samples, falls from the cycle's start to its middle by at least St_min R dalpha; the Strouhal number (peak to
    peak) is the floor's."""
    floor = cruise.spec.min_strouhal
    heave = cruise.q[:, -2]
    lateral_m = rig.heave_link_length_m * np.sin(heave) - (0.0 if cruise.spec.constrained else cruise.q[:, 1])
    middle = cruise.spec.intervals
    alpha_advance_rad = cruise.q[2 * cruise.spec.intervals, 0] - cruise.q[0, 0]
    # the bound is active: it holds to IPOPT's tolerance (1e-8 on the constraint, m)
    assert lateral_m[0] - lateral_m[middle] >= floor * cruise.spec.lane_radius_m * alpha_advance_rad - 1e-7
    assert floor - 1e-6 <= cruise_strouhal_number(cruise, rig.heave_link_length_m) <= floor + 1e-3


def test_constrained_cruise_strokes_at_its_strouhal_floor(rig, circulatory):
    """The stroke bound (PrimitiveSpec.min_strouhal): the pitch axis's excursion across the lane from the cycle's
    start to its middle, recomputed from the stored samples, is at least St_min R dalpha, so the cruise's Strouhal
    number (peak to peak) is at least the floor; and the floor is what sets the stroke (the same cruise without one
    strokes at St 0.014)."""
    _, cruise, _ = circulatory
    assert cruise.spec.min_strouhal == CIRCULATORY_CONSTRAINED_MIN_STROUHAL
    _assert_strokes_at_its_floor(rig, cruise)


@pytest.mark.parametrize("primitive_id", ["free/cruise/R0.43/E0.05", "free/cruise/R0.48/E0.05"])
def test_free_cruise_strokes_at_its_strouhal_floor(rig, solved, primitive_id):
    """The bound's free-vehicle form: the pitch axis's excursion across the lane is Lh sin(phi) - R (the carriage
    moves too). A free cruise meets its floor, recomputed from its samples, and strokes at it; solved without the
    floor it strokes at under half of it (measured 0.020-0.022)."""
    model, cruise = solved[primitive_id]
    assert cruise.spec.min_strouhal == CIRCULATORY_FREE_MIN_STROUHAL
    _assert_strokes_at_its_floor(rig, cruise)
    unfloored = solve_primitive(model, dataclasses.replace(cruise.spec, min_strouhal=None), LIMITS)
    assert cruise_strouhal_number(unfloored, rig.heave_link_length_m) < 0.5 * CIRCULATORY_FREE_MIN_STROUHAL


def test_a_strouhal_floor_is_a_circulatory_cruises_only(rig, circulatory):
    _, cruise, _ = circulatory
    for bad in (0.0, -0.1, math.nan, math.inf):
        with pytest.raises(ValueError, match="min_strouhal"):
            dataclasses.replace(cruise.spec, min_strouhal=bad)
    accelerate = _spec(rig, "constrained/accelerate/E0.05")
    with pytest.raises(ValueError, match="min_strouhal is a cruise's"):
        dataclasses.replace(accelerate, min_strouhal=0.3)
    ideal = VehicleModel(rig, constrained=True)
    with pytest.raises(ValueError, match="min_strouhal is for a cruise with the circulatory flow"):
        solve_primitive(ideal, cruise.spec, LIMITS)


def test_strouhal_number_and_mean_speed_follow_their_definitions(rig, circulatory):
    """Against hand-built samples: a stroke of heave phi = 0.2 sin(2 pi t) over 1 s at alpha rate 0.5 rad/s."""
    _, cruise, _ = circulatory
    times = np.linspace(0.0, 1.0, 161)
    q = np.column_stack([0.5 * times, 0.2 * np.sin(2 * np.pi * times), np.zeros_like(times)])
    spec = dataclasses.replace(cruise.spec, cycles=1, duration_s=1.0)
    made = dataclasses.replace(cruise, spec=spec, time_s=times, q=q)
    speed = 0.5 * spec.lane_radius_m
    assert cruise_mean_speed_m_s(made) == pytest.approx(speed, rel=1e-12)
    amplitude = rig.heave_link_length_m * np.sin(0.2)
    assert cruise_strouhal_number(made, rig.heave_link_length_m) == pytest.approx(2 * amplitude / speed, rel=1e-12)


def test_the_circulatory_set_is_the_papers_graph_with_a_third_level_joined_to_its_neighbour(rig):  # noqa: C901 - one check per property of the graph
    specs = {s.primitive_id: s for s in circulatory_specs(rig)}
    assert len(specs) == len(circulatory_specs(rig))
    for spec in default_specs(rig):                      # the paper's graph, spec for spec
        if not spec.constrained and spec.primitive_type is PrimitiveType.ACCELERATE:
            spec = dataclasses.replace(spec, duration_s=CIRCULATORY_FREE_ACCELERATE_S,
                                       intervals=int(round(CIRCULATORY_FREE_ACCELERATE_S * INTERVALS_PER_S)))
        if not spec.constrained and spec.primitive_type is PrimitiveType.DECELERATE:
            spec = dataclasses.replace(spec, duration_s=CIRCULATORY_FREE_DECELERATE_S, end_lag_free=True,
                                       angle_of_attack_continuation_rad=CIRCULATORY_FREE_DECELERATE_CONTINUATION_RAD)
        if spec.primitive_id in CIRCULATORY_LONGER_S:
            longer_s = CIRCULATORY_LONGER_S[spec.primitive_id]
            spec = dataclasses.replace(spec, duration_s=longer_s, intervals=int(round(longer_s * INTERVALS_PER_S)))
        if not spec.constrained and spec.primitive_type is PrimitiveType.DECELERATE:
            # its finer grid at any duration, refined from the coarse one
            spec = dataclasses.replace(spec, intervals=int(round(spec.duration_s
                                                                 * CIRCULATORY_FREE_DECELERATE_INTERVALS_PER_S)),
                                       coarse_intervals=int(round(spec.duration_s * INTERVALS_PER_S)))
        if spec.primitive_type is PrimitiveType.CRUISE:
            spec = dataclasses.replace(spec, min_strouhal=CIRCULATORY_CONSTRAINED_MIN_STROUHAL if spec.constrained
                                       else CIRCULATORY_FREE_MIN_STROUHAL)
        if spec.constrained and spec.primitive_type is PrimitiveType.DECELERATE:
            spec = dataclasses.replace(
                spec, rest_window_s=CIRCULATORY_CONSTRAINED_DECELERATE_REST_WINDOW_S,
                rest_window_foil_rate_limit_rad_s=CIRCULATORY_CONSTRAINED_DECELERATE_FOIL_RATE_RAD_S)
        assert specs[spec.primitive_id] == spec
    assert CIRCULATORY_ENERGY_LEVELS_J[:2] == (0.05, 0.1) and CIRCULATORY_ENERGY_LEVELS_J[2] > 0.1
    def primitive_id(kind, lane, tags):
        return f"constrained/{kind}/{tags}" if lane is None else f"free/{kind}/R{lane:.2f}/{tags}"

    for lane in (None, rig.lane_1_radius_m, rig.lane_2_radius_m):
        cruise = cruise_id(lane is None, 0.2, lane)
        assert specs[cruise].energy_j == 0.2
        assert specs[primitive_id("accelerate", lane, "E0.20")].end_at == cruise
        assert specs[primitive_id("decelerate", lane, "E0.20")].start_from == cruise
        up = specs[primitive_id("cruise_to_cruise", lane, "E0.10-E0.20")]
        down = specs[primitive_id("cruise_to_cruise", lane, "E0.20-E0.10")]
        assert (up.end_at, up.speeding_up, down.start_from, down.speeding_up) == (cruise, True, cruise, False)
        assert primitive_id("cruise_to_cruise", lane, "E0.05-E0.20") not in specs   # neighbours only
    for energy in CIRCULATORY_ENERGY_LEVELS_J:
        for a, b in ((rig.lane_1_radius_m, rig.lane_2_radius_m), (rig.lane_2_radius_m, rig.lane_1_radius_m)):
            spec = specs[f"free/lane_change/R{a:.2f}-R{b:.2f}/E{energy:.2f}"]
            assert (spec.start_from, spec.end_at) == (cruise_id(False, energy, a), cruise_id(False, energy, b))
    for spec in specs.values():                          # every join names a spec of the set
        assert all(d in specs for d in (spec.start_from, spec.end_at) if d is not None)


@pytest.mark.parametrize("primitive_id", TRANSITIONS)
def test_transitions_join_their_cruises_boundary_states_lag_included(solved, primitive_id):
    model, primitive = solved[primitive_id]
    spec = primitive.spec
    assert _collocation_defects(model, primitive) < 1e-7
    starts = ({spec.start_from: solved[spec.start_from][1].end_boundary_state} if spec.start_from else
              {"rest": rest_boundary_state(model, spec.lane_radius_m)})
    ends = ({spec.end_at: solved[spec.end_at][1].start_boundary_state} if spec.end_at else
            {"rest": rest_boundary_state(model, spec.end_lane_radius_m)})
    for (_, wanted), got in ((next(iter(starts.items())), primitive.start_boundary_state),
                             (next(iter(ends.items())), primitive.end_boundary_state)):
        assert len(got) == 3
        np.testing.assert_allclose(got[0][1:], wanted[0][1:], atol=JOIN_TOLERANCE)   # alpha: up to a translation
        np.testing.assert_allclose(got[1], wanted[1], atol=JOIN_TOLERANCE)
        np.testing.assert_allclose(got[2], wanted[2], atol=JOIN_TOLERANCE)
    assert primitive.q[0, 0] == pytest.approx(0.0, abs=1e-12)
    assert primitive.q[-1, 0] > 0.0
    if spec.primitive_type is PrimitiveType.DECELERATE:
        assert primitive.qdot[:, 0].min() >= LIMITS.min_alpha_rate_rad_s - 1e-6
    if spec.primitive_type is PrimitiveType.LANE_CHANGE:
        low = min(spec.lane_radius_m, spec.end_lane_radius_m) - LIMITS.lane_band_m
        high = max(spec.lane_radius_m, spec.end_lane_radius_m) + LIMITS.lane_band_m
        assert low - 1e-6 <= primitive.q[:, 1].min() and primitive.q[:, 1].max() <= high + 1e-6


@pytest.mark.parametrize("primitive_id", SOLVED)
def test_angle_of_attack_95th_percentile_over_the_samples_is_at_most_30_degrees(solved, primitive_id):
    model, primitive = solved[primitive_id]
    angles = np.abs([model.angle_of_attack(a, b) for a, b in zip(primitive.q, primitive.qdot)])
    # the bound itself at every sample outside the window next to rest (the spec's, else PlanningLimits'), and the
    # percentile over those samples for a spec that widens that window (a constrained decelerate), else over all
    times = primitive.time_s
    from_rest_s = {PrimitiveType.ACCELERATE: times,
                   PrimitiveType.DECELERATE: times[-1] - times}.get(primitive.spec.primitive_type, times + np.inf)
    bounded = from_rest_s >= rest_window_s(primitive.spec, LIMITS) - 1e-9
    counted = bounded if primitive.spec.rest_window_s is not None else np.ones(len(times), dtype=bool)
    assert np.percentile(angles[counted], 95) <= ANGLE_OF_ATTACK_P95_LIMIT_RAD
    assert np.abs(angles[bounded]).max() <= LIMITS.angle_of_attack_limit_rad + BOUND_TOLERANCE_RAD


@pytest.mark.parametrize("primitive_id", TRANSITIONS)
def test_open_loop_replay_of_the_transitions_stays_close(solved, primitive_id):
    model, primitive = solved[primitive_id]
    result = replay_open_loop(model, primitive.time_s, primitive.q, primitive.qdot, primitive.foil_acceleration,
                              lag=primitive.lag)
    assert result.max_position_error < REPLAY_TOLERANCE
