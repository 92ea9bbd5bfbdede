"""Motion primitives solved by optimal control (paper Secs. 4-5, eqs. 9-15): the optimizer of swim_planner.primitives.

Every primitive maximizes s alpha(Tf) - int_0^Tf (w_h tau_h^2 + w_p tau_p^2) dt (eqs. 10, 12, 13) over the state
x = (q, qdot) and the input u = psiddot (the planning input of eq. 16), subject to the equations of motion (eqs.
14-15), the planning limits (PlanningLimits) and the boundary conditions of its type. Transcription:
Hermite-Simpson collocation (swim_planner.collocation), solved by IPOPT with exact derivatives of the pointwise
function (swim_planner.pointwise).

- The problem of each type, the cruise's cut and energy level (the cycle's mean kinetic energy, not eq. 9's end
  value) and the transcription: docs/model_and_method.md, section 3.1 "The optimal-control problem of each type".
- With ``VehicleModel(..., flow="circulatory")`` the state is x = (q, qdot, z), z the flow's two lag states, with
  a periodic cruise in (psi, qdot, z), the angle-of-attack bound at F and at the three-quarter chord, its window
  next to rest, the Strouhal floor, a decelerate's free end lag, the continuation and the coarser grid:
  docs/circulatory_primitives.md, "The problem".
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Optional, TypeVar, cast

import casadi as ca
import numpy as np
import numpy.typing as npt

from swim_model import SinusoidalGait, VehicleModel, simulate_gait
from swim_planner import pointwise
from swim_planner.collocation import collocation_grid, fine_grid_times, hermite_simpson, simpson_integral
from swim_planner.errors import PrimitiveSolveError
from swim_planner.pointwise import PointwiseFunction, PointwiseNlp
from swim_planner.primitives import (
    CONVERGED_STATUSES,
    PlanningLimits,
    Primitive,
    PrimitiveSpec,
    PrimitiveType,
    SolverSettings,
    rest_boundary_state,
    rest_state,
)

Array = npt.NDArray[np.float64]
Symbol = TypeVar("Symbol", ca.MX, ca.DM)   # a decision-variable expression or a numeric constant


# Rows of the pointwise function phi(x, u; w_h, w_p) of every primitive's NLP (swim_planner.pointwise)
EFFORT_ROW = 0       # w_h tau_h^2 + w_p tau_p^2, the integrand of eq. 10's effort
ENERGY_ROW = 1       # kinetic energy T(q, qdot)
MOMENTUM_ROW = 2     # p_alpha (docs/model_and_method.md P1)
TORQUE_ROWS = slice(3, 5)
STATE_DERIVATIVE_ROWS = slice(5, None)   # the ideal flow's; state_derivative_rows(model) for any model


def state_derivative_rows(model: VehicleModel) -> slice:
    """The rows of xdot = (qdot, qddot[, zdot]) in the model's pointwise function.

    Parameters
    ----------
    model : VehicleModel
        The vehicle, ideal or circulatory flow: nx is 2 nq, or 2 nq + n_lag with the circulatory flow.

    Returns
    -------
    slice
        Rows 5 to 5 + nx.
    """
    return slice(5, 5 + model.nx)


def foil_velocity_rows(model: VehicleModel) -> slice:
    """Circulatory flow: the rows of (U, V, Omega), the foil frame's velocity in foil axes (eq. 40).

    Parameters
    ----------
    model : VehicleModel
        A circulatory-flow vehicle (the ideal flow's pointwise function has no such rows).

    Returns
    -------
    slice
        The three rows, in m/s, m/s and rad/s.
    """
    return slice(5 + model.nx, 8 + model.nx)


def lateral_row(model: VehicleModel) -> int:
    """Circulatory flow: the row of the pitch axis's position across the lane.

    Parameters
    ----------
    model : VehicleModel
        A circulatory-flow vehicle.

    Returns
    -------
    int
        The row of Lh sin(phi), less R for the free vehicle, m (primitives.cruise_strouhal_number's lateral
        coordinate).
    """
    return 8 + model.nx


GUESS_TOLERANCE = 1e-6   # relative tolerance of the simulated gait that is a cruise's initial guess
# circulatory cruise's guess (_folded_cruise_guess), assumed: a stroke small enough to leave the folded posture
# and the steady flow about as they are, but not zero (IPOPT's first steps then have a stroke to grow or shrink)
FOLDED_GUESS_HEAVE_AMPLITUDE_RAD = 0.02
FOLDED_GUESS_PITCH_AMPLITUDE_RAD = 0.05
FOLDED_GUESS_HEAVE_MARGIN_RAD = 0.01   # the guess's heave stays this far inside its planning range

#: the compiled pointwise functions of the models used in this process, by (rig digest, constrained, lane)
_POINTWISE: dict[tuple, PointwiseFunction] = {}


def pointwise_function(model: VehicleModel) -> PointwiseFunction:
    """The pointwise function phi(y, theta) of every primitive's NLP, compiled once per model.

    Parameters
    ----------
    model : VehicleModel
        The vehicle; its rig, kind, lane and flow parameters key the compiled function.

    Returns
    -------
    PointwiseFunction
        phi(y, theta) with y = (q, qdot, u), theta = (w_h, w_p): the rows ``EFFORT_ROW`` .. ``state_derivative_rows``.
        With the circulatory flow y = (q, qdot, z, u), and phi gains zdot, the foil velocity (U, V, Omega) and the
        lateral row.
    """
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
        lateral_m = model.rig.heave_link_length_m * ca.sin(q[nq - 2]) - (0.0 if model.constrained else q[1])
        phi = ca.vertcat(ca.dot(theta, tau ** 2), s.functions["kinetic_energy"](q, qdot),
                         s.functions["momentum"](q, qdot)[0], tau, qdot, qddot, lag_rate, foil_velocity, lateral_m)
        _POINTWISE[key] = PointwiseFunction.compiled(phi, y, theta, tag="primitive_pointwise_circulatory")
    return _POINTWISE[key]


@dataclasses.dataclass(frozen=True)
class PrimitiveNlp:
    """One primitive's NLP (swim_planner.pointwise form), its initial guess, bounds and solution's expressions.

    The expressions give the solution's samples on the fine grid (2N + 1 points for N intervals).

    Attributes
    ----------
    nlp : PointwiseNlp
        The NLP.
    z0 : (nz,) array
        The initial guess of its variables.
    lbg : (ng,) array
        The constraints' lower bounds.
    ubg : (ng,) array
        The constraints' upper bounds.
    states : casadi.MX
        x at the fine grid's points, nx x (2N + 1).
    inputs : casadi.MX
        u = psiddot, 2 x (2N + 1), rad/s^2.
    torques : casadi.MX
        (tau_h, tau_p), 2 x (2N + 1), N m, in terms of Phi.
    effort : casadi.MX
        int (w_h tau_h^2 + w_p tau_p^2) dt over the solved horizon, in terms of Phi.
    """

    nlp: PointwiseNlp
    z0: Array
    lbg: Array
    ubg: Array
    states: ca.MX     # nx x (2N + 1)
    inputs: ca.MX     # 2 x (2N + 1)
    torques: ca.MX    # 2 x (2N + 1), in terms of Phi
    effort: ca.MX     # int (w_h tau_h^2 + w_p tau_p^2) dt over the solved horizon, in terms of Phi


def solve_primitive(model: VehicleModel, spec: PrimitiveSpec, limits: Optional[PlanningLimits] = None,
                    start: Optional[tuple[Array, ...]] = None, end: Optional[tuple[Array, ...]] = None,
                    guess: Optional[Primitive] = None, settings: SolverSettings = SolverSettings()) -> Primitive:
    """Solve one primitive: its NLP by IPOPT, and a cruise's cycle tiled ``spec.cycles`` times.

    With the circulatory flow and a spec that names an angle-of-attack continuation
    (``PrimitiveSpec.angle_of_attack_continuation_rad``), the NLP is solved in steps (``continuation_bounds``): first
    without the angle-of-attack bound, then with each looser bound of the spec, then with the bound of ``limits``,
    each step from the last converged step's solution (the first from the guess). A step that does not converge is
    passed over (the next starts from the last converged one); the last must converge. With a coarser grid
    (``PrimitiveSpec.coarse_intervals``) all that is solved on it to ``settings.coarse_grid_tolerance``, and then the
    spec's own grid once, from the coarse solution interpolated. The primitive's iterations and solve time are the
    sums over the steps. Without either: one solve.

    Parameters
    ----------
    model : VehicleModel
        The vehicle, constrained or free, ideal or circulatory flow (it must match ``spec.constrained``).
    spec : PrimitiveSpec
        What to solve.
    limits : PlanningLimits, optional
        The ranges and limits the primitive respects (None: ``PlanningLimits.of(model.rig)``, the model's rig's
        planning ranges).
    start : tuple of array, optional
        (q (nq,), qdot (nq,)) the primitive starts from (required for decelerate, cruise-to-cruise, lane change;
        alpha is ignored: it starts at 0); (q, qdot, lag (n_lag,) m/s) with the circulatory flow
        (Primitive.end_boundary_state). rad, m, rad/s, m/s.
    end : tuple of array, optional
        (q, qdot) it must reach (required for accelerate, cruise-to-cruise, lane change; alpha free);
        (q, qdot, lag) with the circulatory flow (Primitive.start_boundary_state).
    guess : Primitive, optional
        A primitive of the same grid size to warm-start from (else a built-in guess).
    settings : SolverSettings, optional
        IPOPT's settings.

    Returns
    -------
    Primitive
        The solved primitive on the fine grid, without gains.

    Raises
    ------
    PrimitiveSolveError
        IPOPT did not converge (in the continuation's last step), or CasADi refused the NLP; the message gives the
        status.
    ValueError
        A continuation with the ideal flow, or one that is not descending from below 90 deg to above the bound of
        ``limits``; a Strouhal floor (PrimitiveSpec.min_strouhal) with the ideal flow; a bad start or end state.

    References
    ----------
    Saimek & Li 2004, Secs. 4-5, eqs. 9-15; docs/model_and_method.md section 3.1; docs/circulatory_primitives.md,
    "The problem".
    """
    limits = PlanningLimits.of(model.rig) if limits is None else limits
    if spec.coarse_intervals is not None:
        return _solve_refined(model, spec, limits, start, end, guess, settings)
    ipopt_options = {"print_level": settings.print_level, "tol": settings.tolerance,
                     "max_iter": settings.max_iterations, "mu_strategy": settings.barrier_strategy, "sb": "yes"}
    bounds = continuation_bounds(model, spec, limits)
    warm_start: Optional[Array] = None
    iterations, elapsed = 0, 0.0
    for bound in bounds:
        step_limits = limits if bound is None else dataclasses.replace(limits, angle_of_attack_limit_rad=bound)
        problem = primitive_nlp(model, spec, step_limits, start, end, guess, bound_angle_of_attack=bound is not None)
        nlp = problem.nlp
        started = time.perf_counter()
        try:
            result = pointwise.solve(nlp, problem.z0 if warm_start is None else warm_start, problem.lbg, problem.ubg,
                                     ipopt_options, settings.derivatives, settings.expand_to_sx)
        except RuntimeError as err:   # CasADi refused the problem (e.g. bounds that contradict each other)
            raise PrimitiveSolveError(f"{spec.primitive_id}: the NLP was refused: {err}") from err
        elapsed += time.perf_counter() - started
        iterations += result.iterations
        if result.status in CONVERGED_STATUSES:
            warm_start = result.z
    if result.status not in CONVERGED_STATUSES:
        step = "" if len(bounds) == 1 else (f" in the continuation's last step, "
                                            f"{math.degrees(limits.angle_of_attack_limit_rad):.1f} deg")
        raise PrimitiveSolveError(f"{spec.primitive_id}: IPOPT did not converge ({result.status}){step}")
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
                     iterations=iterations, lag=lag)


def _solve_refined(model: VehicleModel, spec: PrimitiveSpec, limits: PlanningLimits, start, end,
                   guess: Optional[Primitive], settings: SolverSettings) -> Primitive:
    """Solve a primitive of a spec with a coarser grid, then on its own grid.

    On spec.coarse_intervals (continuation included) to settings.coarse_grid_tolerance, then on spec.intervals
    from the coarse solution interpolated, with the bound of ``limits`` alone.
    """
    coarse_spec = dataclasses.replace(spec, intervals=cast(int, spec.coarse_intervals), coarse_intervals=None)
    coarse_settings = dataclasses.replace(settings, tolerance=max(settings.tolerance, settings.coarse_grid_tolerance))
    coarse = solve_primitive(model, coarse_spec, limits, start, end, guess, coarse_settings)
    fine_spec = dataclasses.replace(spec, coarse_intervals=None, angle_of_attack_continuation_rad=())
    fine = solve_primitive(model, fine_spec, limits, start, end, _resampled(coarse, fine_spec), settings)
    return dataclasses.replace(fine, spec=spec, iterations=coarse.iterations + fine.iterations,
                               solve_time_s=coarse.solve_time_s + fine.solve_time_s)


def _resampled(primitive: Primitive, spec: PrimitiveSpec) -> Primitive:
    """The primitive interpolated (linearly, per column) onto the fine grid of spec: an initial guess."""
    time_s = fine_grid_times(spec.solved_duration_s, spec.intervals)

    def on_grid(values: Array) -> Array:
        return _interpolated_columns(time_s, primitive.time_s, values)

    return dataclasses.replace(primitive, spec=spec, time_s=time_s, q=on_grid(primitive.q),
                               qdot=on_grid(primitive.qdot), foil_acceleration=on_grid(primitive.foil_acceleration),
                               torque=on_grid(primitive.torque),
                               lag=None if primitive.lag is None else on_grid(primitive.lag), gains=None)


def _interpolated_columns(time_s: Array, sample_time_s: Array, values: Array) -> Array:
    """Each column of ``values`` (samples at ``sample_time_s``) interpolated linearly at ``time_s``.

    The result has the shape (len(time_s), columns).
    """
    return np.column_stack([np.interp(time_s, sample_time_s, column) for column in values.T])


def continuation_bounds(model: VehicleModel, spec: PrimitiveSpec, limits: PlanningLimits) -> list[Optional[float]]:
    """The angle-of-attack bounds ``solve_primitive`` solves with, in order.

    Parameters
    ----------
    model : VehicleModel
        The vehicle.
    spec : PrimitiveSpec
        Its ``angle_of_attack_continuation_rad`` names the looser bounds, if any.
    limits : PlanningLimits
        Its ``angle_of_attack_limit_rad`` is the last bound.

    Returns
    -------
    list of float or None
        rad (None: no bound): the bound of ``limits`` alone, or with the spec's continuation None, its looser
        bounds, then the bound of ``limits``.

    Raises
    ------
    ValueError
        A continuation with the ideal flow (which has no angle-of-attack bound), or bounds that do not descend
        strictly from below pi/2 to above ``limits.angle_of_attack_limit_rad``.
    """
    looser = spec.angle_of_attack_continuation_rad
    if not looser:
        return [limits.angle_of_attack_limit_rad]
    if model.n_lag == 0:
        raise ValueError(f"{spec.primitive_id}: an angle-of-attack continuation needs the circulatory flow")
    steps = (math.pi / 2, *looser, limits.angle_of_attack_limit_rad)
    if not all(math.isfinite(a) and a > b for a, b in zip(steps[:-1], steps[1:])):
        raise ValueError(f"{spec.primitive_id}: angle_of_attack_continuation_rad must descend strictly from below "
                         f"pi/2 to above the limit {limits.angle_of_attack_limit_rad!r}; got {looser!r}")
    return [None, *looser, limits.angle_of_attack_limit_rad]


def primitive_nlp(  # noqa: C901 - one NLP: a block of constraints per primitive type, read beside eqs. 9-15
        model: VehicleModel, spec: PrimitiveSpec, limits: Optional[PlanningLimits] = None,
        start: Optional[tuple[Array, ...]] = None, end: Optional[tuple[Array, ...]] = None,
        guess: Optional[Primitive] = None, *, bound_angle_of_attack: bool = True) -> PrimitiveNlp:
    """The NLP of one primitive (docs/model_and_method.md section 3.1).

    Parameters
    ----------
    model : VehicleModel
        The vehicle.
    spec : PrimitiveSpec
        What to solve.
    limits : PlanningLimits, optional
        The ranges and limits.
    start : tuple of array, optional
        As for ``solve_primitive``.
    end : tuple of array, optional
        As for ``solve_primitive``.
    guess : Primitive, optional
        As for ``solve_primitive``.
    bound_angle_of_attack : bool, optional
        False leaves the circulatory flow's angle-of-attack bound out (the first step of a continuation); the ideal
        flow has none.

    Returns
    -------
    PrimitiveNlp
        The NLP, its initial guess and bounds, and the solution's expressions.

    Raises
    ------
    ValueError
        A start or end state that is not (q, qdot) of finite numbers of the model's size ((q, qdot, lag) with the
        circulatory flow); a Strouhal floor with the ideal flow (its pointwise function has no lateral row); a rest
        window with the ideal flow; bad boundary conditions for the type.
    """
    limits = PlanningLimits.of(model.rig) if limits is None else limits
    if model.n_lag:
        _check_circulatory_states(model, spec, start, end)
    elif spec.min_strouhal is not None:
        raise ValueError(f"{spec.primitive_id}: min_strouhal is for a cruise with the circulatory flow")
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
    if spec.min_strouhal is not None:
        _stroke_bound(opti, model, spec, grid, phi)
    if model.n_lag and bound_angle_of_attack:
        _angle_of_attack_bound(opti, model, spec, limits, grid, phi)
    if spec.rest_window_s is not None or spec.rest_window_foil_rate_limit_rad_s is not None:
        if not model.n_lag:
            raise ValueError(f"{spec.primitive_id}: rest_window_s and rest_window_foil_rate_limit_rad_s are for the "
                             "circulatory flow, whose angle-of-attack bound has the window next to rest")
        if spec.rest_window_foil_rate_limit_rad_s is not None:
            _rest_window_rate_bound(opti, model, spec, limits, grid)
    _boundary_conditions(opti, model, spec, limits, grid, phi, start, end)
    _initial_guess(opti, model, spec, limits, grid, start, end, guess)

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
    """Bound |atan2(-V, U)| <= a at the collocation points ``angle_of_attack_bounded`` names.

    Written as U tan(a) -+ V >= 0, and the same at the three-quarter chord (docs/circulatory_primitives.md,
    "The problem").
    """
    if not 0.0 < limits.angle_of_attack_limit_rad < math.pi / 2:
        raise ValueError(f"{spec.primitive_id}: angle_of_attack_limit_rad must be in (0, pi/2), got "
                         f"{limits.angle_of_attack_limit_rad!r}")
    if not (math.isfinite(limits.angle_of_attack_free_from_rest_s) and limits.angle_of_attack_free_from_rest_s > 0.0):
        raise ValueError(f"{spec.primitive_id}: angle_of_attack_free_from_rest_s must be finite and > 0, got "
                         f"{limits.angle_of_attack_free_from_rest_s!r}")
    velocity = grid.fine(phi[foil_velocity_rows(model), :])[:, np.flatnonzero(angle_of_attack_bounded(spec, limits))]
    assert model.circulatory_flow is not None
    normal_34 = -(velocity[1, :] + model.circulatory_flow.three_quarter_chord_x_m * velocity[2, :])
    slope = math.tan(limits.angle_of_attack_limit_rad)
    for across in (velocity[1, :], normal_34):
        opti.subject_to(slope * velocity[0, :] - across >= 0.0)
        opti.subject_to(slope * velocity[0, :] + across >= 0.0)


def _stroke_bound(opti: ca.Opti, model: VehicleModel, spec: PrimitiveSpec, grid, phi: ca.MX) -> None:
    """Bound a cruise's Strouhal number 2 A f / U (primitives.cruise_strouhal_number) below by spec.min_strouhal.

    The pitch axis's excursion across the lane from the cycle's start (a turn of the heave) to its middle is at
    least St_min U / f = St_min R dalpha, with f one stroke per cycle and U = R dalpha / T. Affine in the NLP's
    variables; a peak-to-peak excursion is at least this one.
    """
    assert spec.min_strouhal is not None
    lateral_m = grid.fine(phi[lateral_row(model), :])
    middle = spec.intervals
    alpha_advance_rad = grid.x[0, -1] - grid.x[0, 0]
    opti.subject_to(lateral_m[0, 0] - lateral_m[0, middle]
                    - spec.min_strouhal * spec.lane_radius_m * alpha_advance_rad >= 0.0)


def _rest_window_rate_bound(opti: ca.Opti, model: VehicleModel, spec: PrimitiveSpec, limits: PlanningLimits,
                            grid) -> None:
    """Bound |heave rate| and |pitch rate| by PrimitiveSpec.rest_window_foil_rate_limit_rad_s (rad/s) next to rest.

    At the fine grid's points inside the window next to rest, where the angle-of-attack bound is off
    (docs/circulatory_primitives.md, "The problem").
    """
    assert spec.rest_window_foil_rate_limit_rad_s is not None
    nq = model.nq
    inside = np.flatnonzero(~angle_of_attack_bounded(spec, limits))
    rates = grid.all_states()[2 * nq - 2:2 * nq, :][:, inside]
    bound = spec.rest_window_foil_rate_limit_rad_s
    opti.subject_to(opti.bounded(-bound, rates, bound))


def rest_window_s(spec: PrimitiveSpec, limits: PlanningLimits) -> float:
    """The window next to rest (an accelerate's start, a decelerate's end) where the angle-of-attack bound is off.

    Parameters
    ----------
    spec : PrimitiveSpec
        Its ``rest_window_s``, if set, is the window.
    limits : PlanningLimits
        Else its ``angle_of_attack_free_from_rest_s``.

    Returns
    -------
    float
        The window, s.
    """
    return limits.angle_of_attack_free_from_rest_s if spec.rest_window_s is None else spec.rest_window_s


def angle_of_attack_bounded(spec: PrimitiveSpec, limits: PlanningLimits) -> npt.NDArray[np.bool_]:
    """Which of the fine grid's points carry the angle-of-attack bound.

    Parameters
    ----------
    spec : PrimitiveSpec
        The primitive (its type, horizon and intervals N).
    limits : PlanningLimits
        Gives the window next to rest (``rest_window_s``).

    Returns
    -------
    (2N + 1,) bool array
        True at every point but those within ``rest_window_s`` of rest (an accelerate's start, a decelerate's end).
    """
    times = fine_grid_times(spec.solved_duration_s, spec.intervals)
    if spec.primitive_type is PrimitiveType.ACCELERATE:
        from_rest_s = times
    elif spec.primitive_type is PrimitiveType.DECELERATE:
        from_rest_s = times[-1] - times
    else:
        return np.ones(times.shape, dtype=bool)
    # a rounding margin: a point at exactly the window's end carries the bound
    return from_rest_s >= rest_window_s(spec, limits) - 1e-9 * spec.solved_duration_s


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
    kind = spec.primitive_type
    if spec.end_lag_free and (kind is not PrimitiveType.DECELERATE or model.n_lag == 0):
        raise ValueError(f"{spec.primitive_id}: end_lag_free is for a decelerate with the circulatory flow")
    opti.subject_to(x0[0] == 0.0)
    if kind is PrimitiveType.CRUISE:
        if spec.energy_j is None:
            raise ValueError(f"{spec.primitive_id}: a cruise needs energy_j")
        opti.subject_to(x0[nq - 2:nq] == x_end[nq - 2:nq])          # psi periodic
        opti.subject_to(x0[nq:] == x_end[nq:])                      # qdot (and the lag states z) periodic
        if model.n_lag == 0:
            opti.subject_to(grid.knots(phi)[MOMENTUM_ROW, 0] == 0.0)    # reachable from rest: p_alpha = 0
        else:
            # the cut at a turn of the heave: a periodic cycle shifted in time is a cycle of the same index, a
            # continuous family of optima along which IPOPT's Hessian is singular (the constrained E = 0.05
            # cruise took 109 iterations without this row, 50 with it, to the same J within 2e-6). Every cycle
            # has a turn of the heave; alphadot(0) >= v_min is the only other condition on the cut, and the
            # circulatory cruises move forward throughout
            opti.subject_to(x0[2 * nq - 2] == 0.0)
        # cut the cycle where the vehicle moves forward: a decelerate from here can keep alphadot >= v_min
        opti.subject_to(x0[nq] >= limits.min_alpha_rate_rad_s)
        # energy level: the cycle's mean kinetic energy (docs/model_and_method.md section 3.1)
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
    if spec.end_lag_free:
        opti.subject_to(x_end[1:2 * nq] == ca.DM(end_x[1:2 * nq]))   # at rest, the lag states as they come
    else:
        opti.subject_to(_without_alpha(x_end, nq) == _without_alpha(ca.DM(end_x), nq))


def _initial_guess(opti: ca.Opti, model: VehicleModel, spec: PrimitiveSpec, limits: PlanningLimits, grid, start,
                   end, guess: Optional[Primitive]) -> None:
    times = fine_grid_times(spec.solved_duration_s, spec.intervals)
    if guess is not None and guess.spec.primitive_id == spec.primitive_id and len(guess.time_s) == len(times):
        x_guess, u_guess = np.column_stack([guess.q, guess.qdot, *_lag_columns(model, guess)]), guess.foil_acceleration
    elif spec.primitive_type is PrimitiveType.CRUISE and model.n_lag:
        x_guess, u_guess = _folded_cruise_guess(model, spec, limits, times)
    elif spec.primitive_type is PrimitiveType.CRUISE:
        x_guess, u_guess = _gait_guess(model, spec, times)
    elif spec.primitive_type is PrimitiveType.DECELERATE and model.n_lag and guess is not None:
        x_guess, u_guess = _still_foil_guess(model, spec, limits, times, start)
    elif spec.primitive_type is PrimitiveType.ACCELERATE and model.n_lag and guess is not None:
        x_guess, u_guess = _still_foil_guess(model, spec, limits, times, end)
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


def _folded_cruise_guess(model: VehicleModel, spec: PrimitiveSpec, limits: PlanningLimits,
                         times: Array) -> tuple[Array, Array]:
    """A circulatory cruise's guess: the folded posture, a small stroke and the steady flow's lag states.

    The heave link is folded inward near its limit (which lowers the hub's inertia), the foil pitched along its own
    velocity, the hub turning at the rate that holds the energy level, with a small stroke (pitch leading heave by
    90 deg) and the lag states of that steady flow. The cruises this flow solves to are close to it
    (docs/circulatory_primitives.md): a built-in guess of the ideal cruise's gait swum from rest took 112-157 IPOPT
    iterations to the constrained E = 0.05 cruise.
    """
    nq = model.nq
    heave_rad = limits.heave_range_rad - FOLDED_GUESS_HEAVE_AMPLITUDE_RAD - FOLDED_GUESS_HEAVE_MARGIN_RAD
    q_mean = np.zeros(nq)
    q_mean[nq - 2] = heave_rad
    if not model.constrained:
        q_mean[1] = spec.lane_radius_m
    hub_rate = np.zeros(nq)
    hub_rate[0] = 1.0

    def sideslip(theta_rad: float) -> float:   # V of the foil frame for a unit hub rate, m/s per rad/s
        posture = q_mean.copy()
        posture[nq - 1] = theta_rad
        return float((model.foil_velocity_map(posture) @ hub_rate)[1])

    pitches = np.linspace(-limits.pitch_range_rad, limits.pitch_range_rad, 29)   # 5 deg apart: enough for a guess
    q_mean[nq - 1] = pitches[int(np.argmin([abs(sideslip(p)) for p in pitches]))]
    mass = model.mass_matrix(q_mean)
    assert spec.energy_j is not None   # _boundary_conditions refused a cruise without one
    alpha_rate = math.sqrt(2.0 * spec.energy_j / mass[0, 0])   # T = 1/2 M_aa alphadot^2, the stroke neglected
    omega = 2.0 * math.pi / spec.solved_duration_s
    amplitudes = np.array([FOLDED_GUESS_HEAVE_AMPLITUDE_RAD, FOLDED_GUESS_PITCH_AMPLITUDE_RAD])
    phase = np.column_stack([omega * times, omega * times + 0.5 * math.pi])
    q = np.tile(q_mean, (len(times), 1))
    qdot = np.zeros_like(q)
    q[:, 0] = alpha_rate * times
    qdot[:, 0] = alpha_rate
    q[:, nq - 2:] += amplitudes * np.sin(phase)
    qdot[:, nq - 2:] = amplitudes * omega * np.cos(phase)
    u = -amplitudes * omega ** 2 * np.sin(phase)
    return np.column_stack([q, qdot, _steady_lag(model, q, qdot)]), u


def _steady_lag(model: VehicleModel, q: Array, qdot: Array) -> Array:
    """The lag states of a steady flow at each sample (samples, n_lag), m/s.

    Each is at the three-quarter chord's normal velocity -(V + Omega x_34), where its rate vanishes
    (swim_model.flow).
    """
    assert model.circulatory_flow is not None
    x34 = model.circulatory_flow.three_quarter_chord_x_m
    normal = np.array([-(v + w * x34) for _, v, w in (model.foil_velocity_map(a) @ b for a, b in zip(q, qdot))])
    return np.tile(normal[:, None], (1, model.n_lag))


def _smoothstep(x: Array) -> tuple[Array, Array, Array]:
    """s(x) = 3x^2 - 2x^3 on [0, 1] (0 before, 1 after) and its first two derivatives."""
    x = np.clip(x, 0.0, 1.0)
    inside = (x > 0.0) & (x < 1.0)
    return 3 * x ** 2 - 2 * x ** 3, (6 * x - 6 * x ** 2) * inside, (6 - 12 * x) * inside


def _still_foil_guess(model: VehicleModel, spec: PrimitiveSpec, limits: PlanningLimits, times: Array,
                      moving: tuple[Array, ...]) -> tuple[Array, Array]:
    """A circulatory accelerate's or decelerate's guess inside the angle-of-attack bound.

    The foil is held still in the posture of ``moving`` (the cruise's boundary state it joins; its stroke dropped),
    so it moves with the hub only, along its own chord, while the hub's rate goes smoothly between 0 and the
    cruise's; in the window next to rest where the bound is off (``rest_window_s``) the foil turns between rest and
    that posture with the hub still. The guess neither thrusts nor brakes: IPOPT finds the stroke. The blend of the
    boundary states has the foil broadside to its motion: from the blend with the cruise's stroke IPOPT found the
    constrained E = 0.05 decelerate (also from the plain blend) and the E = 0.10 and 0.20 accelerates infeasible.
    """
    nq = model.nq
    q_moving, qdot_moving = np.asarray(moving[0], dtype=float), np.asarray(moving[1], dtype=float)
    window_s = min(rest_window_s(spec, limits), 0.5 * times[-1])
    stop_s = times[-1] - window_s
    # built as a decelerate (moving at t = 0, at rest at the end), then mirrored in time for an accelerate
    q = np.tile(q_moving, (len(times), 1))
    qdot = np.zeros_like(q)
    qdot[:, 0] = qdot_moving[0] * (1.0 - _smoothstep(times / stop_s)[0])
    fold, fold_rate, fold_acceleration = _smoothstep((times - stop_s) / window_s)
    posture = q_moving[nq - 2:]
    q[:, nq - 2:] = posture * (1.0 - fold[:, None])
    qdot[:, nq - 2:] = -posture * fold_rate[:, None] / window_s
    u = -posture * fold_acceleration[:, None] / window_s ** 2
    if spec.primitive_type is PrimitiveType.ACCELERATE:
        q, u = q[::-1].copy(), u[::-1].copy()
        qdot = qdot[::-1].copy()
        qdot[:, nq - 2:] *= -1.0          # the shape runs backwards; the hub still turns forward
    q[:, 0] = np.concatenate([[0.0], np.cumsum(0.5 * (qdot[1:, 0] + qdot[:-1, 0]) * np.diff(times))])
    return np.column_stack([q, qdot, _steady_lag(model, q, qdot)]), u


def _blend_guess(model: VehicleModel, spec: PrimitiveSpec, times: Array, start, end,
                 cruise: Optional[Primitive]) -> tuple[Array, Array]:
    """Blend between the boundary states, with a given cruise's stroke faded in, out or kept.

    With a cruise given, fade its stroke in (accelerate), out (decelerate), or keep it (between cruises), so the
    guess already swims in the right phase.
    """
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
    stroke, rates, accel = (_interpolated_columns(phase, cruise.time_s[one], values[one])
                            for values in (cruise.q, cruise.qdot, cruise.foil_acceleration))
    envelope = {PrimitiveType.ACCELERATE: weight, PrimitiveType.DECELERATE: 1.0 - weight}.get(
        spec.primitive_type, np.ones_like(weight))  # between cruises: keep stroking
    x_guess[:, nq - 2:nq] = envelope * stroke[:, nq - 2:]
    x_guess[:, 2 * nq - 2:2 * nq] = envelope * rates[:, nq - 2:]
    if model.n_lag:
        lags = _lag_columns(model, cruise)[0]
        x_guess[:, 2 * nq:] = envelope * _interpolated_columns(phase, cruise.time_s[one], lags[one])
    mean_rate = (cruise.q[-1, 0] - cruise.q[0, 0]) / cruise.time_s[-1]
    x_guess[:, nq] = envelope[:, 0] * mean_rate
    x_guess[:, 0] = np.concatenate([[0.0], np.cumsum(0.5 * (x_guess[1:, nq] + x_guess[:-1, nq]) * np.diff(times))])
    return x_guess, envelope * accel
