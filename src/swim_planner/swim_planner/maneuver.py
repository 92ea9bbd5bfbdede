"""Maneuvers: primitives concatenated and time-scaled (paper Secs. 4.2-4.3; docs/model_and_method.md section 4).

Concatenation: each primitive starts where the previous one ended; its alpha is translated by the
previous end value (Prop. 1), and the junction is checked: the states (all but alpha) must agree within
JUNCTION_TOLERANCE, else the request is refused with the mismatch named, never spliced over. Our
primitives are solved with equal junction states including qdot, so the plan's qdot is continuous there;
only u = psiddot may jump. Primitives solved with the circulatory flow model carry the flow's lag states z
(m/s), which join like the velocities (within JUNCTION_TOLERANCE) and make a plan with flow_model "circulatory";
a plan never mixes primitives of the two flow models.

The plan is a swim_control.trajectory.Trajectory: made at lambda = 1 (each sample carries K = R^-1 G'P and
the Riccati input gain G'P of its primitive), then time-scaled by ``Trajectory.time_scaled`` (P3 and Theorem 1:
t -> t / lambda, q(t) -> q(lambda t), qdot -> lambda qdot, u -> lambda^2 u, tau -> lambda^2 tau, z -> lambda z,
K -> lambda R^-1 (G'P) Gamma(lambda), G'P -> (G'P) Gamma(lambda)), which refuses a lambda whose torques exceed
the motor limits. The tracker's law is then u = u_des - K x.

The sliding mode's disturbance bound D(t) (N m; swim_planner.disturbance) joins like the torques: each
primitive's stored samples in turn (the junction sample the earlier one's), scaled by lambda^2. A plan carries it
only if every one of its primitives has one stored (a library that is a ``DisturbanceBounds``); otherwise it carries
none and the tracker uses its constant bound.

A slowly varying lambda (Sec. 4.3): with s the nominal (lambda = 1) plan time and lambda(s) given,
the plan runs t(s) = int_0^s ds' / lambda(s'), q(t) = q_nom(s), qdot = lambda qdot_nom(s),
u = lambda^2 u_nom(s) + lambdadot qdot_nom, tau = lambda^2 tau_nom(s), z = lambda z_nom(s) and D = lambda^2 D_nom(s)
(the flow forces at the velocities lambda qdot_nom; swim_control.trajectory); the torque the
lambdadot term would need (lambdadot Mm qdot_nom) is left to feedback, as in the paper.
"""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Callable, Optional, Protocol, Sequence, runtime_checkable

import numpy as np
import numpy.typing as npt

from swim_control.errors import PlanError
from swim_control.riccati import LqrWeights
from swim_control.time_scaling import lqr_gain_from, retime_feedback
from swim_control.trajectory import (
    MAX_ABS_START_ALPHA_RAD,
    MAX_TRACKED_SAMPLES,
    Segment,
    Trajectory,
    motor_limit_fraction,
)
from swim_model import RigParameters
from swim_planner.errors import LibraryError, ManeuverError
from swim_planner.primitives import Primitive, PrimitiveSpec

Array = npt.NDArray[np.float64]

#: largest junction mismatch accepted: rad, m, rad/s, m/s (the lag states are velocities, m/s)
JUNCTION_TOLERANCE = 1e-5


def junction_mismatch(previous: Primitive, following: Primitive, lag_states: bool = True) -> float:
    """The largest difference between one primitive's end state and the next one's start state, alpha aside.

    Parameters
    ----------
    previous : Primitive
        The earlier primitive (its ``end_boundary_state``).
    following : Primitive
        The later primitive (its ``start_boundary_state``).
    lag_states : bool, optional
        Compare the lag states too, where both have them.

    Returns
    -------
    float
        The largest absolute difference over q (alpha aside), qdot and the lag states: rad, m, rad/s, m/s.

    References
    ----------
    Saimek & Li 2004, Sec. 4.2 and Prop. 1 (alpha is free up to a translation).
    """
    q_end, qdot_end, *lag_end = previous.end_boundary_state
    q_start, qdot_start, *lag_start = following.start_boundary_state
    gaps = [np.abs(q_end[1:] - q_start[1:]).max(), np.abs(qdot_end - qdot_start).max()]
    if lag_states:
        gaps += [np.abs(a - b).max() for a, b in zip(lag_end, lag_start)]
    return float(max(gaps))


def flow_model_of(primitives: Sequence[Primitive]) -> str:
    """The flow model a plan's primitives were solved with.

    Parameters
    ----------
    primitives : sequence of Primitive
        The plan's primitives, at least one.

    Returns
    -------
    str
        "circulatory" if they carry lag states, else "ideal".

    Raises
    ------
    ManeuverError
        If they mix the two.
    """
    flows = {"ideal" if p.lag is None else "circulatory" for p in primitives}
    if len(flows) != 1:
        raise ManeuverError("a plan cannot mix primitives of the ideal and the circulatory flow models "
                            f"({', '.join(sorted({p.spec.primitive_id for p in primitives if p.lag is not None}))} "
                            "carry lag states)")
    return flows.pop()


class PlanLibrary(Protocol):
    """What concatenation reads of a library: a PrimitiveLibrary, or a gains.RetunedLibrary view of one.

    Attributes
    ----------
    path : Path
        The library's directory (named in error messages).
    lqr_weights : LqrWeights
        The weights its stored gains were computed with (R gives K = R^-1 G'P).
    """

    path: Path
    lqr_weights: LqrWeights

    def __contains__(self, primitive_id: str) -> bool:
        """Whether the library holds a primitive of this id."""
        ...

    def spec(self, primitive_id: str) -> PrimitiveSpec:
        """The spec of a primitive: what it is.

        Parameters
        ----------
        primitive_id : str
            The primitive whose spec is asked for.
        """
        ...

    def get(self, primitive_id: str) -> Primitive:
        """A primitive, read and verified: its samples and gains.

        Parameters
        ----------
        primitive_id : str
            The primitive wanted.
        """
        ...

    def sample_count(self, primitive_id: str) -> int:
        """The number N of samples in a primitive's arrays.

        Parameters
        ----------
        primitive_id : str
            The primitive asked about.
        """
        ...

    def digest(self) -> str:
        """The library's digest, which names it in a plan.

        Returns
        -------
        str
            A SHA-256 hex digest.
        """
        ...


@runtime_checkable
class DisturbanceBounds(Protocol):
    """A library that stores the sliding mode's bound D(t) per primitive (PrimitiveLibrary)."""

    def disturbance_bound(self, primitive_id: str) -> Optional[Array]:
        """The stored D(t) of a primitive.

        Parameters
        ----------
        primitive_id : str
            The primitive whose D(t) is asked for.

        Returns
        -------
        (N,) array or None
            D(t), N m on the primitive's samples; None if none is stored.
        """
        ...


def stored_disturbance_bounds(library: PlanLibrary, primitive_ids: Sequence[str]) -> Optional[list[Array]]:
    """Each primitive's stored sliding-mode bound D(t), if the library stores one for every one.

    Parameters
    ----------
    library : PlanLibrary
        The library (one that is not a ``DisturbanceBounds`` stores none).
    primitive_ids : sequence of str
        The plan's primitives, in order.

    Returns
    -------
    list of (N_i,) array or None
        D(t), N m on each primitive's samples; None unless every one has one.
    """
    if not isinstance(library, DisturbanceBounds):
        return None
    bounds = [library.disturbance_bound(pid) for pid in primitive_ids]
    if any(bound is None for bound in bounds):
        return None
    return [bound for bound in bounds if bound is not None]


@dataclasses.dataclass(frozen=True)
class PlanBounds:
    """The largest plan a request may ask for. A request past a bound is refused by name before any work.

    Attributes
    ----------
    max_duration_s : float
        The longest plan, s (assumed: two hours of swimming).
    max_samples : int
        The most samples a plan may have (the tracker's ``MAX_TRACKED_SAMPLES``).
    max_abs_start_alpha_rad : float
        The largest |alpha| a plan may start from, rad.
    """

    max_duration_s: float = 7200.0
    # assumed: two hours of swimming, longer than any run on the rig; a 1000-cruise plan (5008 s) fits
    max_samples: int = MAX_TRACKED_SAMPLES
    # the largest plan the tracker accepts (its reason is there)
    max_abs_start_alpha_rad: float = MAX_ABS_START_ALPHA_RAD
    # the largest start the simulator sets too (its reason is there)

    def validate(self) -> None:
        """Check the bounds.

        Raises
        ------
        ValueError
            Unless every bound is positive and finite.
        """
        for field in dataclasses.fields(self):
            value = getattr(self, field.name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"plan bound {field.name} must be a positive finite number, got {value!r}")


DEFAULT_BOUNDS = PlanBounds()


def check_plan_size(library: PlanLibrary, primitive_ids: Sequence[str], repeat_counts: Sequence[int],
                    time_scale: float, bounds: PlanBounds = DEFAULT_BOUNDS) -> None:
    """Refuse a sequence with an unknown primitive or whose plan would pass the bounds, from the specs alone.

    Nothing is expanded or built. Mismatched lengths are left to ``expand_sequence``.

    Parameters
    ----------
    library : PlanLibrary
        The library the primitives come from.
    primitive_ids : sequence of str
        The primitives, in order.
    repeat_counts : sequence of int
        How often each runs (empty: once each).
    time_scale : float
        lambda > 0.
    bounds : PlanBounds, optional
        The largest plan served.

    Raises
    ------
    ManeuverError
        For a bad time scale, an unknown primitive, or a plan past the duration or sample bound.
    """
    check_time_scale(time_scale)
    check_known(library, primitive_ids)
    counts = list(repeat_counts) or [1] * len(primitive_ids)
    known = [(pid, int(count)) for pid, count in zip(primitive_ids, counts) if pid in library]
    duration_s = sum(library.spec(pid).duration_s * count for pid, count in known) / time_scale
    if duration_s > bounds.max_duration_s:
        raise ManeuverError(f"the plan would last {duration_s:.6g} s, longer than the longest plan served "
                            f"({bounds.max_duration_s:g} s; planner_node parameter max_plan_duration_s)")
    samples = sum(library.sample_count(pid) * count for pid, count in known)
    if samples > bounds.max_samples:
        raise ManeuverError(f"the plan would have {samples} samples, more than the largest plan served "
                            f"({bounds.max_samples}; planner_node parameter max_plan_samples)")


def check_known(library: PlanLibrary, primitive_ids: Sequence[str]) -> None:
    """Refuse primitive ids that are not in the library, naming them.

    Parameters
    ----------
    library : PlanLibrary
        The library.
    primitive_ids : sequence of str
        The ids asked for.

    Raises
    ------
    ManeuverError
        If any id is not in the library.
    """
    unknown = sorted({pid for pid in primitive_ids if pid not in library})
    if unknown:
        raise ManeuverError(f"unknown primitives: {', '.join(unknown)} (see `swim-primitives list`)")


def check_start_alpha(start_alpha_rad: float, bounds: PlanBounds = DEFAULT_BOUNDS) -> None:
    """Refuse a start alpha that is not finite or past the bound.

    Parameters
    ----------
    start_alpha_rad : float
        The alpha the plan starts from, rad.
    bounds : PlanBounds, optional
        Gives the largest |alpha|.

    Raises
    ------
    ManeuverError
        If it is not finite or |alpha| exceeds ``bounds.max_abs_start_alpha_rad``.
    """
    if not (math.isfinite(start_alpha_rad) and abs(start_alpha_rad) <= bounds.max_abs_start_alpha_rad):
        raise ManeuverError(f"start alpha must be finite and within +-{bounds.max_abs_start_alpha_rad:g} rad, "
                            f"got {start_alpha_rad!r}")


def check_time_scale(time_scale: float) -> None:
    """Refuse a time scale that is not a positive finite number.

    Parameters
    ----------
    time_scale : float
        lambda.

    Raises
    ------
    ManeuverError
        Unless lambda is a positive finite number.
    """
    if not (isinstance(time_scale, (int, float)) and math.isfinite(time_scale) and time_scale > 0.0):
        raise ManeuverError(f"time scale must be a positive finite number, got {time_scale!r}")


def expand_sequence(primitive_ids: Sequence[str], repeat_counts: Sequence[int]) -> list[tuple[str, int]]:
    """The sequence of a request: each primitive with its repeat index.

    Parameters
    ----------
    primitive_ids : sequence of str
        The primitives, in order, at least one.
    repeat_counts : sequence of int
        How often each runs, each >= 1, as many as ids (empty: once each).

    Returns
    -------
    list of (str, int)
        [(id, repeat_index), ...], repeat_index from 0.

    Raises
    ------
    ManeuverError
        If the sequence is empty, the counts' length differs from the ids', or a count is below 1.
    """
    counts = list(repeat_counts) or [1] * len(primitive_ids)
    if len(counts) != len(primitive_ids):
        raise ManeuverError(f"{len(primitive_ids)} primitive ids but {len(counts)} repeat counts")
    if not primitive_ids:
        raise ManeuverError("the sequence is empty")
    if any(int(c) < 1 for c in counts):
        raise ManeuverError("every repeat count must be at least 1")
    return [(pid, k) for pid, count in zip(primitive_ids, counts) for k in range(int(count))]


def concatenate(library: PlanLibrary, rig: RigParameters, sequence: Sequence[tuple[str, int]],
                time_scale: float = 1.0, start_alpha_rad: float = 0.0) -> Trajectory:
    """The plan that runs primitives one after another at one time scale (module docstring).

    Parameters
    ----------
    library : PlanLibrary
        The primitives and their gains.
    rig : RigParameters
        Gives the motor torque limits the time-scaled plan must keep.
    sequence : sequence of (str, int)
        (id, repeat_index) in order (``expand_sequence``).
    time_scale : float, optional
        lambda > 0.
    start_alpha_rad : float, optional
        The alpha the plan starts from, rad.

    Returns
    -------
    Trajectory
        The concatenated plan, time-scaled.

    Raises
    ------
    ManeuverError
        For a bad time scale or start, an unknown or ungained primitive, mixed constrained and free primitives or
        flow models, a junction whose states differ by more than ``JUNCTION_TOLERANCE``, an unreadable library, or
        a lambda whose torques exceed the motor limits.

    References
    ----------
    Saimek & Li 2004, Secs. 4.2-4.3, Prop. 1, P3 and Theorem 1; docs/model_and_method.md section 4.
    """
    check_time_scale(time_scale)
    check_start_alpha(start_alpha_rad)
    check_known(library, [pid for pid, _ in sequence])
    try:
        primitives = [library.get(pid) for pid, _ in sequence]
    except LibraryError as err:
        raise ManeuverError(str(err)) from err
    ungained = sorted({pid for (pid, _), p in zip(sequence, primitives) if p.gains is None})
    if ungained:
        raise ManeuverError(f"no tracking gains stored for {', '.join(ungained)} (for the library's LQ weights); "
                            f"run `swim-primitives build {library.path}` to compute them")
    kinds = {p.spec.constrained for p in primitives}
    if len(kinds) != 1:
        raise ManeuverError("a plan cannot mix constrained and free primitives")
    flow_model = flow_model_of(primitives)
    try:
        disturbance_bounds = stored_disturbance_bounds(library, [pid for pid, _ in sequence])
    except LibraryError as err:
        raise ManeuverError(str(err)) from err
    for (pid_a, _), (pid_b, _), a, b in zip(sequence, sequence[1:], primitives, primitives[1:]):
        mismatch = junction_mismatch(a, b)
        if mismatch > JUNCTION_TOLERANCE:
            raise ManeuverError(f"'{pid_a}' does not end where '{pid_b}' starts (states differ by {mismatch:.3g}; "
                                f"tolerance {JUNCTION_TOLERANCE:g})")
    pieces: list[tuple[Array, ...]] = []
    segments: list[Segment] = []
    clock, alpha, sample = 0.0, float(start_alpha_rad), 0
    weights = library.lqr_weights
    input_weights = np.array([weights.heave_input_weight, weights.pitch_input_weight])
    for index, ((pid, repeat), primitive) in enumerate(zip(sequence, primitives)):
        assert primitive.gains is not None   # checked above: ungained primitives are refused
        riccati_input_gain = primitive.gains.riccati_input_gain
        t = primitive.time_s
        q = primitive.q.copy()
        offset = alpha - q[0, 0]
        q[:, 0] += offset
        skip = 0 if index == 0 else 1  # the junction sample is the previous segment's last
        optional = [] if primitive.lag is None else [primitive.lag[skip:]]   # then D(t), if stored
        if disturbance_bounds is not None:
            optional.append(disturbance_bounds[index][skip:])
        pieces.append((t[skip:] + clock, q[skip:], primitive.qdot[skip:], primitive.foil_acceleration[skip:],
                       primitive.torque[skip:], lqr_gain_from(riccati_input_gain[skip:], input_weights),
                       riccati_input_gain[skip:], *optional))
        count = len(t) - skip
        segments.append(Segment(pid, primitive.spec.primitive_type.value, repeat, clock, float(t[-1]), 1.0,
                                offset, sample, count))
        clock += float(t[-1])
        alpha = float(q[-1, 0])
        sample += count
    time_s, q, qdot, u, tau, lqr_gain, riccati_input_gain, *optional_rows = (np.concatenate(parts)
                                                                              for parts in zip(*pieces))
    bound_rows = [optional_rows.pop()] if disturbance_bounds is not None else []
    lag_rows = optional_rows
    nominal = Trajectory(time_s=time_s, q=q, qdot=qdot, foil_acceleration=u, torque=tau, lqr_gain=lqr_gain,
                         riccati_input_gain=riccati_input_gain, segments=tuple(segments),
                         lane_radius_m=primitives[0].spec.lane_radius_m, library_digest=library.digest(),
                         flow_model=flow_model, lag=lag_rows[0] if lag_rows else None,
                         disturbance_bound=bound_rows[0] if bound_rows else None)
    try:
        return nominal.time_scaled(time_scale, rig.torque_limits_n_m)
    except PlanError as err:
        raise ManeuverError(str(err)) from err


def vary_time_scale(nominal: Trajectory, time_scale_of: Callable[[float], float], rig: RigParameters) -> Trajectory:
    """Re-time a plan made at lambda = 1 by a slowly varying lambda(s) of the nominal time s (module docstring).

    A constant lambda is ``Trajectory.time_scaled``.

    Parameters
    ----------
    nominal : Trajectory
        A plan made at time scale 1.
    time_scale_of : callable
        lambda(s) > 0 of the nominal time s (s).
    rig : RigParameters
        Gives the motor torque limits.

    Returns
    -------
    Trajectory
        The re-timed plan.

    Raises
    ------
    ManeuverError
        If the plan is not at time scale 1, lambda(s) is not positive and finite, or the torques exceed the limits.

    References
    ----------
    Saimek & Li 2004, Sec. 4.3.
    """
    for segment in nominal.segments:
        if segment.time_scale != 1.0:
            raise ManeuverError("vary_time_scale re-times a plan made at time scale 1")
    nominal_time = nominal.time_s
    scale = np.array([float(time_scale_of(s)) for s in nominal_time])
    if not np.all(np.isfinite(scale)) or scale.min() <= 0.0:
        raise ManeuverError("lambda(s) must be positive and finite over the whole plan")
    if np.all(scale == scale[0]):
        try:
            return nominal.time_scaled(float(scale[0]), rig.torque_limits_n_m)
        except PlanError as err:
            raise ManeuverError(str(err)) from err
    peak = motor_limit_fraction(nominal.torque * scale[:, None] ** 2, rig.torque_limits_n_m)
    if peak > 1.0:
        raise ManeuverError(f"lambda(s) needs {peak:.0%} of the motor torque limits")
    inverse = 1.0 / scale
    time_s = np.concatenate([[0.0], np.cumsum(0.5 * (inverse[1:] + inverse[:-1]) * np.diff(nominal_time))])
    scale_rate = np.gradient(scale, time_s)   # d lambda / dt
    foil_acceleration = scale[:, None] ** 2 * nominal.foil_acceleration + \
        scale_rate[:, None] * nominal.qdot[:, -2:]
    segments = []
    for segment in nominal.segments:
        first, last = segment.first_sample, segment.first_sample + segment.sample_count - 1
        start = float(time_s[first - 1]) if first > 0 else 0.0
        segments.append(dataclasses.replace(
            segment, start_time_s=start, duration_s=float(time_s[last] - start),
            time_scale=float(scale[max(first - 1, 0):last + 1].mean())))
    lqr_gain, riccati_input_gain = retime_feedback(nominal.lqr_gain, nominal.riccati_input_gain, scale,
                                                   nominal.ny, nominal.nq, nominal.n_lag)
    return dataclasses.replace(nominal, time_s=time_s, qdot=nominal.qdot * scale[:, None],
                               foil_acceleration=foil_acceleration,
                               torque=nominal.torque * scale[:, None] ** 2, lqr_gain=lqr_gain,
                               riccati_input_gain=riccati_input_gain, segments=tuple(segments),
                               lag=None if nominal.lag is None else nominal.lag * scale[:, None],
                               disturbance_bound=None if nominal.disturbance_bound is None
                               else nominal.disturbance_bound * scale ** 2)
