"""Properties of the vehicle model (docs/model_and_method.md section 2), on random states."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from swim_model import StateError, VehicleModel
from swim_model.hydrodynamics import force_route_forward_dynamics

MODELS = {False: VehicleModel(constrained=False), True: VehicleModel(constrained=True)}
settings.register_profile("swim", max_examples=25, deadline=None)
settings.load_profile("swim")

angles = st.floats(-1.2, 1.2)
rates = st.floats(-3.0, 3.0)


@st.composite
def states(draw, constrained):
    """(q, qdot) with R inside the tank and moderate angles and rates."""
    model = MODELS[constrained]
    q = [draw(st.floats(-math.pi, math.pi))]
    if not constrained:
        q.append(draw(st.floats(0.3, 0.6)))
    q += [draw(angles), draw(angles)]
    qdot = [draw(rates) for _ in range(model.nq)]
    return model, np.array(q), np.array(qdot)


both = st.sampled_from([False, True]).flatmap(states)


@given(both)
def test_mass_matrix_symmetric_positive_definite(state):
    model, q, _ = state
    mass = model.mass_matrix(q)
    np.testing.assert_allclose(mass, mass.T, rtol=0, atol=1e-14)
    assert np.linalg.eigvalsh(mass).min() > 0.0


@given(both)
def test_mass_matrix_independent_of_alpha(state):
    """Prop. 1 (symmetry): nothing depends on alpha."""
    model, q, _ = state
    shifted = q.copy()
    shifted[0] += 1.234
    np.testing.assert_allclose(model.mass_matrix(shifted), model.mass_matrix(q), rtol=1e-12, atol=1e-14)


@given(both)
def test_mdot_minus_2c_is_skew(state):
    """Mmdot by central differences of Mm along qdot (independent of the symbolic derivative)."""
    model, q, qdot = state
    h = 1e-6
    mass_dot = (model.mass_matrix(q + h * qdot) - model.mass_matrix(q - h * qdot)) / (2 * h)
    skew = mass_dot - 2.0 * model.coriolis_matrix(q, qdot)
    scale = np.abs(mass_dot).max() + 1e-12
    # central-difference error ~ h^2 |M'''| plus round-off ~ eps |M| / h
    np.testing.assert_allclose(skew + skew.T, 0.0, atol=1e-7 * scale + 1e-9)


@given(both, st.floats(-2, 2), st.floats(-2, 2))
def test_coriolis_is_linear_in_qdot(state, a, b):
    model, q, qdot = state
    other = np.roll(qdot, 1)
    combined = model.coriolis_matrix(q, a * qdot + b * other)
    expected = a * model.coriolis_matrix(q, qdot) + b * model.coriolis_matrix(q, other)
    np.testing.assert_allclose(combined, expected, atol=1e-12 * (1 + np.abs(expected).max()))


@given(both, st.floats(-1, 1), st.floats(-0.5, 0.5))
def test_power_balance(state, tau_h, tau_p):
    """Prop. 2: dT/dt = phidot tau_h + thetadot tau_p, dT/dt by central differences along the motion."""
    model, q, qdot = state
    tau = np.array([tau_h, tau_p])
    qddot = model.forward_dynamics(q, qdot, tau)
    h = 1e-5
    rate = (model.kinetic_energy(q + h * qdot + 0.5 * h * h * qddot, qdot + h * qddot)
            - model.kinetic_energy(q - h * qdot + 0.5 * h * h * qddot, qdot - h * qddot)) / (2 * h)
    power = qdot[-2:] @ tau
    assert rate == pytest.approx(power, abs=1e-6 * (1 + abs(power) + model.kinetic_energy(q, qdot)))


@given(both, st.floats(-1, 1), st.floats(-0.5, 0.5))
def test_energy_and_force_routes_agree(state, tau_h, tau_p):
    """Appendix A: the Lagrangian (A.1) and Kirchhoff-force (A.2) routes give the same qddot."""
    model, q, qdot = state
    force_route = force_route_forward_dynamics(model)
    tau = np.array([tau_h, tau_p])
    energy_qddot = model.forward_dynamics(q, qdot, tau)
    force_qddot = np.asarray(force_route(q, qdot, tau)).ravel()
    np.testing.assert_allclose(force_qddot, energy_qddot, rtol=1e-9, atol=1e-10 * (1 + np.abs(energy_qddot).max()))


@given(both, st.floats(-1, 1), st.floats(-0.5, 0.5))
def test_inverse_dynamics_inverts_forward_dynamics(state, tau_h, tau_p):
    model, q, qdot = state
    tau = np.array([tau_h, tau_p])
    qddot = model.forward_dynamics(q, qdot, tau)
    np.testing.assert_allclose(model.inverse_dynamics(q, qdot, qddot), tau, atol=1e-10)
    np.testing.assert_allclose(model.generalized_force(q, qdot, qddot)[:model.n_unactuated], 0.0, atol=1e-10)


@given(both, st.floats(-5, 5), st.floats(-5, 5))
def test_io_linearization_reproduces_shape_dynamics(state, u_h, u_p):
    """eqs. 22-23: tau = Mio u + Cio qdot makes psiddot = u through the full dynamics."""
    model, q, qdot = state
    u = np.array([u_h, u_p])
    mio, cio_qdot = model.io_linearization(q, qdot)
    tau = mio @ u + cio_qdot
    np.testing.assert_allclose(model.forward_dynamics(q, qdot, tau)[-2:], u, atol=1e-8 * (1 + np.abs(u).max()))
    np.testing.assert_allclose(model.shape_dynamics(q, qdot, u)[1], tau, atol=1e-10)


@given(both)
def test_foil_velocities_follow_printed_eq_40(state):
    model, q, qdot = state
    rig = model.rig
    alpha_dot = qdot[0]
    if model.constrained:
        radius, radius_dot, phi, theta, phi_dot, theta_dot = model.lane_radius_m, 0.0, q[1], q[2], qdot[1], qdot[2]
    else:
        radius, radius_dot, phi, theta, phi_dot, theta_dot = q[1], qdot[1], q[2], q[3], qdot[2], qdot[3]
    lh, ld, lf = rig.heave_link_length_m, rig.heave_pivot_inset_m, rig.pitch_axis_to_foil_reference_m
    u = (-radius_dot * math.sin(theta) + (radius - ld) * alpha_dot * math.cos(theta)
         + lh * (phi_dot + alpha_dot) * math.sin(theta - phi))
    v = (-radius_dot * math.cos(theta) - (radius - ld) * alpha_dot * math.sin(theta)
         + lh * (phi_dot + alpha_dot) * math.cos(theta - phi) + lf * (theta_dot + alpha_dot))
    np.testing.assert_allclose(model.foil_velocity_map(q) @ qdot, [u, v, alpha_dot + theta_dot], atol=1e-12)


def _integrate(model, q0, qdot0, torque, duration_s):
    def rhs(t, x):
        return np.concatenate([x[model.nq:], model.forward_dynamics(x[:model.nq], x[model.nq:], torque(t))])
    return solve_ivp(rhs, (0.0, duration_s), np.concatenate([q0, qdot0]), method="DOP853",
                     rtol=1e-12, atol=1e-14, dense_output=True)


@pytest.mark.parametrize("constrained", [False, True])
def test_free_motion_conserves_energy_and_momentum(constrained):
    """Zero torque for 20 s: T and p_alpha conserved to 1e-8 relative (Props. 1-2)."""
    model = MODELS[constrained]
    rng = np.random.default_rng(7)
    q0 = np.array([0.0, 0.43, 0.3, -0.2]) if not constrained else np.array([0.0, 0.3, -0.2])
    qdot0 = rng.uniform(-1.0, 1.0, model.nq)
    run = _integrate(model, q0, qdot0, lambda t: np.zeros(2), 20.0)
    assert run.success
    q_end, qdot_end = run.y[:model.nq, -1], run.y[model.nq:, -1]
    energy0, energy1 = model.kinetic_energy(q0, qdot0), model.kinetic_energy(q_end, qdot_end)
    assert abs(energy1 - energy0) <= 1e-8 * energy0
    p0, p1 = model.momentum(q0, qdot0)[0], model.momentum(q_end, qdot_end)[0]
    assert abs(p1 - p0) <= 1e-8 * np.linalg.norm(model.momentum(q0, qdot0))
    assert np.abs(q_end - q0).max() > 0.1  # it did move


@settings(max_examples=6, deadline=None)
@given(constrained=st.booleans(), scale=st.floats(0.5, 2.0))
def test_time_scaling_property(constrained, scale):
    """P3: lambda^2 tau(lambda t) from (q0, lambda qdot0) gives q(lambda t)."""
    model = MODELS[constrained]
    q0 = np.array([0.1, 0.45, 0.2, -0.1]) if not constrained else np.array([0.1, 0.2, -0.1])
    qdot0 = np.linspace(-0.4, 0.5, model.nq)

    def torque(t):
        return np.array([0.3 * math.sin(3.0 * t), 0.05 * math.cos(5.0 * t + 0.3)])

    duration = 2.0
    base = _integrate(model, q0, qdot0, torque, duration)
    scaled = _integrate(model, q0, scale * qdot0, lambda t: scale ** 2 * torque(scale * t), duration / scale)
    for t in np.linspace(0.0, duration / scale, 5):
        np.testing.assert_allclose(scaled.sol(t)[:model.nq], base.sol(scale * t)[:model.nq], atol=1e-8)
        np.testing.assert_allclose(scaled.sol(t)[model.nq:], scale * base.sol(scale * t)[model.nq:], atol=1e-7)


def test_rk4_step_agrees_with_accurate_integration():
    model = MODELS[False]
    q, qdot, tau = np.array([0.0, 0.43, 0.2, 0.1]), np.array([0.1, 0.0, 1.0, -1.0]), np.array([0.2, -0.05])
    reference = _integrate(model, q, qdot, lambda t: tau, 0.008)
    x = (q, qdot)
    for _ in range(8):
        x = model.rk4_step(*x, tau, 0.001)
    np.testing.assert_allclose(np.concatenate(x), reference.y[:, -1], atol=1e-9)
    qs, qdots = model.integrate_rk4(q, qdot, np.tile(tau, (8, 1)), 0.001)
    assert qs.shape == (9, 4)
    np.testing.assert_allclose(np.concatenate([qs[-1], qdots[-1]]), np.concatenate(x), atol=1e-13)


@pytest.mark.parametrize("q, qdot, tau", [
    ([0.0, 0.43, 0.1], [0, 0, 0, 0], [0, 0]),
    ([0.0, 0.43, 0.1, float("nan")], [0, 0, 0, 0], [0, 0]),
    ([0.0, 0.43, 0.1, 0.0], [0, 0, 0, 0], [0, 0, 0]),
])
def test_bad_vectors_are_refused(q, qdot, tau):
    with pytest.raises(StateError):
        MODELS[False].forward_dynamics(q, qdot, tau)
