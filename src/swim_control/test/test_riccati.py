"""The LQ stage against closed forms and independent computations (swim_control.riccati)."""
import numpy as np
import pytest
import scipy.linalg
from hypothesis import given, settings
from hypothesis import strategies as st

from swim_control.errors import GainComputationError
from swim_control.riccati import Linearization, LqrWeights, linearize, solve_riccati, terminal_weight


def test_scalar_riccati_matches_its_closed_form():
    """-pdot = 2 a p - p^2 b^2 / r + q with p(T) = s has p(t) = p+ + (p- - p+) ... ; compare to the tanh form."""
    a, b, r, q, s, horizon = 0.7, 1.3, 0.5, 2.0, 0.1, 3.0
    time_s = np.linspace(0.0, horizon, 61)
    lin = Linearization(np.full((61, 1, 1), a), np.full((61, 1, 1), b))
    p = solve_riccati(time_s, lin, np.array([[q]]), np.array([[r]]), np.array([[s]]))[:, 0, 0]
    # closed form: with k = b^2/r, roots p1 > 0 > p2 of k p^2 - 2 a p - q = 0, and tau = T - t,
    # p(tau) = (p1 (s - p2) - p2 (s - p1) e^{-k (p1 - p2) tau}) / ((s - p2) - (s - p1) e^{-k (p1 - p2) tau})
    k = b * b / r
    p1 = (a + np.sqrt(a * a + k * q)) / k
    p2 = (a - np.sqrt(a * a + k * q)) / k
    decay = np.exp(-k * (p1 - p2) * (horizon - time_s))
    exact = (p1 * (s - p2) - p2 * (s - p1) * decay) / ((s - p2) - (s - p1) * decay)
    np.testing.assert_allclose(p, exact, rtol=1e-8)


def test_long_horizon_riccati_reaches_the_algebraic_solution():
    rng = np.random.default_rng(3)
    f = rng.normal(size=(4, 4))
    g = rng.normal(size=(4, 2))
    q, r = np.eye(4), np.diag([0.5, 2.0])
    samples = 11
    lin = Linearization(np.repeat(f[None], samples, 0), np.repeat(g[None], samples, 0))
    p = solve_riccati(np.linspace(0, 30.0, samples), lin, q, r, np.zeros((4, 4)))
    np.testing.assert_allclose(p[0], scipy.linalg.solve_continuous_are(f, g, q, r), rtol=1e-7)


def _time_varying(time_s):
    """A smooth time-varying F (4 x 4) and G (4 x 2) with fast and slow parts, sampled at time_s."""
    rng = np.random.default_rng(11)
    f0, f1, g0, g1 = rng.normal(size=(4, 4)), rng.normal(size=(4, 4)), rng.normal(size=(4, 2)), rng.normal(size=(4, 2))
    wave = np.sin(7.0 * time_s)[:, None, None]
    return Linearization(f0 + 2.0 * wave * f1, g0 + wave * g1 + np.cos(time_s)[:, None, None] * g0)


def test_time_varying_riccati_matches_an_independent_integration():
    """P(t) against eq. 20 itself integrated by DOP853 at tight tolerances (F, G linear between samples)."""
    import scipy.integrate
    time_s = np.linspace(0.0, 2.0, 81)
    lin = _time_varying(time_s)
    q, r, s = np.diag([1.0, 2.0, 0.5, 3.0]), np.diag([0.3, 0.1]), 0.2 * np.eye(4)
    p = solve_riccati(time_s, lin, q, r, s)

    def minus_p_dot(t, p_flat):
        f = np.array([np.interp(t, time_s, lin.state_matrix[:, i, j]) for i in range(4) for j in range(4)])
        g = np.array([np.interp(t, time_s, lin.input_matrix[:, i, j]) for i in range(4) for j in range(2)])
        f, g, pm = f.reshape(4, 4), g.reshape(4, 2), p_flat.reshape(4, 4)
        return -(pm @ f + f.T @ pm - pm @ g @ np.linalg.solve(r, g.T) @ pm + q).ravel()
    exact = scipy.integrate.solve_ivp(minus_p_dot, (2.0, 0.0), s.ravel(), method="DOP853", t_eval=time_s[::-1],
                                      rtol=1e-12, atol=1e-12).y.T[::-1].reshape(-1, 4, 4)
    assert np.abs(p - exact).max() < 1e-7 * np.abs(exact).max()


def test_merged_transitions_carry_p_as_the_single_ones():
    """merge_transitions multiplies consecutive maps; P carried through them equals P carried one by one, and
    the product's norm bound splits a long span into several maps."""
    from swim_control.riccati import backward_transitions, merge_transitions, sweep_backward
    time_s = np.linspace(0.0, 2.0, 81)
    q, r, s = np.eye(4), np.diag([0.3, 0.1]), 0.2 * np.eye(4)
    transitions = backward_transitions(time_s, _time_varying(time_s), q, r)
    single = sweep_backward(transitions, s)[0]
    for bound in (1e3, 30.0):
        merged = merge_transitions(transitions, bound)
        assert 1 <= len(merged) < len(transitions)
        single_norms = {float(np.linalg.norm(t)) for t in transitions}
        assert all(np.linalg.norm(m) <= bound or float(np.linalg.norm(m)) in single_norms for m in merged)
        np.testing.assert_allclose(sweep_backward(merged, s)[0], single, rtol=1e-9)
    assert len(merge_transitions(transitions, 30.0)) > len(merge_transitions(transitions, 1e3))


def test_bad_time_grid_is_refused():
    lin = Linearization(np.zeros((3, 1, 1)), np.zeros((3, 1, 1)))
    with pytest.raises(GainComputationError):
        solve_riccati(np.array([0.0, 1.0, 1.0]), lin, np.eye(1), np.eye(1), np.eye(1))


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(-3, 3), min_size=10, max_size=10), st.booleans())
def test_state_weight_is_the_papers_z_form(values, constrained):
    """x'Qx = z'Gg z with z built independently from the paper's Sec. 7 formula."""
    w = LqrWeights(alpha_rate_per_s=1.1, lateral_rate_per_s=2.3, heave_rate_per_s=5.0, pitch_rate_per_s=7.0,
                   alpha_gain=3.0, lateral_gain=5.0, heave_gain=0.7, pitch_gain=0.2)
    if constrained:
        x = np.array(values[:7])
        ia, ea, ephi, etheta, da, dphi, dtheta = x
        z = [da + 2 * 1.1 * ea + 1.1 ** 2 * ia, dphi + 5.0 * ephi, dtheta + 7.0 * etheta]
        gains = [3.0, 0.7, 0.2]
    else:
        x = np.array(values)
        ia, ir, ea, er, ephi, etheta, da, dr, dphi, dtheta = x
        z = [da + 2 * 1.1 * ea + 1.1 ** 2 * ia, dr + 2 * 2.3 * er + 2.3 ** 2 * ir, dphi + 5.0 * ephi,
             dtheta + 7.0 * etheta]
        gains = [3.0, 5.0, 0.7, 0.2]
    expected = float(np.dot(gains, np.square(z)))
    assert x @ w.state_weight_matrix(constrained) @ x == pytest.approx(expected, rel=1e-12, abs=1e-12)


@pytest.mark.parametrize("constrained", [True, False])
def test_linearization_matches_finite_differences_of_the_model(constrained):
    """CasADi's exact F, G against central differences of swim_model's numeric shape dynamics."""
    from swim_model import VehicleModel, load_rig
    model = VehicleModel(load_rig(), constrained=constrained, lane_radius_m=0.43)
    rng = np.random.default_rng(7)
    nq, ny = model.nq, model.n_unactuated
    q = rng.normal(scale=0.4, size=nq)
    if not constrained:
        q[1] = 0.45
    qdot, u = rng.normal(scale=0.5, size=nq), rng.normal(scale=20.0, size=2)
    lin = linearize(model, q[None], qdot[None], u[None])
    f, g = lin.state_matrix[0], lin.input_matrix[0]
    step = 1e-6

    def accel(qq, qd, uu):
        return model.shape_dynamics(qq, qd, uu)[0]
    for j in range(nq):
        e = np.zeros(nq)
        e[j] = step
        np.testing.assert_allclose(f[ny + nq:, ny + j], (accel(q + e, qdot, u) - accel(q - e, qdot, u)) / (2 * step),
                                   rtol=1e-5, atol=1e-6)
        np.testing.assert_allclose(f[ny + nq:, ny + nq + j],
                                   (accel(q, qdot + e, u) - accel(q, qdot - e, u)) / (2 * step), rtol=1e-5, atol=1e-6)
    for j in range(2):
        e = np.zeros(2)
        e[j] = step
        np.testing.assert_allclose(g[ny + nq:, j], (accel(q, qdot, u + e) - accel(q, qdot, u - e)) / (2 * step),
                                   rtol=1e-5, atol=1e-6)
    # the kinematic blocks: d/dt int e_y = e_y, d/dt e_q = edot_q; u drives psiddot one to one
    np.testing.assert_array_equal(f[:ny, ny:ny + ny], np.eye(ny))
    np.testing.assert_array_equal(f[ny:ny + nq, ny + nq:], np.eye(nq))
    np.testing.assert_allclose(g[-2:], np.eye(2), atol=1e-12)


def test_terminal_weight_solves_the_shifted_algebraic_equation():
    rng = np.random.default_rng(1)
    f = rng.normal(size=(5, 5, 5)) * 0.3
    g = rng.normal(size=(5, 5, 2))
    w = LqrWeights(terminal_scale=0.5, terminal_margin_per_s=0.1)
    q, r = np.eye(5), np.eye(2)
    s = terminal_weight(Linearization(f, g), q, r, w)
    fa, ga = f.mean(0) - 0.1 * np.eye(5), g.mean(0)
    p = s / 0.5
    residual = p @ fa + fa.T @ p - p @ ga @ np.linalg.solve(r, ga.T) @ p + q
    assert np.abs(residual).max() < 1e-8
    assert np.linalg.eigvalsh(s).min() > 0.0


def test_weights_are_validated():
    with pytest.raises(ValueError, match="heave_gain"):
        LqrWeights(heave_gain=-1.0).validate()
    with pytest.raises(ValueError, match="pitch_input_weight"):
        LqrWeights(pitch_input_weight=float("nan")).validate()


def test_continued_terminal_is_one_integration_over_the_tiled_cycles():
    """The pass-by-pass backward sweep of a periodic F(t), G(t) equals one integration over the cycles tiled."""
    from swim_control.riccati import backward_transitions, continued_terminal
    rng = np.random.default_rng(5)
    f0, f1, g0 = rng.normal(size=(3, 3)), rng.normal(size=(3, 3)), rng.normal(size=(3, 1))
    period, samples, cycles = 0.7, 41, 5
    def periodic(t):
        phase = np.sin(2 * np.pi * t / period)[:, None, None]
        return Linearization(f0 + phase * f1, np.repeat(g0[None], len(t), 0) * (1.0 + 0.5 * phase))
    q, r, s = np.eye(3), np.array([[0.3]]), 0.1 * np.eye(3)
    one = np.linspace(0.0, period, samples)
    transitions = backward_transitions(one, periodic(one), q, r)
    continued = continued_terminal(transitions, period, s, lookahead_s=(cycles - 0.5) * period)
    tiled = np.linspace(0.0, (cycles + 1) * period, (cycles + 1) * (samples - 1) + 1)
    direct = solve_riccati(tiled, periodic(tiled), q, r, s)
    np.testing.assert_allclose(continued, direct[samples - 1], rtol=1e-7)


def test_cruise_gains_are_periodic_with_the_lookahead(model_for):
    """A cruise's P(T) is eq. 20 over cruise_lookahead_s more of the same cruise, so its gains nearly repeat
    from cycle to cycle; with the primitive's own horizon only, P(T) is S."""
    from swim_control.riccati import primitive_gains
    from swim_control.testing.strokes import StrokeSpec, make_stroke
    spec = StrokeSpec("free cruise", False, 0.43, 40)
    model = model_for(spec)
    stroke = make_stroke(model, spec, cycles=1, cycle_samples=True)
    periodic = stroke.gains.riccati
    weights = LqrWeights()
    q, r = weights.state_weight_matrix(False), weights.input_weight_matrix()
    terminal = terminal_weight(linearize(model, stroke.q, stroke.qdot, stroke.foil_acceleration), q, r, weights)
    plain = primitive_gains(model, stroke.time_s, stroke.q, stroke.qdot, stroke.foil_acceleration,
                            LqrWeights(cruise_lookahead_s=0.0), cycle_samples=len(stroke.time_s)).riccati
    assert np.abs(periodic[-1] - periodic[0]).max() < 0.05 * np.abs(periodic[0]).max()
    np.testing.assert_allclose(plain[-1], terminal, rtol=1e-12, atol=1e-12 * np.abs(terminal).max())
    assert np.abs(periodic[-1] - terminal).max() > 0.5 * np.abs(periodic[-1]).max()


@pytest.mark.parametrize("constrained", [False, True])
def test_a_primitive_ending_at_rest_weights_the_task_at_its_end(model_for, constrained):
    """ends_at_rest adds rest_lateral_terminal_weight to S's e_R entry for the free vehicle and
    rest_alpha_terminal_weight to S's e_alpha entry for the constrained one, and nothing else (the other weight does
    nothing to either). Without the flag the weights do nothing."""
    from swim_control.riccati import HUB_ERROR_INDEX_CONSTRAINED, LATERAL_ERROR_INDEX, error_state_size, primitive_gains
    from swim_control.testing.strokes import StrokeSpec, make_stroke
    spec = StrokeSpec("free stroke" if not constrained else "constrained stroke", constrained, 0.43, 40)
    model = model_for(spec)
    stroke = make_stroke(model, spec, cycles=1)
    args = (model, stroke.time_s, stroke.q, stroke.qdot, stroke.foil_acceleration)
    lateral_weight, alpha_weight = 1234.5, 678.9
    weights = LqrWeights(rest_lateral_terminal_weight=lateral_weight, rest_alpha_terminal_weight=alpha_weight)
    plain = primitive_gains(*args, LqrWeights()).riccati
    unflagged = primitive_gains(*args, weights).riccati
    at_rest = primitive_gains(*args, weights, ends_at_rest=True).riccati
    np.testing.assert_array_equal(unflagged, plain)
    added = at_rest[-1] - plain[-1]
    expected = np.zeros_like(added)
    if constrained:
        assert error_state_size(3, 1) == plain.shape[1] and HUB_ERROR_INDEX_CONSTRAINED == 1   # ny, then alpha
        index, weight = HUB_ERROR_INDEX_CONSTRAINED, alpha_weight
    else:
        assert error_state_size(4, 2) == plain.shape[1] and LATERAL_ERROR_INDEX == 2 + 1   # ny, then (alpha, R)
        index, weight = LATERAL_ERROR_INDEX, lateral_weight
    expected[index, index] = weight
    # the weight reaches back: the gains on the task's error grow before the end, most near it
    assert at_rest[-2, index, index] > plain[-2, index, index]
    np.testing.assert_allclose(added, expected, atol=1e-9 * weight)


@pytest.mark.parametrize("name", ["rest_lateral_terminal_weight", "rest_alpha_terminal_weight"])
def test_the_rest_weights_are_validated(name):
    LqrWeights(**{name: 0.0}).validate()
    with pytest.raises(ValueError, match=name):
        LqrWeights(**{name: -1.0}).validate()
    with pytest.raises(ValueError, match=name):
        LqrWeights(**{name: float("inf")}).validate()
