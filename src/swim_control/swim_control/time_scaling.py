"""Time scaling of the LQ tracker (paper Sec. 6.4, Theorem 1, eqs. 26-33; docs/model_and_method.md section 5.4).

A primitive run lambda times faster, q(t) -> q(lambda t), is linearized to F_l(t) = lambda Gamma^-1 F(lambda t)
Gamma and G_l(t) = G(lambda t) (eq. 28), with Gamma(lambda) = diag(lambda^2 I_ny, lambda I_nq, I_nq) on
x = (int e_y, e_q, edot_q) (eq. 27). Substituting P_l(t) = Gamma P(lambda t) Gamma into the Riccati equation of
the scaled system, -Pdot_l = lambda Gamma (-Pdot)(lambda t) Gamma, shows that P_l solves it for the weights

    Q_l = lambda Gamma Q Gamma,   R_l = R / lambda,   S_l = Gamma S Gamma.

The paper's eq. 30 prints Q_l = Gamma Q Gamma; the factor lambda is needed for the substitution to close
(swim_control/test/test_time_scaling.py: the printed form misses by the factor, ours agrees to 1e-6).
With Q = Z' Gg Z it is
the same structure with every rate l scaled to lambda l and Gg to lambda Gg: a faster plan is tracked with
proportionally faster error dynamics. The scaled control law is eq. 33:

    u(t) = lambda^2 u_des(lambda t) - lambda R^-1 G(lambda t)' Gamma P(lambda t) Gamma x(t),

and since G has rows only on the velocity block, where Gamma is I, G' Gamma P Gamma = (G'P)(lambda t) Gamma.

The circulatory flow's lag states (swim_model.flow) extend x by e_z = z - z_des (n_lag = 2, m/s). Their block of
Gamma is I_n_lag, derived, not assumed. P3 holds with z_l(t) = lambda z(lambda t) (docs/flow_model.md,
"Smoothness and P3"): f(q, lambda qdot, lambda^2 u, lambda z) = lambda^2 f and g(q, lambda qdot, lambda z) =
lambda^2 g for qddot = f(q, qdot, u, z), zdot = g(q, qdot, z). An error motion of the nominal plan, run lambda
times faster, is x_l(t) = Lambda x(lambda t) with Lambda = diag(I/lambda, I, lambda I, lambda I) (the integral
loses a lambda, the rates and lag states gain one), so Gamma = lambda Lambda^-1 = diag(lambda^2, lambda, 1, 1).
Entry by entry, F_l = lambda Gamma^-1 F(lambda t) Gamma is what the homogeneity gives: the lag rows of F_l are
(lambda^2 dg/dq, lambda dg/dqdot, lambda dg/dz), the qddot rows' lag columns lambda df/dz, each a velocity-degree
count of the derivative; G has no lag rows, so G_l = G(lambda t) and eq. 33 keep their form. The zero weight on
e_z stays zero under Q_l = lambda Gamma Q Gamma.
"""
from __future__ import annotations

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]


def scaling_matrix(time_scale: float, ny: int, nq: int, n_lag: int = 0) -> Array:
    """Gamma(lambda) of eq. 27: the time scaling's change of the error state's coordinates.

    Parameters
    ----------
    time_scale : float
        lambda > 0 (1: the plan as stored; > 1 runs faster).
    ny : int
        Unactuated coordinates y with an integral error: 1 (constrained) or 2 (free).
    nq : int
        Generalized coordinates q: 3 (constrained) or 4 (free).
    n_lag : int, optional
        The flow's lag states at the end of x: 0 (ideal flow) or 2 (circulatory).

    Returns
    -------
    (n, n) array
        diag(lambda^2 I_ny, lambda I_nq, I_nq, I_n_lag), n = ny + 2 nq + n_lag; dimensionless.

    References
    ----------
    Saimek & Li 2004, Sec. 6.4, eq. 27; the lag block: docs/model_and_method.md section 5.5.
    """
    return np.diag(scaling_diagonal(time_scale, ny, nq, n_lag))


def scaling_diagonal(time_scale: float | Array, ny: int, nq: int, n_lag: int = 0) -> Array:
    """The diagonal of Gamma(lambda) (eq. 27), for one lambda or for one per sample.

    Parameters
    ----------
    time_scale : float or (N,) array
        lambda > 0, one or one per row.
    ny, nq, n_lag : int
        The error state's blocks, as for ``scaling_matrix`` (n_lag optional, 0 by default).

    Returns
    -------
    (n,) or (N, n) array
        (lambda^2 [ny], lambda [nq], 1 [nq], 1 [n_lag]), n = ny + 2 nq + n_lag; one row per lambda for an array.
    """
    scale = np.asarray(time_scale, dtype=float)[..., None]
    return np.concatenate([np.repeat(scale ** 2, ny, -1), np.repeat(scale, nq, -1),
                           np.ones(scale.shape[:-1] + (nq + n_lag,))], axis=-1)


def scale_riccati(riccati: Array, time_scale: float, ny: int, nq: int, n_lag: int = 0) -> Array:
    """P_l at the scaled sample times t_k / lambda: Gamma P(t_k) Gamma (Theorem 1).

    Parameters
    ----------
    riccati : (N, n, n) array
        P(t_k) of the plan at lambda = 1 (eq. 20), in the units of x' P x (the cost's).
    time_scale : float
        lambda > 0.
    ny, nq, n_lag : int
        The error state's blocks, as for ``scaling_matrix`` (n_lag optional, 0 by default).

    Returns
    -------
    (N, n, n) array
        P_l(t_k / lambda) = Gamma P(t_k) Gamma.

    References
    ----------
    Saimek & Li 2004, Sec. 6.4, Theorem 1, eqs. 26-30; docs/model_and_method.md section 5.4.
    """
    gamma = scaling_diagonal(time_scale, ny, nq, n_lag)
    return riccati * gamma[:, None] * gamma[None, :]


def scale_weights(state_weight: Array, input_weight: Array, terminal: Array, time_scale: float, ny: int,
                  nq: int, n_lag: int = 0) -> tuple[Array, Array, Array]:
    """The weights (Q_l, R_l, S_l) whose Riccati solution is Gamma P(lambda t) Gamma (module docstring).

    Parameters
    ----------
    state_weight : (n, n) array
        Q of the plan at lambda = 1.
    input_weight : (2, 2) array
        R, 1/(rad/s^2)^2.
    terminal : (n, n) array
        S.
    time_scale : float
        lambda > 0, the one the weights are scaled to.
    ny, nq, n_lag : int
        The sizes of x's blocks, as for ``scaling_matrix`` (n_lag optional, 0 by default).

    Returns
    -------
    state_weight : (n, n) array
        Q_l = lambda Gamma Q Gamma.
    input_weight : (2, 2) array
        R_l = R / lambda.
    terminal : (n, n) array
        S_l = Gamma S Gamma.

    References
    ----------
    Saimek & Li 2004, Sec. 6.4, eq. 30 (printed without the factor lambda on Q_l; docs/model_and_method.md
    section 5.4 gives why it is needed).
    """
    gamma = scaling_diagonal(time_scale, ny, nq, n_lag)
    outer = gamma[:, None] * gamma[None, :]
    return time_scale * state_weight * outer, input_weight / time_scale, terminal * outer


def lqr_gain_from(riccati_input_gain: Array, input_weight_diagonal: Array) -> Array:
    """K = R^-1 G'P, the LQ gains of a plan at lambda = 1, which ``retime_feedback`` scales.

    Parameters
    ----------
    riccati_input_gain : (N, 2, n) array
        G'P at each sample.
    input_weight_diagonal : (2,) array_like
        R's diagonal (heave, pitch), 1/(rad/s^2)^2.

    Returns
    -------
    (N, 2, n) array
        K, so that u = u_des - K x (1/s^2 and 1/s units by block of x).

    References
    ----------
    Saimek & Li 2004, Sec. 6.1, eq. 19 (eq. 33 at lambda = 1).
    """
    return riccati_input_gain * (1.0 / np.asarray(input_weight_diagonal, dtype=float))[None, :, None]


def retime_feedback(lqr_gain: Array, riccati_input_gain: Array, time_scale: float | Array, ny: int,
                    nq: int, n_lag: int = 0) -> tuple[Array, Array]:
    """The gains of eq. 33 of a plan made at lambda = 1, rescaled to lambda per sample.

    Scalings compose: rescaling by lambda2 gains already at lambda1 gives those at lambda1 lambda2.

    Parameters
    ----------
    lqr_gain : (N, 2, n) array
        K of the plan at its current time scale.
    riccati_input_gain : (N, 2, n) array
        G'P of the plan at its current time scale.
    time_scale : float or (N,) array
        lambda > 0, one for all samples or one per sample.
    ny, nq : int
        The unactuated and all generalized coordinates: 1 and 3 (constrained) or 2 and 4 (free).
    n_lag : int, optional
        The flow's lag states at the end of x: 0 (the ideal flow) or 2 (the circulatory one).

    Returns
    -------
    lqr_gain : (N, 2, n) array
        K = lambda R^-1 (G'P) Gamma, so that u = lambda^2 u_des - K x (1/s^2 and 1/s units by block).
    riccati_input_gain : (N, 2, n) array
        (G'P) Gamma = G_l' P_l, so that s = Mio^-1 G_l' P_l x (eq. 24).

    References
    ----------
    Saimek & Li 2004, Sec. 6.4, Theorem 1, eq. 33; docs/model_and_method.md section 5.4.
    """
    scale = np.broadcast_to(np.asarray(time_scale, dtype=float), lqr_gain.shape[:1])
    gamma = scaling_diagonal(scale, ny, nq, n_lag)[:, None, :]
    return lqr_gain * gamma * scale[:, None, None], riccati_input_gain * gamma
