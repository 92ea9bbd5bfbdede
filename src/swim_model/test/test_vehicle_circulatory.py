"""The vehicle with the circulatory flow (VehicleModel(flow="circulatory")): balance laws, time scaling, the
extended state, and the ideal model left exactly as it was.

* Energy: with no torque, T changes at exactly the power of the flow's force, qdot' Q_flow = (U, V, Omega) . f
  (docs/model_and_method.md P2 with the flow as the only external force), and p_alpha at its hub component
  Q_flow[0] (P1: nothing depends on alpha). Checked on the vector field at random states and along 3 s trajectories
  integrated with the work and the impulse as extra states.
* P3 (time scaling): the flow's forces are homogeneous of degree 2 in (qdot, lag) and its lag rates of degree 2,
  so with lag -> lambda lag the vector field scales as the ideal model's: f(q, lambda qdot, lambda z, lambda^2 tau)
  = (lambda qdot, lambda^2 qddot, lambda^2 zdot), to (eps/|u|)^2 (eps = 1e-7 m/s). RK4 commutes with that scaling,
  so the scaled run with steps h/lambda reproduces the run with steps h.
"""
import math

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from swim_model import StateError, VehicleModel, codegen
from swim_model.errors import FlowModelError
from swim_model.flow import CirculatoryFlow, FlowParameters
from swim_model.separation import TrailingEdgeSeparation

MODELS = {constrained: VehicleModel(constrained=constrained, flow="circulatory") for constrained in (False, True)}
#: the trailing edge separating as on the tank's NACA 0012 at Re 4e4 (flow_comparison.static_separation_fit: onset
#: 6.3 deg, width 0.2 deg); its two more lag states
SEPARATED = FlowParameters(separation=TrailingEdgeSeparation(math.radians(6.3), math.radians(0.2)))
IDEAL = {constrained: VehicleModel(constrained=constrained) for constrained in (False, True)}


def random_state(model: VehicleModel, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(q, qdot, lag) with the foil moving 0.1-1 m/s and the lag states near their steady values."""
    q = rng.uniform(-1.0, 1.0, model.nq)
    if not model.constrained:
        q[1] = rng.uniform(0.35, 0.55)
    qdot = rng.uniform(-2.0, 2.0, model.nq)
    u, v, w = model.foil_velocity_map(q) @ qdot
    steady = model.circulatory_flow.steady_lag((u, v, w))
    return q, qdot, steady * rng.uniform(0.5, 1.5, model.n_lag)


@pytest.mark.parametrize("constrained, separation", [(False, False), (True, False), (False, True)])
def test_power_and_hub_torque_of_the_flow_on_the_vector_field(constrained, separation):
    """dT/dt (exact derivative along the dynamics) = qdot' Q_flow = (U, V, Omega) . f, and dp_alpha/dt = Q_flow[0],
    to 1e-9 relative; Q_flow = Q2' f against the foil velocity map and swim_model.flow evaluated separately. With
    the trailing edge separating too (four lag states)."""
    model = (VehicleModel(constrained=constrained, flow="circulatory", flow_parameters=SEPARATED) if separation
             else MODELS[constrained])
    s = model.symbolic
    xdot = model.state_derivative_function()(ca.vertcat(s.q, s.qdot, s.lag), ca.DM.zeros(2))
    energy = 0.5 * s.qdot.T @ s.mass @ s.qdot
    momentum = (s.mass @ s.qdot)[0]
    x = ca.vertcat(s.q, s.qdot, s.lag)
    rates = ca.Function("rates", [s.q, s.qdot, s.lag],
                        [ca.jtimes(energy, x, xdot), ca.jtimes(momentum, x, xdot)])
    rng = np.random.default_rng(21)
    flow = CirculatoryFlow(model.foil, model.rig.water_density_kg_m3, model.circulatory_flow.params)
    for _ in range(20):
        q, qdot, lag = random_state(model, rng)
        f, generalized = model.flow_force(q, qdot, lag)
        q2 = model.foil_velocity_map(q)
        np.testing.assert_allclose(f, flow.evaluate(q2 @ qdot, lag)["f"], rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(generalized, q2.T @ f, rtol=1e-12, atol=1e-14)
        energy_rate, momentum_rate = (float(v) for v in rates(q, qdot, lag))
        power = float((q2 @ qdot) @ f)
        scale = np.abs((q2 @ qdot) * f).sum()
        assert energy_rate == pytest.approx(power, abs=1e-9 * scale)
        assert momentum_rate == pytest.approx(generalized[0], abs=1e-9 * np.abs(generalized).max())


@pytest.mark.parametrize("constrained", [False, True])
def test_coasting_vehicle_energy_and_momentum_follow_the_flows_work_and_impulse(constrained):
    """No torque for 3 s from a swimming state: T(t) - T(0) = int qdot' Q_flow dt and p_alpha(t) - p_alpha(0) =
    int Q_flow[0] dt to 1e-9 relative; the flow takes energy overall, and returns some of it for part of the run
    (the lagged lift)."""
    model = MODELS[constrained]
    s = model.symbolic
    x = ca.vertcat(s.q, s.qdot, s.lag)
    xdot = model.state_derivative_function()(x, ca.DM.zeros(2))
    power = s.qdot.T @ s.generalized_flow_force
    rhs = ca.Function("rhs", [x], [ca.vertcat(xdot, power, s.generalized_flow_force[0])])
    q0 = np.array([0.0, 0.43, 0.4, -0.3]) if not constrained else np.array([0.0, 0.4, -0.3])
    qdot0 = np.array([0.6, 0.0, 3.0, -2.0]) if not constrained else np.array([0.6, 3.0, -2.0])
    lag0 = np.zeros(2)
    run = solve_ivp(lambda t, y: np.asarray(rhs(y[:model.nx]), dtype=float).ravel(), (0.0, 3.0),
                    np.concatenate([q0, qdot0, lag0, [0.0, 0.0]]), method="DOP853", rtol=1e-12, atol=1e-14,
                    dense_output=True)
    assert run.success
    nq = model.nq
    energy0 = model.kinetic_energy(q0, qdot0)
    p0 = model.momentum(q0, qdot0)[0]
    powers = []
    for t in np.linspace(0.0, 3.0, 61):
        y = run.sol(t)
        q, qdot, lag, work, impulse = y[:nq], y[nq:2 * nq], y[2 * nq:2 * nq + 2], y[-2], y[-1]
        assert model.kinetic_energy(q, qdot, lag) - energy0 == pytest.approx(work, abs=1e-9 * energy0)
        assert model.momentum(q, qdot, lag)[0] - p0 == pytest.approx(impulse, abs=1e-9 * np.abs(
            model.momentum(q0, qdot0)).max())
        powers.append(float(qdot @ model.flow_force(q, qdot, lag)[1]))
    y = run.sol(3.0)
    assert model.kinetic_energy(y[:nq], y[nq:2 * nq]) < 0.5 * energy0  # it coasts to a stop
    assert max(powers) > 0.0 > min(powers)                              # some of the energy comes back


@pytest.mark.parametrize("constrained", [False, True])
def test_time_scaling_holds_with_the_flow(constrained):
    """P3: lambda^2 tau(lambda t) from (q0, lambda qdot0, lambda z0) gives q(lambda t), lambda qdot(lambda t) and
    lambda z(lambda t), to 1e-9 (RK4 at h and h / lambda over 2 s; and the vector field at random states)."""
    model = MODELS[constrained]
    rng = np.random.default_rng(5)
    f = model.state_derivative_function()
    for scale in (0.5, 1.7):
        for _ in range(10):
            q, qdot, lag = random_state(model, rng)
            tau = rng.uniform(-0.5, 0.5, 2)
            base = np.asarray(f(np.concatenate([q, qdot, lag]), tau), dtype=float).ravel()
            scaled = np.asarray(f(np.concatenate([q, scale * qdot, scale * lag]), scale ** 2 * tau),
                                dtype=float).ravel()
            nq = model.nq
            expected = np.concatenate([scale * base[:nq], scale ** 2 * base[nq:]])
            np.testing.assert_allclose(scaled, expected, rtol=0.0, atol=1e-9 * np.abs(expected).max())
    q0 = np.array([0.1, 0.45, 0.2, -0.1]) if not constrained else np.array([0.1, 0.2, -0.1])
    qdot0 = np.linspace(-0.4, 0.5, model.nq) + 1.0
    u, v, w = model.foil_velocity_map(q0) @ qdot0
    lag0 = model.circulatory_flow.steady_lag((u, v, w))
    step, duration = 0.002, 2.0
    t = np.arange(round(duration / step)) * step
    torques = np.column_stack([0.3 * np.sin(3.0 * t), 0.05 * np.cos(5.0 * t + 0.3)])
    q, qdot, lag = model.integrate_rk4(q0, qdot0, torques, step, lag=lag0)
    for scale in (0.5, 1.7):
        qs, qdots, lags = model.integrate_rk4(q0, scale * qdot0, scale ** 2 * torques, step / scale, lag=scale * lag0)
        np.testing.assert_allclose(qs, q, rtol=0.0, atol=1e-9)
        np.testing.assert_allclose(qdots / scale, qdot, rtol=0.0, atol=1e-9)
        np.testing.assert_allclose(lags / scale, lag, rtol=0.0, atol=1e-9)
    assert np.abs(q[-1] - q0).max() > 0.1  # it moved


@pytest.mark.parametrize("constrained", [False, True])
def test_circulatory_dynamics_are_consistent(constrained):
    """inverse(forward) = tau with the unactuated rows balanced; I/O linearization reproduces psiddot; RK4 agrees
    with an accurate integration of (q, qdot, lag)."""
    model = MODELS[constrained]
    rng = np.random.default_rng(9)
    for _ in range(10):
        q, qdot, lag = random_state(model, rng)
        tau, u = rng.uniform(-0.5, 0.5, 2), rng.uniform(-5.0, 5.0, 2)
        qddot = model.forward_dynamics(q, qdot, tau, lag)
        np.testing.assert_allclose(model.inverse_dynamics(q, qdot, qddot, lag), tau, atol=1e-10)
        np.testing.assert_allclose(model.generalized_force(q, qdot, qddot, lag)[:model.n_unactuated], 0.0,
                                   atol=1e-10)
        mio, cio_qdot = model.io_linearization(q, qdot, lag)
        np.testing.assert_allclose(model.forward_dynamics(q, qdot, mio @ u + cio_qdot, lag)[-2:], u, atol=1e-8)
        shape_qddot, shape_tau = model.shape_dynamics(q, qdot, u, lag)
        np.testing.assert_allclose(shape_tau, mio @ u + cio_qdot, atol=1e-10)
        np.testing.assert_allclose(model.forward_dynamics(q, qdot, shape_tau, lag), shape_qddot, atol=1e-8)
    q, qdot, lag = random_state(model, rng)
    tau = np.array([0.2, -0.05])
    f = model.state_derivative_function()
    reference = solve_ivp(lambda t, x: np.asarray(f(x, tau), dtype=float).ravel(), (0.0, 0.008),
                          np.concatenate([q, qdot, lag]), method="DOP853", rtol=1e-12, atol=1e-14)
    qs, qdots, lags = model.integrate_rk4(q, qdot, np.tile(tau, (8, 1)), 0.001, lag=lag)
    assert qs.shape == (9, model.nq) and lags.shape == (9, 2)
    np.testing.assert_allclose(np.concatenate([qs[-1], qdots[-1], lags[-1]]), reference.y[:, -1], atol=1e-8)
    one = model.rk4_step(q, qdot, tau, 0.001, lag=lag)
    np.testing.assert_allclose(np.concatenate(one), np.concatenate([qs[1], qdots[1], lags[1]]), atol=1e-14)


def test_smooth_from_rest():
    """At rest (the start of every accelerate primitive) the dynamics and their first and second derivatives are
    finite: every speed in the flow is regularized."""
    model = MODELS[False]
    s = model.symbolic
    x = ca.vertcat(s.q, s.qdot, s.lag)
    xdot = model.state_derivative_function()(x, s.tau)
    jacobian = ca.jacobian(xdot, ca.vertcat(x, s.tau))
    hessian = ca.hessian(ca.sumsqr(xdot), ca.vertcat(x, s.tau))[0]
    check = ca.Function("check", [s.q, s.qdot, s.lag, s.tau], [xdot, jacobian, hessian])
    for value in check([0.0, 0.43, 0.1, -0.2], [0.0] * 4, [0.0, 0.0], [0.3, -0.1]):
        assert np.all(np.isfinite(np.asarray(value, dtype=float)))


def test_state_of_the_wrong_size_is_refused_with_a_clear_message():
    circulatory, ideal = MODELS[False], IDEAL[False]
    q, qdot = np.array([0.0, 0.43, 0.1, 0.0]), np.zeros(4)
    assert (circulatory.nx, circulatory.n_lag, ideal.nx, ideal.n_lag) == (10, 2, 8, 0)
    with pytest.raises(StateError, match="needs the flow's lag states"):
        circulatory.forward_dynamics(q, qdot, [0.0, 0.0])
    with pytest.raises(StateError, match="lag must have 2 entries"):
        circulatory.forward_dynamics(q, qdot, [0.0, 0.0], lag=[0.0, 0.0, 0.0])
    with pytest.raises(StateError, match="no lag states"):
        ideal.forward_dynamics(q, qdot, [0.0, 0.0], lag=[0.0, 0.0])
    with pytest.raises(StateError):
        circulatory.integrate_rk4(q, qdot, np.zeros((3, 2)), 0.001, lag=[0.0])
    with pytest.raises(StateError):
        circulatory.kinetic_energy(q, qdot, lag=[np.nan, 0.0])
    with pytest.raises(FlowModelError):
        VehicleModel(flow="viscous")


@pytest.mark.parametrize("constrained", [False, True])
def test_ideal_flow_is_the_unchanged_default(constrained):
    """flow="ideal" is the default and builds the paper's functions only, with their inputs (the same generated C
    as the default model, so the same compiled library and the same numbers bit for bit), nothing of the flow."""
    default, explicit = IDEAL[constrained], VehicleModel(constrained=constrained, flow="ideal")
    assert explicit._codegen_tag() == default._codegen_tag()
    assert set(default.symbolic.functions) == {
        "mass_matrix", "coriolis_matrix", "forward_dynamics", "generalized_force", "kinetic_energy", "momentum",
        "io_linearization", "shape_dynamics", "foil_velocity_map", "rigid_mass_matrix"}
    for name, function in default.symbolic.functions.items():
        assert function.n_in() == (1 if name in ("mass_matrix", "foil_velocity_map", "rigid_mass_matrix") else
                                   2 if name in ("coriolis_matrix", "kinetic_energy", "momentum",
                                                 "io_linearization") else 3)
    assert codegen.compile_library(explicit._numeric_functions(), explicit._codegen_tag()) == \
        codegen.compile_library(default._numeric_functions(), default._codegen_tag())
    assert default.symbolic.lag is None and default.nx == 2 * default.nq
    rng = np.random.default_rng(2)
    q, qdot, tau = rng.uniform(-1, 1, default.nq), rng.uniform(-2, 2, default.nq), rng.uniform(-1, 1, 2)
    if not constrained:
        q[1] = 0.45
    for a, b in ((default.forward_dynamics(q, qdot, tau), explicit.forward_dynamics(q, qdot, tau)),
                 (default.integrate_rk4(q, qdot, np.tile(tau, (4, 1)), 0.001)[0],
                  explicit.integrate_rk4(q, qdot, np.tile(tau, (4, 1)), 0.001)[0])):
        assert a.tobytes() == b.tobytes()
    # the circulatory model shares the ideal model's inertia exactly
    circulatory = MODELS[constrained]
    assert circulatory.mass_matrix(q).tobytes() == default.mass_matrix(q).tobytes()
    assert circulatory.kinetic_energy(q, qdot) == default.kinetic_energy(q, qdot)


def test_angle_of_attack_of_the_vehicle():
    """VehicleModel.angle_of_attack is atan2(-V, U) of eq. 40's foil velocity."""
    model = IDEAL[True]
    q, qdot = np.array([0.0, 0.2, -0.1]), np.array([0.5, 1.0, -0.7])
    u, v, _ = model.foil_velocity_map(q) @ qdot
    assert model.angle_of_attack(q, qdot) == pytest.approx(math.atan2(-v, u), abs=1e-15)
