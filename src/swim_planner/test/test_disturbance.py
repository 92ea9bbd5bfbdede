"""The sliding mode's disturbance bound from the wake (swim_planner.disturbance): on a towed straight run at a small
steady angle of attack the wake and the reduced model agree (docs/flow_model.md: steady lift within about 3 %), so
D is a small fraction of the force; the generalized force is Q2' f, checked against the model's own Q2' f and
against the foil pose's Jacobian; the matched torque and the unmatched acceleration add up to Mm^-1 dQ; D(t) is
finite, non-negative and sampled at the primitive's times."""
import math

import casadi as ca
import numpy as np
import pytest

from swim_model import VehicleModel
from swim_planner.disturbance import flow_force_mismatch, generalized_force, matched_disturbance
from swim_planner.errors import ManeuverError
from swim_planner.primitives import Primitive, PrimitiveSpec, PrimitiveType

ACCELERATE = "constrained/accelerate/E0.05"
#: the towed run: a lane so wide that the foil's path is straight within 0.4 % of a chord over the run
TOW_LANE_RADIUS_M = 200.0
TOW_SPEED_M_S = 0.2          # the cruises' speed range (0.12-0.18 m/s) and a little above
TOW_PITCH_RAD = math.radians(-3.0)   # a small steady angle of attack (about 3 deg), far from stall
TOW_DURATION_S = 3.0         # 20 semichords: the Wagner lift at 90 % of steady
TOW_SAMPLE_S = 0.025         # the primitives' knot spacing
TOW_COMPARED_FROM_S = 1.5    # 10 semichords on: the starting vortex far behind (the lift differs by 3 % at 0.5 s)
STEADY_LIFT_AGREEMENT = 0.03  # docs/flow_model.md: the two models' steady lift within about 3 %


@pytest.fixture(scope="module")
def towed(rig):
    """A towed straight run (a constrained 'primitive' on a very wide lane at constant alpha rate, the foil
    pitched by TOW_PITCH_RAD), both flow models started impulsively from still water."""
    model = VehicleModel(rig, constrained=True, lane_radius_m=TOW_LANE_RADIUS_M, flow="circulatory")
    time_s = np.arange(0.0, TOW_DURATION_S + 0.5 * TOW_SAMPLE_S, TOW_SAMPLE_S)
    rate = TOW_SPEED_M_S / TOW_LANE_RADIUS_M
    q = np.column_stack([rate * time_s, np.zeros_like(time_s), np.full_like(time_s, TOW_PITCH_RAD)])
    qdot = np.tile([rate, 0.0, 0.0], (len(time_s), 1))
    # the lag states of an impulsive start (still water before): Jones's Wagner response, as the fresh wake's
    flow = model.circulatory_flow
    half = np.arange(2 * len(time_s) - 1) * (0.5 * TOW_SAMPLE_S)
    nu = np.tile(model.foil_velocity_map(q[0]) @ qdot[0], (len(half), 1))
    lag = flow.integrate_lag(nu, TOW_SAMPLE_S, np.zeros(2))
    spec = PrimitiveSpec("towed", PrimitiveType.CRUISE, True, TOW_DURATION_S, TOW_LANE_RADIUS_M,
                         TOW_LANE_RADIUS_M)
    primitive = Primitive(spec=spec, time_s=time_s, q=q, qdot=qdot, foil_acceleration=np.zeros((len(time_s), 2)),
                          torque=np.zeros((len(time_s), 2)), index_j=0.0, effort=0.0, solver_status="prescribed",
                          solve_time_s=0.0, iterations=0, lag=lag)
    return model, primitive, flow_force_mismatch(model, primitive)


@pytest.fixture(scope="module")
def accelerate(circulatory_library, model_for):
    primitive = circulatory_library.get(ACCELERATE)
    model = model_for(primitive.spec, "circulatory")
    return model, primitive, flow_force_mismatch(model, primitive)


def test_towed_run_at_small_angle_of_attack_agrees(towed):
    model, primitive, profile = towed
    angle = math.degrees(abs(model.angle_of_attack(primitive.q[0], primitive.qdot[0])))
    assert 2.0 < angle < 4.0
    window = profile.window(TOW_COMPARED_FROM_S)
    lift_wake, lift_reduced = profile.wake_force[window, 1], profile.reduced_force[window, 1]
    assert np.all(np.abs(lift_reduced) > 0.05)   # a real lift to compare, N
    assert np.max(np.abs(lift_wake - lift_reduced) / np.abs(lift_reduced)) < STEADY_LIFT_AGREEMENT
    # D against the torque the reduced flow's force itself puts on the motors: a small fraction of it
    reduced_q = generalized_force(model, primitive.q, profile.reduced_force)
    reduced_torque = np.array([np.linalg.norm(matched_disturbance(model, qk, gk)[0])
                               for qk, gk in zip(primitive.q, reduced_q)])
    assert np.all(profile.disturbance_bound_n_m[window] < STEADY_LIFT_AGREEMENT * reduced_torque[window])


def test_generalized_force_is_q2_transpose_f(accelerate):
    model, primitive, profile = accelerate
    # the reduced force through our map equals the model's own Q_flow = Q2' f
    mapped = generalized_force(model, primitive.q, profile.reduced_force)
    expected = np.array([model.flow_force(q, v, z)[1] for q, v, z in zip(primitive.q, primitive.qdot, primitive.lag)])
    np.testing.assert_allclose(mapped, expected, rtol=1e-10, atol=1e-12)
    # and the difference equals the virtual work of the tank-frame force at F and the moment about it: J_F' F + J_th' M
    q_sym = model.symbolic.q
    jacobian = ca.Function("pose_jacobian", [q_sym], [ca.jacobian(model.foil_pose_function()(q_sym), q_sym)])
    for k in range(0, len(primitive.time_s), 16):
        q = primitive.q[k]
        pose = model.foil_pose(q)
        jac = np.asarray(jacobian(q), dtype=float)
        fx, fy, mz = profile.force_difference[k]
        c, s = math.cos(pose[2]), math.sin(pose[2])
        tank = np.array([c * fx - s * fy, s * fx + c * fy])
        np.testing.assert_allclose(profile.generalized_force_difference[k], jac[:2].T @ tank + jac[2] * mz,
                                   rtol=1e-9, atol=1e-12)


def test_matched_and_unmatched_parts_make_up_the_acceleration(accelerate):
    model, primitive, profile = accelerate
    ny = model.n_unactuated
    for k in range(0, len(primitive.time_s), 20):
        q, dq = primitive.q[k], profile.generalized_force_difference[k]
        mass = model.mass_matrix(q)
        mio, _ = model.io_linearization(q, primitive.qdot[k], primitive.lag[k])
        input_map = np.vstack([-np.linalg.solve(mass[:ny, :ny], mass[:ny, ny:]), np.eye(2)])
        rebuilt = input_map @ np.linalg.solve(mio, profile.matched_torque[k])
        rebuilt[:ny] += profile.unmatched_acceleration[k]
        np.testing.assert_allclose(rebuilt, np.linalg.solve(mass, dq), rtol=1e-9, atol=1e-12)
        d, _ = matched_disturbance(model, q, dq)
        np.testing.assert_allclose(d, input_map.T @ dq, rtol=1e-10, atol=1e-14)


def test_bound_is_finite_non_negative_at_the_primitive_times(accelerate):
    _, primitive, profile = accelerate
    bound = profile.disturbance_bound_n_m
    np.testing.assert_array_equal(profile.time_s, primitive.time_s)
    assert bound.shape == primitive.time_s.shape
    assert np.all(np.isfinite(bound)) and np.all(bound >= 0.0)
    np.testing.assert_allclose(bound, profile.margin * np.linalg.norm(profile.matched_torque, axis=1))
    assert bound.max() > 0.0
    stats = profile.statistics()
    assert 0.0 < stats.mean_n_m <= stats.p95_n_m <= stats.max_n_m == bound.max()
    assert profile.wake_step_s <= 0.008


def test_a_lead_in_that_does_not_join_is_refused(circulatory_library, model_for):
    primitive = circulatory_library.get(ACCELERATE)
    with pytest.raises(ManeuverError, match="does not end where"):
        flow_force_mismatch(model_for(primitive.spec, "circulatory"), primitive, lead_in=[primitive])
