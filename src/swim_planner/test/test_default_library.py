"""The shipped library: complete, converged, within limits, joined, consistent with the model, and the
paper's qualitative findings."""
import math

import numpy as np
import pytest

from swim_model import VehicleModel, load_rig
from swim_planner.catalog import default_specs
from swim_planner.primitives import CONVERGED_STATUSES, PlanningLimits, PrimitiveType, rest_state
from swim_planner.testing.consistency import REPLAY_TOLERANCE, replay_open_loop

LIMITS = PlanningLimits.of(load_rig())
IDS = [s.primitive_id for s in default_specs(load_rig())]


def model_for(spec, rig):
    return VehicleModel(rig, constrained=spec.constrained, lane_radius_m=spec.lane_radius_m)


def test_every_default_primitive_is_there_and_converged(library):
    assert sorted(IDS) == library.ids()
    for primitive_id in IDS:
        assert library.entry(primitive_id)["solver_status"] in CONVERGED_STATUSES, primitive_id


@pytest.mark.parametrize("primitive_id", IDS)
def test_limits_and_boundary_conditions(library, rig, primitive_id):
    primitive = library.get(primitive_id)
    spec = primitive.spec
    model = model_for(spec, rig)
    torque_cap = LIMITS.torque_fraction * model.torque_limits() * (1 + 1e-6)
    assert np.all(np.abs(primitive.torque) <= torque_cap)
    assert np.all(np.abs(primitive.q[:, -2]) <= LIMITS.heave_range_rad + 1e-6)
    assert np.all(np.abs(primitive.q[:, -1]) <= LIMITS.pitch_range_rad + 1e-6)
    assert primitive.q[0, 0] == pytest.approx(0.0, abs=1e-9)
    # the torques are what the model needs for the motion (eq. 15), at every sample
    for k in range(0, len(primitive.time_s), 7):
        _, tau = model.shape_dynamics(primitive.q[k], primitive.qdot[k], primitive.foil_acceleration[k])
        np.testing.assert_allclose(primitive.torque[k], tau, atol=1e-9)
    q0, qdot0 = primitive.start_state
    q1, qdot1 = primitive.end_state
    if spec.primitive_type is PrimitiveType.CRUISE:
        np.testing.assert_allclose(q1[1:], q0[1:], atol=1e-6)
        np.testing.assert_allclose(qdot1, qdot0, atol=1e-6)
        assert model.momentum(q0, qdot0)[0] == pytest.approx(0.0, abs=1e-7)
    if spec.primitive_type is PrimitiveType.ACCELERATE:
        rest_q, rest_qdot = rest_state(model, spec.lane_radius_m)
        np.testing.assert_allclose(q0, rest_q, atol=1e-9)
        np.testing.assert_allclose(qdot0, rest_qdot, atol=1e-9)
    if spec.primitive_type is PrimitiveType.DECELERATE:
        np.testing.assert_allclose(qdot1, 0.0, atol=1e-6)
        np.testing.assert_allclose(q1[1:], rest_state(model, spec.lane_radius_m)[0][1:], atol=1e-6)
        assert primitive.qdot[:, 0].min() >= LIMITS.min_alpha_rate_rad_s - 1e-6
    if spec.start_from:
        np.testing.assert_allclose(q0[1:], library.get(spec.start_from).end_state[0][1:], atol=1e-6)
        np.testing.assert_allclose(qdot0, library.get(spec.start_from).end_state[1], atol=1e-6)
    if spec.end_at:
        np.testing.assert_allclose(q1[1:], library.get(spec.end_at).start_state[0][1:], atol=1e-6)
        np.testing.assert_allclose(qdot1, library.get(spec.end_at).start_state[1], atol=1e-6)
    if not spec.constrained:
        low = min(spec.lane_radius_m, spec.end_lane_radius_m) - LIMITS.lane_band_m
        high = max(spec.lane_radius_m, spec.end_lane_radius_m) + LIMITS.lane_band_m
        assert low - 1e-6 <= primitive.q[:, 1].min() and primitive.q[:, 1].max() <= high + 1e-6


@pytest.mark.parametrize("primitive_id", IDS)
def test_open_loop_replay_reproduces_the_states(library, rig, primitive_id):
    primitive = library.get(primitive_id)
    # a cruise is one solved cycle tiled: replay that cycle (the copies are it, translated in alpha; u may
    # jump where they join, which the replay's smooth torque signal cannot represent)
    cycle = primitive.time_s <= primitive.spec.solved_duration_s + 1e-9
    result = replay_open_loop(model_for(primitive.spec, rig), primitive.time_s[cycle], primitive.q[cycle],
                              primitive.qdot[cycle], primitive.foil_acceleration[cycle])
    assert result.max_position_error <= REPLAY_TOLERANCE


def first_harmonic_phase(time_s, signal, period_s):
    w = 2 * math.pi / period_s
    return np.angle(np.trapezoid(signal * np.exp(-1j * w * time_s), time_s))


@pytest.mark.parametrize("primitive_id", [i for i in IDS if "/cruise/" in i])
def test_cruise_pitch_leads_heave_by_about_90_degrees(library, primitive_id):
    primitive = library.get(primitive_id)
    period = primitive.spec.solved_duration_s
    one_cycle = primitive.time_s <= period + 1e-9
    t = primitive.time_s[one_cycle]
    lead = first_harmonic_phase(t, primitive.q[one_cycle, -1], period) - \
        first_harmonic_phase(t, primitive.q[one_cycle, -2], period)
    lead_deg = math.degrees((lead + math.pi) % (2 * math.pi) - math.pi)
    assert 60.0 <= lead_deg <= 120.0, lead_deg


def test_higher_energy_cruises_faster(library):
    for low, high in (("constrained/cruise/E0.05", "constrained/cruise/E0.10"),
                      ("free/cruise/R0.43/E0.05", "free/cruise/R0.43/E0.10"),
                      ("free/cruise/R0.48/E0.05", "free/cruise/R0.48/E0.10")):
        slow, fast = library.get(low), library.get(high)
        assert fast.q[-1, 0] / fast.time_s[-1] > slow.q[-1, 0] / slow.time_s[-1]
