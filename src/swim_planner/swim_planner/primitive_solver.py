"""Motion primitives solved by optimal control (paper Secs. 4-5; docs/model_and_method.md section 3).

The data model (PrimitiveSpec, Primitive, ...) is swim_planner.primitives; this module is its optimizer.

Every primitive solves, for the free or the laterally constrained vehicle, with state x = (q, qdot) and
the foil accelerations u = psiddot as input (the planning input of eq. 16):

    maximize  s alpha(Tf) - int_0^Tf (w_h tau_h^2 + w_p tau_p^2) dt          (eqs. 10, 12, 13)
    subject to  the equations of motion (eq. 14, torques from eq. 15), heave/pitch ranges, torque limits,
                and the boundary conditions of its type:

    cruise           alpha(0) = 0, p_alpha(0) = 0, psi(0) = psi(Tf), qdot(0) = qdot(Tf), mean T = E  (eq. 9),
                     alphadot(0) >= v_min (the cycle is cut where the vehicle moves forward, so that the
                     decelerate's alphadot >= v_min can hold from its first instant). u is not periodic: tiled
                     cycles may jump in u where they join. With u(0) = u(Tf) imposed the free R = 0.43 m,
                     E = 0.10 decelerate is infeasible, with the cut at v_min and at v_min + 0.02 rad/s
                     alike (the cruise then ends at a pitch rate of -11 rad/s).
    accelerate       from rest (q = (0, R_lane, 0, 0), qdot = 0) to a cruise's start state
    decelerate       from a cruise's end state to rest, alphadot >= v_min                         (eq. 12)
    cruise_to_cruise from cruise i's end state to cruise j's start state                        (eq. 13)
    lane_change      cruise_to_cruise between lanes, R(t) in [R1 - Rb, R2 + Rb]

with s = +1, except decelerate (s = -1) and a cruise-to-cruise that slows down (s = -1). States are
matched up to a translation of alpha (the symmetry of Prop. 1), which concatenation adds back. In-lane
primitives of the free vehicle keep R(0) = R(Tf) = R_lane. Transcription: Hermite-Simpson collocation,
solved by IPOPT with exact derivatives from CasADi.

Flow models. With ``VehicleModel(..., flow="circulatory")`` the state is x = (q, qdot, z), z the flow's two lag
states (swim_model.flow), collocated with their own dynamics zdot = g(Q2 qdot, z). Then:

    - a cruise is periodic in (psi, qdot, z), and p_alpha(0) is free: the fluid's force changes p_alpha, so rest
      reaches a cruise whatever its p_alpha (with the ideal flow p_alpha is conserved and must be 0);
    - start and end states are (q, qdot, z); rest has the lag states of still water (z = 0);
    - at every collocation point (knots and midpoints) |angle of attack| <= PlanningLimits.angle_of_attack_limit_rad,
      the angle atan2(-V, U) of the foil frame's velocity in foil axes (eq. 40, swim_model.flow.angle_of_attack),
      written smoothly as U tan(a) + c -+ V >= 0 (for c = 0 the same set for a < 90 deg; atan2 itself has no
      derivative at rest). c = PlanningLimits.angle_of_attack_speed_floor_m_s frees the angle while the foil crawls:
      from rest the foil's first velocities are linear in the two foil accelerations, and V = 0 with Q = 0 (below)
      leaves only u = 0, so with c = 0 an accelerate from rest is infeasible (IPOPT: Infeasible_Problem_Detected).
      Points held at rest by a boundary condition are left out: the angle is undefined there.
    - the same bound on the incidence at the three-quarter chord, U tan(a) + c -+ Q >= 0 with Q = -(V + Omega x_34)
      (swim_model.flow's normal velocity, whose lagged value sets the circulation and the stall transition).
      The bound at F alone admits U = V = 0, where the angle at F has no value: the optimizer then held F still
      and turned the foil about it (Omega 4 rad/s, the three-quarter chord broadside), paddling with the separated
      flat plate's drag (measured on the constrained E = 0.05 accelerate). With both bounds, F at rest means the
      foil at rest (to c).

Energy level of a cruise: the paper fixes E = T(q(Tf), qdot(Tf)), the kinetic energy at the cycle's end.
Over a periodic cycle the kinetic energy oscillates, so that end-point value only selects where the cycle is
cut, not how fast the vehicle swims (we found E = 0.05 and E = 0.1 cruises of equal speed with it). We fix
instead the cycle's mean kinetic energy (1/Tf) int T dt = E, which orders cruises by speed as the paper's
graph intends. A cruise is solved over one cycle of ``cycle_s`` and repeated (the paper's Fourier series
have period T with Tf a multiple of T).
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Optional, TypeVar

import casadi as ca
import numpy as np
import numpy.typing as npt
from scipy.integrate import solve_ivp

from swim_model import SinusoidalGait, VehicleModel, simulate_gait
from swim_planner.collocation import collocation_grid, fine_grid_times, hermite_simpson, simpson_integral
from swim_planner.errors import PrimitiveSolveError
from swim_planner import pointwise
from swim_planner.pointwise import PointwiseFunction, PointwiseNlp
from swim_planner.primitives import (CONVERGED_STATUSES, PlanningLimits, Primitive, PrimitiveSpec, PrimitiveType,
                                     SolverSettings, rest_boundary_state, rest_state)

Array = npt.NDArray[np.float64]
Symbol = TypeVar("Symbol", ca.MX, ca.DM)   # a decision-variable expression or a numeric constant


# Rows of the pointwise function phi(x, u; w_h, w_p) of every primitive's NLP (swim_planner.pointwise)
EFFORT_ROW = 0       # w_h tau_h^2 + w_p tau_p^2, the integrand of eq. 10's effort
ENERGY_ROW = 1       # kinetic energy T(q, qdot)
MOMENTUM_ROW = 2     # p_alpha (docs/model_and_method.md P1)
TORQUE_ROWS = slice(3, 5)
STATE_DERIVATIVE_ROWS = slice(5, None)   # the ideal flow's; state_derivative_rows(model) for any model


def state_derivative_rows(model: VehicleModel) -> slice:
    """The rows of xdot = (qdot, qddot[, zdot]) in the model's pointwise function."""
    return slice(5, 5 + model.nx)


def foil_velocity_rows(model: VehicleModel) -> slice:
    """Circulatory flow: the rows of (U, V, Omega), the foil frame's velocity in foil axes (eq. 40), m/s, m/s,
    rad/s."""
    return slice(5 + model.nx, 8 + model.nx)


GUESS_TOLERANCE = 1e-6   # relative tolerance of the simulated gait that is a cruise's initial guess
GUESS_START_CYCLES = 3   # circulatory flow: cycles the guess's gait swims from rest before the one it keeps

#: the compiled pointwise functions of the models used in this process, by (rig digest, constrained, lane)
_POINTWISE: dict[tuple, PointwiseFunction] = {}


def pointwise_function(model: VehicleModel) -> PointwiseFunction:
    """phi(y, theta) with y = (q, qdot, u), theta = (w_h, w_p): the rows above, compiled once per model.
    With the circulatory flow y = (q, qdot, z, u) and phi gains zdot and the foil velocity (U, V, Omega)."""
    if model.circulatory_flow is not None:
        return _circulatory_pointwise_function(model)
    key = (model.rig.digest(), model.constrained, model.lane_radius_m)
    if key not in _POINTWISE:
        s = model.symbolic
        y, theta = ca.SX.sym("y", 2 * model.nq + 2), ca.SX.sym("theta", 2)
        q, qdot, u = y[:model.nq], y[model.nq:2 * model.nq], y[2 * model.nq:]
        qddot, tau = s.functions["shape_dynamics"](q, qdot, u)
        phi = ca.vertcat(ca.dot(theta, tau ** 2), s.functions["kinetic_energy"](q, qdot),
                         s.functions["momentum"](q, qdot)[0], tau, qdot, qddot)
        _POINTWISE[key] = PointwiseFunction.compiled(phi, y, theta, tag="primitive_pointwise")
    return _POINTWISE[key]


def _circulatory_pointwise_function(model: VehicleModel) -> PointwiseFunction:
    assert model.circulatory_flow is not None
    key = (model.rig.digest(), model.constrained, model.lane_radius_m, model.circulatory_flow.params.digest())
    if key not in _POINTWISE:
        s = model.symbolic
        nq, nx = model.nq, model.nx
        y, theta = ca.SX.sym("y", nx + 2), ca.SX.sym("theta", 2)
        q, qdot, lag, u = y[:nq], y[nq:2 * nq], y[2 * nq:nx], y[nx:]
        qddot, tau = s.functions["shape_dynamics"](q, qdot, u, lag)
        lag_rate = s.functions["lag_rate"](q, qdot, lag)
        foil_velocity = s.functions["foil_velocity_map"](q) @ qdot
        phi = ca.vertcat(ca.dot(theta, tau ** 2), s.functions["kinetic_energy"](q, qdot),
                         s.functions["momentum"](q, qdot)[0], tau, qdot, qddot, lag_rate, foil_velocity)
        _POINTWISE[key] = PointwiseFunction.compiled(phi, y, theta, tag="primitive_pointwise_circulatory")
    return _POINTWISE[key]


@dataclasses.dataclass(frozen=True)
class PrimitiveNlp:
    """One primitive's NLP (swim_planner.pointwise form), its initial guess and constraint bounds, and the
    expressions of the solution's samples on the fine grid."""

    nlp: PointwiseNlp
    z0: Array
    lbg: Array
    ubg: Array
    states: ca.MX     # nx x (2N + 1)
    inputs: ca.MX     # 2 x (2N + 1)
    torques: ca.MX    # 2 x (2N + 1), in terms of Phi
    effort: ca.MX     # int (w_h tau_h^2 + w_p tau_p^2) dt over the solved horizon, in terms of Phi


def solve_primitive(model: VehicleModel, spec: PrimitiveSpec, limits: PlanningLimits = PlanningLimits(),
                    start: Optional[tuple[Array, ...]] = None, end: Optional[tuple[Array, ...]] = None,
                    guess: Optional[Primitive] = None, settings: SolverSettings = SolverSettings()) -> Primitive:
    """Solve one primitive.

    Args:
        start: (q, qdot) the primitive starts from (required for decelerate, cruise-to-cruise, lane change;
            alpha is ignored: it starts at 0); (q, qdot, lag) with the circulatory flow
            (Primitive.end_boundary_state).
        end: (q, qdot) it must reach (required for accelerate, cruise-to-cruise, lane change; alpha free);
            (q, qdot, lag) with the circulatory flow (Primitive.start_boundary_state).
        guess: a primitive of the same grid size to warm-start from (else a built-in guess).
    Raises:
        PrimitiveSolveError: IPOPT did not converge; the message gives its status.
    """
    problem = primitive_nlp(model, spec, limits, start, end, guess)
    nlp = problem.nlp
    ipopt_options = {"print_level": settings.print_level, "tol": settings.tolerance,
                     "max_iter": settings.max_iterations, "mu_strategy": settings.barrier_strategy, "sb": "yes"}
    started = time.perf_counter()
    try:
        result = pointwise.solve(nlp, problem.z0, problem.lbg, problem.ubg, ipopt_options, settings.derivatives,
                                 settings.expand_to_sx)
    except RuntimeError as err:   # CasADi refused the problem (e.g. bounds that contradict each other)
        raise PrimitiveSolveError(f"{spec.primitive_id}: the NLP was refused: {err}") from err
    elapsed = time.perf_counter() - started
    if result.status not in CONVERGED_STATUSES:
        raise PrimitiveSolveError(f"{spec.primitive_id}: IPOPT did not converge ({result.status})")
    samples = 2 * spec.intervals + 1
    values = ca.Function("values", [nlp.z], nlp.substitute(problem.states, problem.inputs, problem.torques,
                                                            problem.effort))
    solved_states, solved_inputs, solved_torques, solved_effort = values(result.z)
    state_values = np.asarray(solved_states).reshape(model.nx, samples).T
    input_values = np.asarray(solved_inputs).reshape(2, samples).T
    torque_values = np.asarray(solved_torques).reshape(2, samples).T
    effort_value = float(solved_effort)
    time_s = fine_grid_times(spec.solved_duration_s, spec.intervals)
    q, qdot = state_values[:, :model.nq], state_values[:, model.nq:2 * model.nq]
    lag = state_values[:, 2 * model.nq:] if model.n_lag else None
    if spec.cycles > 1:
        time_s, q, qdot, input_values, torque_values = _repeat_cycle(
            spec.cycles, time_s, q, qdot, input_values, torque_values)
        if lag is not None:
            lag = np.concatenate([lag] + [lag[1:]] * (spec.cycles - 1))
        effort_value *= spec.cycles
    return Primitive(spec=spec, time_s=time_s, q=q, qdot=qdot, foil_acceleration=input_values,
                     torque=torque_values, index_j=float(spec.index_sign() * q[-1, 0] - effort_value),
                     effort=effort_value, solver_status=result.status, solve_time_s=elapsed,
                     iterations=result.iterations, lag=lag)


def primitive_nlp(model: VehicleModel, spec: PrimitiveSpec, limits: PlanningLimits = PlanningLimits(),
                  start: Optional[tuple[Array, ...]] = None, end: Optional[tuple[Array, ...]] = None,
                  guess: Optional[Primitive] = None) -> PrimitiveNlp:
    """The NLP of one primitive (arguments as for ``solve_primitive``).

    Raises:
        ValueError: a start or end state that is not (q, qdot) of finite numbers of the model's size
            ((q, qdot, lag) with the circulatory flow).
    """
    if model.n_lag:
        _check_circulatory_states(model, spec, start, end)
    for name, state in (("start", start), ("end", end)) if model.n_lag == 0 else ():
        if state is not None and not (len(state) == 2 and all(np.shape(part) == (model.nq,) for part in state)
                                      and np.all(np.isfinite(state))):
            raise ValueError(f"{spec.primitive_id}: the {name} state must be (q, qdot), {model.nq} finite numbers "
                             f"each; got {state!r}")
    nq = model.nq
    nx = model.nx
    phi_function = pointwise_function(model)
    opti = ca.Opti()
    grid = collocation_grid(opti, nx, 2, spec.intervals, spec.solved_duration_s)
    samples = 2 * spec.intervals + 1
    # Phi, the pointwise function's values over grid.points(): a placeholder the NLP is written in (an Opti
    # variable, as Opti takes no constraint without one; the NLP solved has the grid's variables only)
    phi = opti.variable(phi_function.value.size1_out(0), samples)
    hermite_simpson(grid, phi[STATE_DERIVATIVE_ROWS if model.n_lag == 0 else state_derivative_rows(model), :])
    states, inputs = grid.all_states(), grid.all_inputs()
    torques = grid.fine(phi[TORQUE_ROWS, :])
    effort = simpson_integral(grid, phi[EFFORT_ROW, :])
    x_end = grid.x[:, -1]
    sign = spec.index_sign()
    # w_u int |udot|^2 dt on the fine grid: without it the optimizer makes the light pitch axis ring at the
    # grid's own frequency (cheap in torque), a plan no sampled controller can follow
    fine_step = spec.solved_duration_s / (samples - 1)
    roughness = spec.input_smoothness_weight * ca.sumsqr(inputs[:, 1:] - inputs[:, :-1]) / fine_step
    opti.minimize(-(sign * x_end[0] - effort) + roughness)

    # ranges and limits on the fine grid
    heave, pitch = states[nq - 2, :], states[nq - 1, :]
    opti.subject_to(opti.bounded(-limits.heave_range_rad, heave, limits.heave_range_rad))
    opti.subject_to(opti.bounded(-limits.pitch_range_rad, pitch, limits.pitch_range_rad))
    tau_max = limits.torque_fraction * model.torque_limits()
    opti.subject_to(opti.bounded(-tau_max[0], torques[0, :], tau_max[0]))
    opti.subject_to(opti.bounded(-tau_max[1], torques[1, :], tau_max[1]))
    u_max = limits.foil_acceleration_limit_rad_s2
    opti.subject_to(opti.bounded(-u_max, inputs, u_max))
    if not model.constrained:
        low = min(spec.lane_radius_m, spec.end_lane_radius_m) - limits.lane_band_m
        high = max(spec.lane_radius_m, spec.end_lane_radius_m) + limits.lane_band_m
        opti.subject_to(opti.bounded(low, states[1, :], high))

    # an accelerate starts at rest and a decelerate ends there, whatever the caller passed
    if spec.primitive_type is PrimitiveType.ACCELERATE:
        start = rest_state(model, spec.lane_radius_m) if model.n_lag == 0 else rest_boundary_state(
            model, spec.lane_radius_m)
    if spec.primitive_type is PrimitiveType.DECELERATE:
        end = rest_state(model, spec.end_lane_radius_m) if model.n_lag == 0 else rest_boundary_state(
            model, spec.end_lane_radius_m)
    if model.n_lag:
        _angle_of_attack_bound(opti, model, spec, limits, grid, phi)
    _boundary_conditions(opti, model, spec, limits, grid, phi, start, end)
    _initial_guess(opti, model, spec, grid, start, end, guess)

    nlp = PointwiseNlp(z=grid.variables(), f=opti.f, g=opti.g, points=grid.points(), phi_placeholder=phi,
                       pointwise=phi_function, theta=np.array([spec.heave_effort_weight, spec.pitch_effort_weight]))
    return PrimitiveNlp(nlp=nlp, z0=np.asarray(opti.value(nlp.z, opti.initial()), dtype=float).ravel(),
                        lbg=np.asarray(ca.evalf(opti.lbg), dtype=float).ravel(),
                        ubg=np.asarray(ca.evalf(opti.ubg), dtype=float).ravel(),
                        states=states, inputs=inputs, torques=torques, effort=effort)


def _check_circulatory_states(model: VehicleModel, spec: PrimitiveSpec, start, end) -> None:
    sizes = (model.nq, model.nq, model.n_lag)
    for name, state in (("start", start), ("end", end)):
        if state is not None and not (len(state) == 3 and all(np.shape(part) == (size,) for part, size
                                                              in zip(state, sizes))
                                      and all(np.all(np.isfinite(part)) for part in state)):
            raise ValueError(f"{spec.primitive_id}: with the circulatory flow the {name} state must be "
                             f"(q, qdot, lag), {model.nq}, {model.nq} and {model.n_lag} finite numbers; got {state!r}")


def _angle_of_attack_bound(opti: ca.Opti, model: VehicleModel, spec: PrimitiveSpec, limits: PlanningLimits,
                           grid, phi: ca.MX) -> None:
    """|atan2(-V, U)| <= a at every collocation point, as U tan(a) + c -+ V >= 0, and the same at the
    three-quarter chord (module docstring)."""
    if not 0.0 < limits.angle_of_attack_limit_rad < math.pi / 2:
        raise ValueError(f"{spec.primitive_id}: angle_of_attack_limit_rad must be in (0, pi/2), got "
                         f"{limits.angle_of_attack_limit_rad!r}")
    if not (math.isfinite(limits.angle_of_attack_speed_floor_m_s) and limits.angle_of_attack_speed_floor_m_s >= 0.0):
        raise ValueError(f"{spec.primitive_id}: angle_of_attack_speed_floor_m_s must be finite and >= 0, got "
                         f"{limits.angle_of_attack_speed_floor_m_s!r}")
    velocity = grid.fine(phi[foil_velocity_rows(model), :])
    if spec.primitive_type is PrimitiveType.ACCELERATE:
        velocity = velocity[:, 1:]
    if spec.primitive_type is PrimitiveType.DECELERATE:
        velocity = velocity[:, :-1]
    assert model.circulatory_flow is not None
    normal_34 = -(velocity[1, :] + model.circulatory_flow.three_quarter_chord_x_m * velocity[2, :])
    slope = math.tan(limits.angle_of_attack_limit_rad)
    floor = limits.angle_of_attack_speed_floor_m_s
    for across in (velocity[1, :], normal_34):
        opti.subject_to(slope * velocity[0, :] - across >= -floor)
        opti.subject_to(slope * velocity[0, :] + across >= -floor)


def _repeat_cycle(cycles: int, time_s: Array, q: Array, qdot: Array, u: Array, tau: Array):
    """Tile a periodic cycle: each copy starts where the last ended, alpha carried over (Prop. 1)."""
    period, advance = time_s[-1], q[-1, 0] - q[0, 0]
    times, qs = [time_s], [q]
    for k in range(1, cycles):
        times.append(time_s[1:] + k * period)
        shifted = q[1:].copy()
        shifted[:, 0] += k * advance
        qs.append(shifted)
    def tile(a: Array) -> Array:
        return np.concatenate([a] + [a[1:]] * (cycles - 1))
    return np.concatenate(times), np.concatenate(qs), tile(qdot), tile(u), tile(tau)


def _without_alpha(x: Symbol, nq: int) -> Symbol:
    return ca.vertcat(x[1:nq], x[nq:])


def _boundary_conditions(opti: ca.Opti, model: VehicleModel, spec: PrimitiveSpec, limits: PlanningLimits,
                         grid, phi: ca.MX, start, end) -> None:
    nq = model.nq
    x0, x_end = grid.x[:, 0], grid.x[:, -1]
    opti.subject_to(x0[0] == 0.0)
    kind = spec.primitive_type
    if kind is PrimitiveType.CRUISE:
        if spec.energy_j is None:
            raise ValueError(f"{spec.primitive_id}: a cruise needs energy_j")
        opti.subject_to(x0[nq - 2:nq] == x_end[nq - 2:nq])          # psi periodic
        opti.subject_to(x0[nq:] == x_end[nq:])                      # qdot (and the lag states z) periodic
        if model.n_lag == 0:
            opti.subject_to(grid.knots(phi)[MOMENTUM_ROW, 0] == 0.0)    # reachable from rest: p_alpha = 0
        # cut the cycle where the vehicle moves forward: a decelerate from here can keep alphadot >= v_min
        opti.subject_to(x0[nq] >= limits.min_alpha_rate_rad_s)
        # energy level: the cycle's mean kinetic energy (see the module docstring)
        mean_energy = simpson_integral(grid, phi[ENERGY_ROW, :]) / spec.solved_duration_s
        opti.subject_to(mean_energy == spec.energy_j)
        if not model.constrained:
            opti.subject_to(x0[1] == spec.lane_radius_m)
            opti.subject_to(x_end[1] == spec.lane_radius_m)
        return
    if kind is PrimitiveType.DECELERATE:
        alpha_rate = ca.horzcat(grid.x[nq, :], grid.x_mid[nq, :])
        opti.subject_to(alpha_rate >= limits.min_alpha_rate_rad_s)
    if start is None or end is None:
        raise ValueError(f"{spec.primitive_id}: a {kind.value} needs its start and end states")
    start_x = np.concatenate(start)
    end_x = np.concatenate(end)
    opti.subject_to(_without_alpha(x0, nq) == _without_alpha(ca.DM(start_x), nq))
    opti.subject_to(_without_alpha(x_end, nq) == _without_alpha(ca.DM(end_x), nq))


def _initial_guess(opti: ca.Opti, model: VehicleModel, spec: PrimitiveSpec, grid, start, end,
                   guess: Optional[Primitive]) -> None:
    times = fine_grid_times(spec.solved_duration_s, spec.intervals)
    if guess is not None and guess.spec.primitive_id == spec.primitive_id and len(guess.time_s) == len(times):
        x_guess, u_guess = np.column_stack([guess.q, guess.qdot, *_lag_columns(model, guess)]), guess.foil_acceleration
    elif spec.primitive_type is PrimitiveType.CRUISE and model.n_lag:
        x_guess, u_guess = _circulatory_gait_guess(model, spec, times)
    elif spec.primitive_type is PrimitiveType.CRUISE:
        x_guess, u_guess = _gait_guess(model, spec, times)
    else:
        x_guess, u_guess = _blend_guess(model, spec, times, start, end, guess)
    opti.set_initial(grid.x, x_guess[0::2].T)
    opti.set_initial(grid.x_mid, x_guess[1::2].T)
    opti.set_initial(grid.u, u_guess[0::2].T)
    opti.set_initial(grid.u_mid, u_guess[1::2].T)


def _gait_guess(model: VehicleModel, spec: PrimitiveSpec, times: Array) -> tuple[Array, Array]:
    """A fish-like gait: pitch leads heave by 90 deg (paper Sec. 5.1), one cycle per second."""
    gait = SinusoidalGait(0.35, 0.6, 1.0)
    # a guess needs no 1e-10 accuracy: 1e-6 takes a third of the model evaluations
    run = simulate_gait(model, gait, times[-1], sample_period_s=times[1] - times[0],
                        initial_y=None if model.constrained else [0.0, spec.lane_radius_m], rtol=GUESS_TOLERANCE)
    return np.column_stack([run.q, run.qdot]), np.array([gait.shape(t)[2] for t in times])


def _lag_columns(model: VehicleModel, primitive: Primitive) -> list[Array]:
    """A guess's lag states for this model: its own, zeros if it has none, nothing with the ideal flow."""
    if model.n_lag == 0:
        return []
    return [primitive.lag if primitive.lag is not None else np.zeros((len(primitive.time_s), model.n_lag))]


def _circulatory_gait_guess(model: VehicleModel, spec: PrimitiveSpec, times: Array) -> tuple[Array, Array]:
    """_gait_guess's gait with the circulatory flow: swum from rest for GUESS_START_CYCLES cycles (the unactuated
    coordinates and the lag states integrated under the prescribed foil motion), its last cycle with alpha from 0:
    close to periodic, at the speed the gait makes."""
    gait = SinusoidalGait(0.35, 0.6, 1.0 / spec.solved_duration_s)
    nq, ny = model.nq, model.n_unactuated
    y0 = np.zeros(ny) if model.constrained else np.array([0.0, spec.lane_radius_m])
    start_s = GUESS_START_CYCLES * spec.solved_duration_s

    def state(time_s: float, x: Array) -> tuple[Array, Array, Array, Array]:
        psi, psidot, psiddot = gait.shape(time_s)
        return (np.concatenate([x[:ny], psi]), np.concatenate([x[ny:2 * ny], psidot]), x[2 * ny:], psiddot)

    def rhs(time_s: float, x: Array) -> Array:
        q, qdot, lag, psiddot = state(time_s, x)
        qddot, _ = model.shape_dynamics(q, qdot, psiddot, lag)
        return np.concatenate([x[ny:2 * ny], qddot[:ny], model.lag_rate(q, qdot, lag)])

    x0 = np.concatenate([y0, np.zeros(ny + model.n_lag)])
    solution = solve_ivp(rhs, (0.0, start_s + times[-1]), x0, method="DOP853", t_eval=start_s + times,
                         rtol=GUESS_TOLERANCE, atol=GUESS_TOLERANCE * 1e-2)
    rows = [state(t, x) for t, x in zip(solution.t, solution.y.T)]
    q = np.array([r[0] for r in rows])
    q[:, 0] -= q[0, 0]
    x_guess = np.column_stack([q, np.array([r[1] for r in rows]), np.array([r[2] for r in rows])])
    assert x_guess.shape[1] == 2 * nq + model.n_lag
    return x_guess, np.array([r[3] for r in rows])


def _blend_guess(model: VehicleModel, spec: PrimitiveSpec, times: Array, start, end,
                 cruise: Optional[Primitive]) -> tuple[Array, Array]:
    """Blend between the boundary states; with a cruise given, fade its stroke in (accelerate), out
    (decelerate), or keep it (between cruises), so the guess already swims in the right phase."""
    weight = (times / times[-1])[:, None]
    x_start, x_end = np.concatenate(start), np.concatenate(end)
    x_guess = (1 - weight) * x_start + weight * x_end
    x_guess[:, 0] = 0.02 * times
    u_guess = np.zeros((len(times), 2))
    if cruise is None:
        return x_guess, u_guess
    nq = model.nq
    period = cruise.spec.solved_duration_s
    one = cruise.time_s <= period + 1e-12
    # the cruise's stroke, periodic, phased so the accelerate ends (decelerate starts) at its junction
    phase = (times - times[-1]) % period if spec.primitive_type is PrimitiveType.ACCELERATE else times % period
    stroke = np.column_stack([np.interp(phase, cruise.time_s[one], cruise.q[one, j]) for j in range(nq)])
    rates = np.column_stack([np.interp(phase, cruise.time_s[one], cruise.qdot[one, j]) for j in range(nq)])
    accel = np.column_stack([np.interp(phase, cruise.time_s[one], cruise.foil_acceleration[one, j]) for j in range(2)])
    envelope = {PrimitiveType.ACCELERATE: weight, PrimitiveType.DECELERATE: 1.0 - weight}.get(
        spec.primitive_type, np.ones_like(weight))  # between cruises: keep stroking
    x_guess[:, nq - 2:nq] = envelope * stroke[:, nq - 2:]
    x_guess[:, 2 * nq - 2:2 * nq] = envelope * rates[:, nq - 2:]
    if model.n_lag:
        lags = _lag_columns(model, cruise)[0]
        x_guess[:, 2 * nq:] = envelope * np.column_stack([np.interp(phase, cruise.time_s[one], lags[one, j])
                                                          for j in range(model.n_lag)])
    mean_rate = (cruise.q[-1, 0] - cruise.q[0, 0]) / cruise.time_s[-1]
    x_guess[:, nq] = envelope[:, 0] * mean_rate
    x_guess[:, 0] = np.concatenate([[0.0], np.cumsum(0.5 * (x_guess[1:, nq] + x_guess[:-1, nq]) * np.diff(times))])
    return x_guess, envelope * accel
