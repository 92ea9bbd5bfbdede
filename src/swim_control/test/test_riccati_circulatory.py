"""The LQ stage and Theorem 1 on the circulatory flow model's extended error state x = (int e_y, e_q, edot_q, e_z).

The trajectories are shape-driven runs integrated here through the circulatory model (the foil's heave and pitch
prescribed, alpha [and R] and the lag states z from the dynamics), so (q, qdot, u, z) are consistent with the
model and need no planner. Checked: F and G against finite differences of the model's compiled state derivative,
the terminal weight, Theorem 1 against a direct Riccati solve of the scaled problem, and that Gamma's lag block
must be I (not lambda I).
"""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from swim_control.errors import GainComputationError
from swim_control.riccati import (
    LqrWeights,
    error_state_size,
    linearize,
    primitive_gains,
    solve_riccati,
    terminal_weight,
)
from swim_control.time_scaling import scale_riccati, scale_weights, scaling_diagonal
from swim_model import SinusoidalGait, VehicleModel
from swim_model.gait import zero_momentum_velocity

GAIT = SinusoidalGait(heave_amplitude_rad=0.3, pitch_amplitude_rad=0.5, frequency_hz=1.0, heave_bias_rad=0.1)
SAMPLES_PER_S = 80     # a primitive's fine grid density (2 x 40 intervals a second)
DURATION_S = 2.0
N_LAG = 2


def shape_driven_run(model: VehicleModel, duration_s: float = DURATION_S):
    """(time_s, q, qdot, u, lag) of the gait driven through the circulatory model from zero momentum and the
    steady lag of the starting motion, DOP853 at rtol 1e-11."""
    ny = model.n_unactuated
    y0 = np.array([0.0] if model.constrained else [0.0, model.lane_radius_m])
    psi0, psidot0, _ = GAIT.shape(0.0)
    q0 = np.concatenate([y0, psi0])
    qdot0 = np.concatenate([zero_momentum_velocity(model, q0, psidot0), psidot0])
    assert model.circulatory_flow is not None
    lag0 = model.circulatory_flow.steady_lag(model.foil_velocity_map(q0) @ qdot0)

    def unpack(time_s, x):
        psi, psidot, psiddot = GAIT.shape(time_s)
        return (np.concatenate([x[:ny], psi]), np.concatenate([x[ny:2 * ny], psidot]), psiddot, x[2 * ny:])

    def rhs(time_s, x):
        q, qdot, u, lag = unpack(time_s, x)
        qddot, _ = model.shape_dynamics(q, qdot, u, lag)
        return np.concatenate([qdot[:ny], qddot[:ny], model.lag_rate(q, qdot, lag)])

    time_s = np.linspace(0.0, duration_s, int(round(duration_s * SAMPLES_PER_S)) + 1)
    solution = solve_ivp(rhs, (0.0, duration_s), np.concatenate([y0, qdot0[:ny], lag0]), method="DOP853",
                         t_eval=time_s, rtol=1e-11, atol=1e-13)
    assert solution.success
    rows = [unpack(t, x) for t, x in zip(solution.t, solution.y.T)]
    q, qdot, u, lag = (np.array([row[i] for row in rows]) for i in range(4))
    return time_s, q, qdot, u, lag


@pytest.fixture(scope="module")
def circulatory_models(rig):
    return {"constrained": VehicleModel(rig, constrained=True, lane_radius_m=0.43, flow="circulatory"),
            "free": VehicleModel(rig, constrained=False, lane_radius_m=0.43, flow="circulatory")}


@pytest.fixture(scope="module")
def runs(circulatory_models):
    return {kind: shape_driven_run(model) for kind, model in circulatory_models.items()}


def _extended_rate(model, q, qdot, u, lag):
    """(qdot, qddot, zdot) from the model's compiled numeric functions (not the Jacobians linearize uses)."""
    qddot, _ = model.shape_dynamics(q, qdot, u, lag)
    return np.concatenate([qdot, qddot, model.lag_rate(q, qdot, lag)])


@pytest.mark.parametrize("kind", ["constrained", "free"])
def test_linearization_matches_finite_differences_of_the_state_derivative(circulatory_models, runs, kind):
    """F's (e_q, edot_q, e_z) rows and columns and G are d(qdot, qddot, zdot)/d(q, qdot, z) and d/du, by central
    differences; the integral rows are d/dt int e_y = e_y; G has no lag rows."""
    model = circulatory_models[kind]
    time_s, q, qdot, u, lag = runs[kind]
    ny, nq = model.n_unactuated, model.nq
    n = error_state_size(nq, ny, N_LAG)
    lin = linearize(model, q, qdot, u, lag)
    assert lin.state_matrix.shape == (len(time_s), n, n) and lin.input_matrix.shape == (len(time_s), n, 2)
    step = 1e-6
    for k in (0, 37, 101, len(time_s) - 1):
        x = np.concatenate([q[k], qdot[k], lag[k]])
        columns = []
        for j in range(len(x)):
            dx = np.zeros(len(x))
            dx[j] = step
            plus, minus = x + dx, x - dx
            columns.append((_extended_rate(model, plus[:nq], plus[nq:2 * nq], u[k], plus[2 * nq:])
                            - _extended_rate(model, minus[:nq], minus[nq:2 * nq], u[k], minus[2 * nq:]))
                           / (2 * step))
        numeric_state = np.column_stack(columns)
        du = np.eye(2) * step
        numeric_input = np.column_stack([(_extended_rate(model, q[k], qdot[k], u[k] + d, lag[k])
                                          - _extended_rate(model, q[k], qdot[k], u[k] - d, lag[k])) / (2 * step)
                                         for d in du])
        exact = lin.state_matrix[k]
        scale = np.abs(numeric_state).max()
        np.testing.assert_allclose(exact[ny:, ny:], numeric_state, atol=1e-6 * scale)
        np.testing.assert_array_equal(exact[:ny], np.eye(ny, n, ny))       # d/dt int e_y = e_y
        np.testing.assert_array_equal(exact[ny:, :ny], 0.0)                # nothing depends on int e_y
        np.testing.assert_allclose(lin.input_matrix[k, ny:], numeric_input, atol=1e-6 * np.abs(numeric_input).max())
        np.testing.assert_array_equal(lin.input_matrix[k, :ny], 0.0)
        np.testing.assert_array_equal(lin.input_matrix[k, ny + 2 * nq:], 0.0)   # u does not drive z
    # the flow couples the lag states into the motion (where the foil is not stalled: the stalled force is the
    # flat plate's, which has no lag) and the motion into them
    assert np.abs(lin.state_matrix[:, ny + nq:ny + 2 * nq, ny + 2 * nq:]).max() > 0.1
    assert np.abs(lin.state_matrix[:, ny + 2 * nq:, ny:ny + 2 * nq]).max(axis=(1, 2)).min() > 1e-3


def test_the_lag_dynamics_are_stable_along_the_run(circulatory_models, runs):
    """dg/dz has eigenvalues with negative real parts wherever the foil moves (the Wagner lags decay), which is
    what lets the terminal weight leave e_z unweighted."""
    model = circulatory_models["constrained"]
    _, q, qdot, u, lag = runs["constrained"]
    lin = linearize(model, q, qdot, u, lag)
    lag_block = lin.state_matrix[:, -N_LAG:, -N_LAG:]
    assert np.linalg.eigvals(lag_block).real.max() < 0.0


def test_linearize_refuses_a_lag_that_does_not_fit_the_model(circulatory_models, runs, model_for, strokes):
    model = circulatory_models["constrained"]
    _, q, qdot, u, lag = runs["constrained"]
    with pytest.raises(GainComputationError, match="needs the plan"):
        linearize(model, q, qdot, u)
    with pytest.raises(GainComputationError, match="shape"):
        linearize(model, q, qdot, u, lag[:, :1])
    stroke = strokes["constrained"]
    with pytest.raises(GainComputationError, match="takes no"):
        linearize(model_for(stroke.spec), stroke.q, stroke.qdot, stroke.foil_acceleration,
                  np.zeros((len(stroke.q), N_LAG)))


@pytest.mark.parametrize("kind", ["constrained", "free"])
def test_terminal_weight_solves_the_algebraic_riccati_equation_with_the_lag_block(circulatory_models, runs, kind):
    """S / terminal_scale solves the ARE of the averaged, mu-shifted pair on the extended state (residual at
    rounding level), is symmetric positive semi-definite, and the state weight puts nothing on e_z."""
    model = circulatory_models[kind]
    _, q, qdot, u, lag = runs[kind]
    weights = LqrWeights()
    state_weight = weights.state_weight_matrix(model.constrained, N_LAG)
    np.testing.assert_array_equal(state_weight[-N_LAG:], 0.0)
    np.testing.assert_array_equal(state_weight[:-N_LAG, :-N_LAG], weights.state_weight_matrix(model.constrained))
    input_weight = weights.input_weight_matrix()
    lin = linearize(model, q, qdot, u, lag)
    solution = terminal_weight(lin, state_weight, input_weight, weights) / weights.terminal_scale
    a = lin.state_matrix.mean(axis=0) - weights.terminal_margin_per_s * np.eye(len(solution))
    b = lin.input_matrix.mean(axis=0)
    residual = a.T @ solution + solution @ a - solution @ b @ np.linalg.solve(input_weight, b.T) @ solution \
        + state_weight
    assert np.abs(residual).max() < 1e-8 * np.abs(solution).max()
    assert np.linalg.eigvalsh(solution).min() > -1e-9 * np.abs(solution).max()
    # the closed loop of the averaged pair is stable
    closed = a - b @ np.linalg.solve(input_weight, b.T) @ solution
    assert np.linalg.eigvals(closed).real.max() < 0.0


def _direct_scaled_riccati(model, run, weights, time_scale):
    """Linearize the time-scaled run itself (q(lambda t), lambda qdot, lambda^2 u, lambda z) and solve its Riccati
    equation with the weights of eq. 30, independently of the stored P."""
    time_s, q, qdot, u, lag = run
    ny, nq = model.n_unactuated, model.nq
    state_weight, input_weight = weights.state_weight_matrix(model.constrained, N_LAG), weights.input_weight_matrix()
    terminal = terminal_weight(linearize(model, q, qdot, u, lag), state_weight, input_weight, weights)
    q_l, r_l, s_l = scale_weights(state_weight, input_weight, terminal, time_scale, ny, nq, N_LAG)
    scaled = linearize(model, q, qdot * time_scale, u * time_scale ** 2, lag * time_scale)
    return solve_riccati(time_s / time_scale, scaled, q_l, r_l, s_l)


@pytest.mark.parametrize("kind", ["constrained", "free"])
@pytest.mark.parametrize("time_scale", [0.8, 1.67])
def test_theorem_1_on_the_extended_state(circulatory_models, runs, kind, time_scale):
    """Gamma P(lambda t) Gamma, Gamma = diag(lambda^2, lambda, 1, 1), equals P of the scaled problem solved
    directly (as test_time_scaling.py checks the ideal one)."""
    model = circulatory_models[kind]
    time_s, q, qdot, u, lag = runs[kind]
    stored = primitive_gains(model, time_s, q, qdot, u, LqrWeights(), lag=lag).riccati
    predicted = scale_riccati(stored, time_scale, model.n_unactuated, model.nq, N_LAG)
    direct = _direct_scaled_riccati(model, runs[kind], LqrWeights(), time_scale)
    relative = np.abs(direct - predicted).max() / np.abs(direct).max()
    assert relative < 1e-6
    # with lambda on the lag entries (z -> lambda z taken for Gamma) the scaled P misses by about 1 %
    wrong = scaling_diagonal(time_scale, model.n_unactuated, model.nq, N_LAG)
    wrong[-N_LAG:] = time_scale
    missed = stored * wrong[None, :, None] * wrong[None, None, :]
    assert np.abs(direct - missed).max() / np.abs(direct).max() > 1e-3


def test_gammas_lag_block_is_the_identity_by_the_scaled_linearization(circulatory_models, runs):
    """F_l = lambda Gamma^-1 F(lambda t) Gamma (eq. 28) holds for the directly linearized scaled run with the lag
    entries of Gamma 1 and fails with lambda (what z -> lambda z alone might suggest)."""
    model = circulatory_models["constrained"]
    _, q, qdot, u, lag = runs["constrained"]
    ny, nq, lam = model.n_unactuated, model.nq, 1.3
    original = linearize(model, q, qdot, u, lag)
    scaled = linearize(model, q, lam * qdot, lam ** 2 * u, lam * lag)
    gamma = scaling_diagonal(lam, ny, nq, N_LAG)
    np.testing.assert_array_equal(gamma[-N_LAG:], 1.0)
    wrong = gamma.copy()
    wrong[-N_LAG:] = lam

    def predicted(diagonal):
        return lam * original.state_matrix * diagonal[None, None, :] / diagonal[None, :, None]
    scale = np.abs(scaled.state_matrix).max()
    assert np.abs(predicted(gamma) - scaled.state_matrix).max() < 1e-9 * scale
    assert np.abs(predicted(wrong) - scaled.state_matrix).max() > 1e-3 * scale
    np.testing.assert_allclose(scaled.input_matrix, original.input_matrix, rtol=1e-9, atol=1e-12)


def test_a_stored_run_cycle_lookahead_keeps_the_lag_block(circulatory_models, runs):
    """cycle_samples works on the extended state: P(T) continued over the lookahead is finite and its lag block
    is coupled (the gains act on e_z through df/dz)."""
    model = circulatory_models["constrained"]
    time_s, q, qdot, u, lag = runs["constrained"]
    gains = primitive_gains(model, time_s, q, qdot, u, LqrWeights(), cycle_samples=SAMPLES_PER_S + 1, lag=lag)
    n = error_state_size(model.nq, model.n_unactuated, N_LAG)
    assert gains.riccati.shape == (len(time_s), n, n) and gains.riccati_input_gain.shape == (len(time_s), 2, n)
    assert np.all(np.isfinite(gains.riccati))
    assert np.abs(gains.riccati_input_gain[:, :, -N_LAG:]).max() > 1e-6 * np.abs(gains.riccati_input_gain).max()
    assert math.isfinite(float(np.abs(gains.riccati).max()))
