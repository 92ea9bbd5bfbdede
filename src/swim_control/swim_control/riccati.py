"""The time-varying LQ regulator about a planned trajectory (paper Sec. 6.1, eqs. 16-21).

The method: docs/model_and_method.md section 5.1.

Error state (n = ny + 2 nq: 10 for the free vehicle, 7 for the laterally constrained one)::

    x = ( int_0^t (y - y_des) dt,  q - q_des,  qdot - qdot_des ),   y = (alpha, R) or (alpha)

The integral error is taken with the same sign as the others (y - y_des) so that the paper's
z = edot + 2 l e + l^2 int e is one consistent PID-like combination. With u = psiddot as input and
qddot = f(q, qdot, u) the shape dynamics (eq. 14 solved for yddot, psiddot = u), the Jacobian
linearization about the plan is (eqs. 16-17)::

    xdot = F(t) x + G(t) (u - u_des),
    F = [[0, [I_ny 0], 0], [0, 0, I_nq], [0, df/dq, df/dqdot]],   G = [[0], [0], [df/du]]

and the finite-horizon LQ problem min int (du' R du + x' Q x) dt + x(T)' S x(T) has the gain
du = -R^-1 G' P x with P from the backward Riccati equation (eq. 20)::

    -Pdot = P F + F' P - P G R^-1 G' P + Q,     P(T) = S.

Q = Z' Gg Z (Sec. 7) with z = Z x = (edot_a + 2 l_a e_a + l_a^2 int e_a, [same for R],
edot_phi + l_phi e_phi, edot_theta + l_theta e_theta); Gg diagonal. S is the algebraic Riccati solution for
the time-averaged F, G, scaled (Sec. 7). p_alpha is a first integral of the ideal model
(docs/model_and_method.md P1), so its linearization is an uncontrollable mode with eigenvalue 0 and the averaged
pair is not stabilizable; the algebraic equation is therefore solved for F_avg - mu I, a small stability margin mu
(a named parameter).

P(t) is computed off-line, once per primitive: the Riccati equation is the linear-fractional image of the
linear Hamiltonian system d/dt (X, Y) = [[F, -G R^-1 G'], [-Q, -F']] (X, Y), P = Y X^-1, whose transition over
each interval between the plan's samples (F, G linear there) is one matrix exponential of a sixth-order
Magnus expansion. P is carried back interval by interval, so a periodic motion's cycle is computed once and
its map applied cycle after cycle.

With the circulatory flow model (swim_model.flow; docs/model_and_method.md section 5.2) the flow's n_lag = 2 lag
states z (m/s) are part of the plant: qddot = f(q, qdot, u, z) and zdot = g(q, qdot, z), driven by the motion
alone. The error state gains their errors, x = (int e_y, e_q, edot_q, e_z), e_z = z - z_des (n = ny + 2 nq + 2),
and the linearization their rows and columns::

    F = [[0, [I_ny 0], 0, 0], [0, 0, I_nq, 0], [0, df/dq, df/dqdot, df/dz], [0, dg/dq, dg/dqdot, dg/dz]],
    G = [[0], [0], [df/du], [0]]

Q has no weight on e_z (``LqrWeights.state_weight_matrix``); the gains still act on it, through df/dz.
"""
from __future__ import annotations

import dataclasses
from typing import Optional, cast

import casadi as ca
import numpy as np
import numpy.typing as npt
import scipy.linalg

from swim_control.errors import GainComputationError
from swim_model import VehicleModel

Array = npt.NDArray[np.float64]


@dataclasses.dataclass(frozen=True)
class LqrWeights:
    """The tuning of the LQ stage (Sec. 7): rates l, coordination gains Gg, input weights R, terminal S.

    The paper publishes the structure, not its numbers; every default here is assumed, tuned in simulation
    on the ideal model (swim_planner/test/test_closed_loop_ideal.py) for convergence within a few seconds without
    saturating the motors. The comment at each field gives its reason.

    Attributes
    ----------
    alpha_rate_per_s : float
        l_alpha, 1/s: the rate at which the hub's error is asked to decay.
    lateral_rate_per_s : float
        l_R, 1/s: the same for the carriage's lateral error (the free vehicle).
    heave_rate_per_s : float
        l_phi, 1/s.
    pitch_rate_per_s : float
        l_theta, 1/s.
    alpha_gain : float
        Gg[alpha], 1/(rad/s)^2 (z_alpha is a rate).
    lateral_gain : float
        Gg[R], 1/(m/s)^2.
    heave_gain : float
        Gg[phi], 1/(rad/s)^2.
    pitch_gain : float
        Gg[theta], 1/(rad/s)^2.
    heave_input_weight : float
        R[phi_ddot], 1/(rad/s^2)^2.
    pitch_input_weight : float
        R[theta_ddot], 1/(rad/s^2)^2.
    terminal_scale : float
        S = terminal_scale P_are (Sec. 7, "a scaled version"), dimensionless.
    terminal_margin_per_s : float
        mu, 1/s, >= 0: the shift of the averaged F that makes the pair stabilizable.
    cruise_lookahead_s : float
        s, >= 0: a cruise's gains are the Riccati solution of the cruise continued this long (0: its own horizon).
    rest_lateral_terminal_weight : float
        1/m^2, >= 0: added to S's e_R entry at the end of a free primitive that ends at rest.
    rest_alpha_terminal_weight : float
        1/rad^2, >= 0: added to S's e_alpha entry at the end of a constrained primitive that ends at rest.

    References
    ----------
    Saimek & Li 2004, Sec. 7 (the structure Q = Z' Gg Z and the scaled S); docs/model_and_method.md section 5.1.
    """

    alpha_rate_per_s: float = 1.5        # assumed: l_alpha, longitudinal error decays with ~0.7 s
    lateral_rate_per_s: float = 1.5      # assumed: l_R
    # l_phi, l_theta 4 and Gg[alpha] 30: the softer foil loops leave the slow alpha and R loops the torque they
    # need, so on the ideal model the lane change ends 0.1 mm from its lane with 0.7 % of its periods saturated;
    # stiffer foil loops (l 8, Gg[alpha] 100: 7 to 15 mm off, 6 % saturated) and stronger lateral terms saturated
    # the motors (swim_planner/test/test_closed_loop_ideal.py)
    heave_rate_per_s: float = 4.0        # assumed: l_phi
    pitch_rate_per_s: float = 4.0        # assumed: l_theta
    alpha_gain: float = 30.0             # assumed: Gg[alpha], 1/(rad/s)^2 (z_alpha is a rate)
    lateral_gain: float = 100.0          # assumed: Gg[R], 1/(m/s)^2
    heave_gain: float = 1.0              # assumed: Gg[phi], 1/(rad/s)^2
    pitch_gain: float = 1.0              # assumed: Gg[theta], 1/(rad/s)^2
    heave_input_weight: float = 1e-2     # assumed: R[phi_ddot], 1/(rad/s^2)^2 (1e-4 saturated the motors)
    pitch_input_weight: float = 1e-2     # assumed: R[theta_ddot], 1/(rad/s^2)^2
    terminal_scale: float = 0.01         # assumed: S = terminal_scale * P_are (Sec. 7 "a scaled version");
                                         # P_are of the averaged system is ~10x the mid-primitive P, and at
                                         # scale 1 the gains near each primitive's end saturate the motors
    terminal_margin_per_s: float = 0.05  # assumed: mu, the shift that makes the averaged pair stabilizable
    # A cruise is tiled and repeated, so its gains should not fade toward S at each 1 s cycle's end: they are the
    # Riccati solution of the cruise continued for this long (0: its own horizon only). Assumed: the paper's
    # longest maneuver, 30 s. On the ideal model the free lane keeping at E = 0.05 then ends 6 mm from its lane
    # and 2 mrad behind (24 mm and 69 mrad with each 1 s cycle's own horizon).
    cruise_lookahead_s: float = 30.0
    # Added to S's entry of the carriage's error e_R at the end of a free primitive that ends at rest (a decelerate:
    # the maneuver's end, where the task is judged), 1/m^2. The carriage has no motor: once the hub stops, the
    # foil's strokes no longer move it against the rails' breakaway friction and the tilt, so its error must be
    # gone before then. 0 (the default) keeps the paper's S; the circulatory library's value is its catalog's.
    rest_lateral_terminal_weight: float = 0.0
    # Added to S's entry of the hub's error e_alpha at the end of a constrained primitive that ends at rest, 1/rad^2:
    # the same reasoning for the hub, whose angle is the constrained task. As the hub comes to rest the strokes'
    # forces fade with its speed, and the water its braking strokes threw forward meets the foil; an error left for
    # those last moments stays. 0 (the default) keeps the paper's S. The free vehicle's end is judged by its lane,
    # and S's e_R entry serves it (a weight on its e_alpha too pulled the carriage off its lane).
    rest_alpha_terminal_weight: float = 0.0

    def validate(self) -> None:
        """Check the weights.

        Raises
        ------
        ValueError
            Unless every weight is positive and finite (the margin, the lookahead and the rest weights may be zero).
        """
        for field in dataclasses.fields(self):
            value = getattr(self, field.name)
            low_ok = (value >= 0.0 if field.name in ("terminal_margin_per_s", "cruise_lookahead_s",
                                                      "rest_lateral_terminal_weight",
                                                      "rest_alpha_terminal_weight") else value > 0.0)
            if not (isinstance(value, (int, float)) and np.isfinite(value) and low_ok):
                raise ValueError(f"LQR weight {field.name} must be a positive finite number, got {value!r}")

    def input_weight_matrix(self) -> Array:
        """The input weight R of the LQ cost.

        Returns
        -------
        (2, 2) array
            R = diag(heave_input_weight, pitch_input_weight), 1/(rad/s^2)^2, for u = (phi_ddot, theta_ddot).
        """
        return np.diag([self.heave_input_weight, self.pitch_input_weight])

    def state_weight_matrix(self, constrained: bool, n_lag: int = 0) -> Array:
        """The state weight Q = Z' Gg Z (Sec. 7) on x = (int e_y, e_q, edot_q[, e_z]).

        The flow's lag-state errors e_z (n_lag of them, the circulatory flow) get no weight: z is the flow's
        memory of the foil's motion, not a quantity the task asks to track, and the inputs cannot steer it apart
        from the motion (zdot = g(q, qdot, z) has no u). Its dynamics are stable (dg/dz < 0: a disturbance of
        the flow decays at the Wagner rates), so e_z -> 0 once the motion's errors do; weighting it would trade
        tracking error for a flow error no one asked to remove. Its effect on the motion is not ignored: F's
        df/dz columns make P, and the gains, act on e_z as the disturbance of the motion it is.

        Parameters
        ----------
        constrained : bool
            The laterally constrained vehicle (nq = 3, ny = 1), else the free one (nq = 4, ny = 2).
        n_lag : int, optional
            The flow's lag states: 0 (ideal flow) or 2 (circulatory).

        Returns
        -------
        (n, n) array
            Q, n = ny + 2 nq + n_lag, symmetric positive semi-definite.

        References
        ----------
        Saimek & Li 2004, Sec. 7; docs/model_and_method.md sections 5.1 and 5.5.
        """
        nq, ny = (3, 1) if constrained else (4, 2)
        n = error_state_size(nq, ny, n_lag)
        rates_y = [self.alpha_rate_per_s] if constrained else [self.alpha_rate_per_s, self.lateral_rate_per_s]
        gains = [self.alpha_gain] if constrained else [self.alpha_gain, self.lateral_gain]
        gains += [self.heave_gain, self.pitch_gain]
        z_map = np.zeros((nq, n))
        for i, rate in enumerate(rates_y):
            z_map[i, i] = rate ** 2                 # int e
            z_map[i, ny + i] = 2.0 * rate           # e
            z_map[i, ny + nq + i] = 1.0             # edot
        for j, rate in enumerate([self.heave_rate_per_s, self.pitch_rate_per_s]):
            row, coordinate = ny + j, nq - 2 + j
            z_map[row, ny + coordinate] = rate
            z_map[row, ny + nq + coordinate] = 1.0
        return z_map.T @ np.diag(gains) @ z_map


#: e_R's index in the free vehicle's error state (int e_alpha, int e_R, e_alpha, e_R, ...): ny = 2, then q = (alpha, R,
#: phi, theta)
LATERAL_ERROR_INDEX = 3
#: e_alpha's index in the constrained vehicle's error state (int e_alpha, e_alpha, e_phi, e_theta, ...): ny = 1
HUB_ERROR_INDEX_CONSTRAINED = 1


def error_state_size(nq: int, ny: int, n_lag: int = 0) -> int:
    """The size of the error state x = (int e_y, e_q, edot_q, e_z).

    Parameters
    ----------
    nq : int
        Generalized coordinates: 3 (constrained) or 4 (free).
    ny : int
        Unactuated coordinates with an integral error: 1 (constrained) or 2 (free).
    n_lag : int, optional
        The flow's lag states: 0 for the ideal flow, 2 for the circulatory one.

    Returns
    -------
    int
        n = ny + 2 nq + n_lag: integral errors of y, position errors, velocity errors and lag-state errors.
    """
    return ny + 2 * nq + n_lag


@dataclasses.dataclass(frozen=True)
class Linearization:
    """The linearization of the shape dynamics about a plan, at its samples (eqs. 16-17).

    Attributes
    ----------
    state_matrix : (N, n, n) array
        F(t_k), n = error_state_size(nq, ny, n_lag); 1/s and 1/s^2 by block.
    input_matrix : (N, n, 2) array
        G(t_k): nonzero on the velocity rows only (df/du, dimensionless).
    """

    state_matrix: Array
    input_matrix: Array


def _jacobian_function(model: VehicleModel) -> ca.Function:
    s = model.symbolic
    qddot, _ = s.functions["shape_dynamics"](s.q, s.qdot, s.u)
    outputs = [ca.jacobian(qddot, s.q), ca.jacobian(qddot, s.qdot), ca.jacobian(qddot, s.u)]
    return ca.Function("shape_jacobians", [s.q, s.qdot, s.u], outputs)


def _lag_jacobian_function(model: VehicleModel) -> ca.Function:
    """(q, qdot, u, z) -> the Jacobians of (f, g) = (qddot, zdot) in q, qdot, z (rows: f then g) and of f in u."""
    s = model.symbolic
    lag = s.lag
    assert lag is not None   # called for a circulatory model only (linearize checks)
    qddot, _ = s.functions["shape_dynamics"](s.q, s.qdot, s.u, lag)
    rates = ca.vertcat(qddot, s.functions["lag_rate"](s.q, s.qdot, lag))
    outputs = [ca.jacobian(rates, s.q), ca.jacobian(rates, s.qdot), ca.jacobian(rates, lag),
               ca.jacobian(qddot, s.u)]
    return ca.Function("shape_lag_jacobians", [s.q, s.qdot, s.u, lag], outputs)


def linearize(model: VehicleModel, q: Array, qdot: Array, foil_acceleration: Array,
              lag: Optional[Array] = None) -> Linearization:
    """F and G of eq. 16 along a trajectory, by CasADi's exact derivatives (no finite differences).

    Parameters
    ----------
    model : VehicleModel
        The vehicle, ideal or circulatory flow.
    q : (N, nq) array
        Planned positions, rad and m.
    qdot : (N, nq) array
        Planned velocities, rad/s and m/s.
    foil_acceleration : (N, 2) array
        Planned u = psiddot (heave, pitch), rad/s^2.
    lag : (N, n_lag) array, optional
        The plan's lag states, m/s: required by a circulatory model (model.n_lag = 2), refused by the ideal one.

    Returns
    -------
    Linearization
        F (N, n, n) and G (N, n, 2), n = error_state_size(nq, ny, n_lag) (module docstring).

    Raises
    ------
    GainComputationError
        If lag is given to an ideal model, missing for a circulatory one, or of the wrong shape.

    References
    ----------
    Saimek & Li 2004, Sec. 6.1, eqs. 16-17; docs/model_and_method.md sections 5.1 and 5.5.
    """
    samples, nq, ny, n_lag = len(q), model.nq, model.n_unactuated, model.n_lag
    if (lag is None) != (n_lag == 0):
        raise GainComputationError(f"linearize: the {model.flow} flow model "
                                   f"{'needs the plan' if n_lag else 'takes no'} lag states")
    n = error_state_size(nq, ny, n_lag)
    rows = nq + n_lag                                     # the rows of (f, g)
    if lag is None:
        jacobians = _jacobian_function(model).map(samples)
        d_q, d_qdot, d_u = (np.asarray(a, dtype=float) for a in jacobians(q.T, qdot.T, foil_acceleration.T))
    else:
        lag = np.asarray(lag, dtype=float)
        if lag.shape != (samples, n_lag):
            raise GainComputationError(f"linearize: lag must have shape {(samples, n_lag)}, got {lag.shape}")
        jacobians = _lag_jacobian_function(model).map(samples)
        d_q, d_qdot, d_z, d_u = (np.asarray(a, dtype=float)
                                 for a in jacobians(q.T, qdot.T, foil_acceleration.T, lag.T))
        d_z = d_z.reshape(rows, samples, n_lag).transpose(1, 0, 2)
    # map() stacks the per-sample rows x m blocks side by side: (rows, samples * m)
    d_q = d_q.reshape(rows, samples, nq).transpose(1, 0, 2)
    d_qdot = d_qdot.reshape(rows, samples, nq).transpose(1, 0, 2)
    d_u = d_u.reshape(nq, samples, 2).transpose(1, 0, 2)
    state = np.zeros((samples, n, n))
    state[:, np.arange(ny), ny + np.arange(ny)] = 1.0                    # d/dt int e_y = e_y
    state[:, ny + np.arange(nq), ny + nq + np.arange(nq)] = 1.0          # d/dt e_q = edot_q
    state[:, ny + nq:, ny:ny + nq] = d_q
    state[:, ny + nq:, ny + nq:ny + 2 * nq] = d_qdot
    if lag is not None:
        state[:, ny + nq:, ny + 2 * nq:] = d_z                           # df/dz, dg/dz
    inputs = np.zeros((samples, n, 2))
    inputs[:, ny + nq:ny + 2 * nq, :] = d_u
    return Linearization(state, inputs)


def terminal_weight(linearization: Linearization, state_weight: Array, input_weight: Array,
                    weights: LqrWeights) -> Array:
    """The terminal weight S: the scaled algebraic Riccati solution for the time-averaged F, G.

    Parameters
    ----------
    linearization : Linearization
        F (N, n, n) and G (N, n, 2) along the plan; their means over the samples are used.
    state_weight, input_weight : (n, n) and (2, 2) array
        Q and R (1/(rad/s^2)^2).
    weights : LqrWeights
        Gives the scale and the margin mu by which F_avg is shifted (F_avg - mu I).

    Returns
    -------
    (n, n) array
        S = terminal_scale P_are, symmetric.

    Raises
    ------
    GainComputationError
        If the algebraic Riccati equation has no solution for the shifted averaged pair.

    References
    ----------
    Saimek & Li 2004, Sec. 7 ("a scaled version" of the algebraic solution); docs/model_and_method.md section 5.1.
    """
    state_avg = linearization.state_matrix.mean(axis=0)
    input_avg = linearization.input_matrix.mean(axis=0)
    shifted = state_avg - weights.terminal_margin_per_s * np.eye(len(state_avg))
    try:
        solution: Array = scipy.linalg.solve_continuous_are(shifted, input_avg, state_weight, input_weight)
    except (np.linalg.LinAlgError, ValueError) as err:
        raise GainComputationError(f"no algebraic Riccati solution for the averaged linearization: {err}") from err
    return weights.terminal_scale * 0.5 * (solution + solution.T)


# The sixth-order Magnus integrator with three Gauss-Legendre nodes per step (Blanes, Casas & Ros, "Improved
# high order integrators based on the Magnus expansion", BIT 40(3), 434-450, 2000; also Blanes et al., "The
# Magnus expansion and some of its applications", Physics Reports 470, 2009, Sec. 5).
_GAUSS_NODES = np.array([0.5 - np.sqrt(15.0) / 10.0, 0.5, 0.5 + np.sqrt(15.0) / 10.0])
# Magnus steps per plan interval. Assumed from measurement: with 2, P(t) of every primitive of the shipped
# library is within 5e-6 of eq. 20 integrated by DOP853 at rtol 1e-10 (1 step: 3e-4, the free accelerates);
# swim_planner/test/test_gains.py checks the library against its stored gains.
MAGNUS_STEPS_PER_INTERVAL = 2
# A periodic motion's cycle is carried as few transitions as this bound allows (merge_transitions): 1e3 keeps
# each map's condition number at most 1e6, its rounding error near 1e-10, far below the Magnus error.
MERGED_TRANSITION_MAX_NORM = 1e3


def _hamiltonian(state_matrix: Array, input_matrix: Array, state_weight: Array, input_inverse: Array) -> Array:
    """[[F, -G R^-1 G'], [-Q, -F']], (..., 2n, 2n), for F (..., n, n) and G (..., n, 2)."""
    n = state_matrix.shape[-1]
    hamiltonian = np.empty(state_matrix.shape[:-2] + (2 * n, 2 * n))
    hamiltonian[..., :n, :n] = state_matrix
    hamiltonian[..., :n, n:] = -np.einsum("...ia,ab,...jb->...ij", input_matrix, input_inverse, input_matrix)
    hamiltonian[..., n:, :n] = -state_weight
    hamiltonian[..., n:, n:] = -np.swapaxes(state_matrix, -1, -2)
    return hamiltonian


def _commutator(a: Array, b: Array) -> Array:
    return a @ b - b @ a


def backward_transitions(time_s: Array, linearization: Linearization, state_weight: Array, input_weight: Array,
                         steps_per_interval: int = MAGNUS_STEPS_PER_INTERVAL) -> Array:
    """The Hamiltonian system's transition over each interval between the plan's samples, backward.

    With X(T) = I, Y(T) = S and d/dt (X, Y) = H(t) (X, Y), H = [[F, -G R^-1 G'], [-Q, -F']], P = Y X^-1 solves
    eq. 20; so P at a step's start is (Psi21 + Psi22 P)(Psi11 + Psi12 P)^-1 of P at its end. F and G are taken
    linear between the plan's samples.

    Parameters
    ----------
    time_s : (N,) array
        The plan's sample times, s, strictly increasing.
    linearization : Linearization
        F (N, n, n) and G (N, n, 2) at those samples.
    state_weight : (n, n) array
        Q.
    input_weight : (2, 2) array
        R, 1/(rad/s^2)^2.
    steps_per_interval : int, optional
        Sixth-order Magnus steps per interval (``MAGNUS_STEPS_PER_INTERVAL``).

    Returns
    -------
    (N - 1, 2n, 2n) array
        Psi_k, from the end of interval k back to its start, in time order.

    Raises
    ------
    GainComputationError
        If the time grid has fewer than two samples or is not strictly increasing.

    References
    ----------
    Saimek & Li 2004, eq. 20; Blanes, Casas & Ros, BIT 40(3), 2000 (the Magnus integrator).
    """
    time_s = np.asarray(time_s, dtype=float)
    if time_s.ndim != 1 or len(time_s) < 2 or np.any(np.diff(time_s) <= 0.0):
        raise GainComputationError("the time grid must be strictly increasing with at least two samples")
    state_matrix, input_matrix = linearization.state_matrix, linearization.input_matrix
    # the fraction of each interval at every Magnus step's three nodes: (steps, 3)
    fraction = (np.arange(steps_per_interval)[:, None] + _GAUSS_NODES[None, :]) / steps_per_interval
    weight = fraction[None, :, :, None, None]
    f_nodes = state_matrix[:-1, None, None] + weight * (state_matrix[1:] - state_matrix[:-1])[:, None, None]
    g_nodes = input_matrix[:-1, None, None] + weight * (input_matrix[1:] - input_matrix[:-1])[:, None, None]
    h_nodes = _hamiltonian(f_nodes, g_nodes, state_weight, cast(Array, np.linalg.inv(input_weight)))
    step = (np.diff(time_s) / steps_per_interval)[:, None, None, None]
    a1 = step * h_nodes[:, :, 1]
    a2 = np.sqrt(15.0) / 3.0 * step * (h_nodes[:, :, 2] - h_nodes[:, :, 0])
    a3 = 10.0 / 3.0 * step * (h_nodes[:, :, 2] - 2.0 * h_nodes[:, :, 1] + h_nodes[:, :, 0])
    c1 = _commutator(a1, a2)
    c2 = -_commutator(a1, 2.0 * a3 + c1) / 60.0
    omega = a1 + a3 / 12.0 + _commutator(-20.0 * a1 - a3 + c1, a2 + c2) / 240.0
    steps: Array = scipy.linalg.expm(-omega)       # (N - 1, steps_per_interval, 2n, 2n)
    transitions = steps[:, 0]
    for j in range(1, steps_per_interval):
        transitions = transitions @ steps[:, j]
    return transitions


def merge_transitions(transitions: Array, max_norm: float = MERGED_TRANSITION_MAX_NORM) -> list[Array]:
    """The same span in fewer transitions: consecutive ones multiplied while the product stays small.

    A Hamiltonian transition is symplectic, so its condition number is its 2-norm squared: the bound keeps each
    map's rounding error below max_norm^2 times the machine epsilon.

    Parameters
    ----------
    transitions : (K, 2n, 2n) array
        Backward transitions in time order (``backward_transitions``).
    max_norm : float, optional
        The largest Frobenius norm of a merged product.

    Returns
    -------
    list of (2n, 2n) array
        The merged transitions, in time order, spanning the same interval.
    """
    merged = [transitions[-1]]
    for psi in transitions[-2::-1]:
        product = psi @ merged[-1]
        if np.linalg.norm(product) <= max_norm:
            merged[-1] = product
        else:
            merged.append(psi)
    return merged[::-1]


def sweep_backward(transitions: Array | list[Array], terminal: Array) -> Array:
    """Carry P backward through transitions as linear-fractional maps, from P = terminal at the last one.

    Parameters
    ----------
    transitions : (K, 2n, 2n) array or list of (2n, 2n) array
        Backward transitions in time order.
    terminal : (n, n) array
        P at the end of the last transition.

    Returns
    -------
    (K + 1, n, n) array
        P at every transition's ends, symmetric.

    Raises
    ------
    GainComputationError
        If the solution is not finite.
    """
    n = terminal.shape[0]
    riccati = np.empty((len(transitions) + 1, n, n))
    riccati[-1] = p = terminal
    for j in range(len(transitions) - 1, -1, -1):
        psi = transitions[j]
        x = psi[:n, :n] + psi[:n, n:] @ p
        y = psi[n:, :n] + psi[n:, n:] @ p
        p = np.linalg.solve(x.T, y.T)        # (Y X^-1)' = X'^-1 Y'; P is symmetric
        p = 0.5 * (p + p.T)
        riccati[j] = p
    if not np.all(np.isfinite(riccati)):
        raise GainComputationError("the Riccati solution is not finite")
    return riccati


def solve_riccati(time_s: Array, linearization: Linearization, state_weight: Array, input_weight: Array,
                  terminal: Array) -> Array:
    """P(t_k): eq. 20 solved backward from P(T) = S, F and G linear between samples.

    Each interval's Hamiltonian transition is found by sixth-order Magnus steps (``backward_transitions``)
    and P is carried back through them as a linear-fractional map (``sweep_backward``).

    Parameters
    ----------
    time_s, linearization, state_weight, input_weight
        The sample times (N,), s, F and G, Q and R, as for ``backward_transitions``.
    terminal : (n, n) array
        S = P(T).

    Returns
    -------
    (N, n, n) array
        P(t_k), symmetric.

    Raises
    ------
    GainComputationError
        If the time grid is bad or the solution is not finite.

    References
    ----------
    Saimek & Li 2004, Sec. 6.1, eq. 20; docs/model_and_method.md section 5.1.
    """
    transitions = backward_transitions(time_s, linearization, state_weight, input_weight)
    return sweep_backward(transitions, terminal)


def continued_terminal(cycle_transitions: Array, cycle_duration_s: float, terminal: Array,
                       lookahead_s: float) -> Array:
    """P at the start of a periodic motion's cycle when the motion continues for lookahead_s more.

    Eq. 20 over the one cycle, backward, again and again, for whole cycles (rounded up), from P = terminal.

    Parameters
    ----------
    cycle_transitions : (K, 2n, 2n) array
        The cycle's ``backward_transitions``; merged once, so that each pass is only a few linear-fractional maps.
    cycle_duration_s : float
        The cycle's period, s.
    terminal : (n, n) array
        P at the end of the continued motion.
    lookahead_s : float
        How long the motion continues, s.

    Returns
    -------
    (n, n) array
        P at the cycle's start.
    """
    passes = int(np.ceil(lookahead_s / cycle_duration_s - 1e-9))
    merged = merge_transitions(cycle_transitions)
    for _ in range(passes):
        terminal = sweep_backward(merged, terminal)[0]
    return terminal


@dataclasses.dataclass
class TrackingGains:
    """What the tracker needs along one primitive, at its samples: P(t) and G(t)' P(t).

    Attributes
    ----------
    riccati : (N, n, n) array
        P(t_k) of eq. 20.
    riccati_input_gain : (N, 2, n) array
        G'P: du = -R^-1 G'P x and s = Mio^-1 G'P x (eq. 24).
    """

    riccati: Array              # P, (N, n, n)
    riccati_input_gain: Array   # G' P, (N, 2, n): du = -R^-1 G'P x and s = Mio^-1 G'P x (eq. 24)


def primitive_gains(model: VehicleModel, time_s: Array, q: Array, qdot: Array, foil_acceleration: Array,
                    weights: Optional[LqrWeights] = None, cycle_samples: Optional[int] = None,
                    lag: Optional[Array] = None, ends_at_rest: bool = False) -> TrackingGains:
    """P(t) and G'P along a planned trajectory: the tracking gains of one primitive.

    Parameters
    ----------
    model : VehicleModel
        The vehicle the primitive was planned on.
    time_s : (N,) array
        Sample times, s, strictly increasing.
    q : (N, nq) array
        Planned positions, rad and m.
    qdot : (N, nq) array
        Planned velocities, rad/s and m/s.
    foil_acceleration : (N, 2) array
        Planned u = psiddot, rad/s^2.
    weights : LqrWeights, optional
        The LQ weights (None: the defaults).
    cycle_samples : int, optional
        A cruise, whose first cycle_samples samples are one period of it (the rest are copies): P(T) is then not
        S but the solution of eq. 20 over ``weights.cruise_lookahead_s`` more seconds of the same cruise, found by
        carrying P back through one cycle again and again (F, G are periodic: alpha does not enter them, Prop. 1).
    lag : (N, n_lag) array, optional
        The plan's lag states, m/s, for a circulatory model (None for the ideal one); the gains are then on the
        extended error state, n = ny + 2 nq + n_lag (module docstring).
    ends_at_rest : bool, optional
        The primitive ends the vehicle at rest (a decelerate); S then gains ``weights.rest_lateral_terminal_weight``
        on e_R, the carriage's position error, for the free vehicle, and ``weights.rest_alpha_terminal_weight`` on
        e_alpha, the hub's, for the constrained one.

    Returns
    -------
    TrackingGains
        P (N, n, n) and G'P (N, 2, n) at the samples.

    Raises
    ------
    ValueError
        If a weight is invalid.
    GainComputationError
        If the lag states do not fit the model, or no Riccati solution exists.

    References
    ----------
    Saimek & Li 2004, Sec. 6.1, eqs. 16-21, and Sec. 7; docs/model_and_method.md section 5.1.
    """
    weights = weights or LqrWeights()
    weights.validate()
    linearization = linearize(model, q, qdot, foil_acceleration, lag)
    state_weight = weights.state_weight_matrix(model.constrained, model.n_lag)
    input_weight = weights.input_weight_matrix()
    terminal = terminal_weight(linearization, state_weight, input_weight, weights)
    transitions = backward_transitions(time_s, linearization, state_weight, input_weight)
    if cycle_samples is not None:
        terminal = continued_terminal(transitions[:cycle_samples - 1], time_s[cycle_samples - 1] - time_s[0],
                                      terminal, weights.cruise_lookahead_s)
    if ends_at_rest:
        terminal = terminal.copy()
        if model.constrained:
            terminal[HUB_ERROR_INDEX_CONSTRAINED, HUB_ERROR_INDEX_CONSTRAINED] += weights.rest_alpha_terminal_weight
        else:
            terminal[LATERAL_ERROR_INDEX, LATERAL_ERROR_INDEX] += weights.rest_lateral_terminal_weight
    riccati = sweep_backward(transitions, terminal)
    riccati_input_gain = np.einsum("kni,knm->kim", linearization.input_matrix, riccati)
    return TrackingGains(riccati=riccati, riccati_input_gain=riccati_input_gain)
