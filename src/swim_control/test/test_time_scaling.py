"""Theorem 1 (paper Sec. 6.4) numerically: the scaled stored P against a direct solve of the scaled system."""
import numpy as np
import pytest

from swim_control.riccati import LqrWeights, linearize, solve_riccati, terminal_weight
from swim_control.time_scaling import (
    lqr_gain_from,
    retime_feedback,
    scale_riccati,
    scale_weights,
    scaling_diagonal,
    scaling_matrix,
)

PRIMITIVES = ["constrained", "free"]


def _direct_scaled_riccati(model, primitive, weights, time_scale, paper_printed_q=False):
    """Linearize the time-scaled plan itself (q(lambda t), lambda qdot, lambda^2 u) and solve its Riccati
    equation with the weights of eq. 30, independently of the stored P."""
    ny, nq = model.n_unactuated, model.nq
    q, r = weights.state_weight_matrix(model.constrained), weights.input_weight_matrix()
    lin = linearize(model, primitive.q, primitive.qdot, primitive.foil_acceleration)
    s = terminal_weight(lin, q, r, weights)
    q_l, r_l, s_l = scale_weights(q, r, s, time_scale, ny, nq)
    if paper_printed_q:
        q_l = q_l / time_scale           # eq. 30 as printed: Gamma Q Gamma
    scaled = linearize(model, primitive.q, primitive.qdot * time_scale,
                       primitive.foil_acceleration * time_scale ** 2)
    return solve_riccati(primitive.time_s / time_scale, scaled, q_l, r_l, s_l)


@pytest.mark.parametrize("primitive_id", PRIMITIVES)
@pytest.mark.parametrize("time_scale", [0.8, 1.2, 1.67])
def test_theorem_1_scaled_stored_riccati_equals_the_direct_solution(strokes, model_for, primitive_id, time_scale):
    primitive = strokes[primitive_id]
    model = model_for(primitive.spec)
    stored = primitive.gains.riccati
    predicted = scale_riccati(stored, time_scale, model.n_unactuated, model.nq)
    direct = _direct_scaled_riccati(model, primitive, LqrWeights(), time_scale)
    relative = np.abs(direct - predicted).max() / np.abs(direct).max()
    assert relative < 1e-6


def test_theorem_1_needs_the_lambda_factor_on_q(strokes, model_for):
    """Eq. 30 as extracted prints Q_l = Gamma Q Gamma; that P_l does not match: the factor lambda is needed."""
    primitive = strokes[PRIMITIVES[0]]
    model = model_for(primitive.spec)
    predicted = scale_riccati(primitive.gains.riccati, 1.2, model.n_unactuated, model.nq)
    printed = _direct_scaled_riccati(model, primitive, LqrWeights(), 1.2, paper_printed_q=True)
    assert np.abs(printed - predicted).max() / np.abs(printed).max() > 1e-3


def test_eq_33_gains_from_the_scaled_riccati():
    """K = R_l^-1 G_l' P_l and G_l' P_l: the lambda = 1 gains (lqr_gain_from) re-timed to lambda (retime_feedback)
    against the matrices built explicitly."""
    rng = np.random.default_rng(0)
    ny, nq, lam = 2, 4, 1.3
    n = ny + 2 * nq
    a = rng.normal(size=(3, n, n))
    p = a @ a.transpose(0, 2, 1)
    g = np.zeros((3, n, 2))
    g[:, ny + nq:, :] = rng.normal(size=(3, nq, 2))
    r = np.array([0.3, 0.05])
    gamma = scaling_matrix(lam, ny, nq)
    riccati_input_gain = np.einsum("kni,knm->kim", g, p)
    unscaled = lqr_gain_from(riccati_input_gain, r)
    lqr, scaled_input_gain = retime_feedback(unscaled, riccati_input_gain, lam, ny, nq)
    for k in range(3):
        np.testing.assert_allclose(unscaled[k], np.linalg.inv(np.diag(r)) @ g[k].T @ p[k], rtol=1e-12)
        p_l = gamma @ p[k] @ gamma
        np.testing.assert_allclose(scaled_input_gain[k], g[k].T @ p_l, rtol=1e-12)
        np.testing.assert_allclose(lqr[k], np.linalg.inv(np.diag(r) / lam) @ g[k].T @ p_l, rtol=1e-12)
    # lambda per sample gives the same gains as the scalar
    lqr_r, scaled_r = retime_feedback(unscaled, riccati_input_gain, np.full(3, lam), ny, nq)
    np.testing.assert_array_equal(lqr_r, lqr)
    np.testing.assert_array_equal(scaled_r, scaled_input_gain)
    np.testing.assert_array_equal(scaling_diagonal(lam, ny, nq), np.diag(gamma))
