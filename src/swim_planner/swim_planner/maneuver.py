"""Maneuvers: primitives concatenated and time-scaled (paper Secs. 4.2-4.3; docs/model_and_method.md section 4).

Concatenation: each primitive starts where the previous one ended; its alpha is translated by the
previous end value (Prop. 1), and the junction is checked: the states (all but alpha) must agree within
JUNCTION_TOLERANCE, else the request is refused with the mismatch named, never spliced over. Our
primitives are solved with equal junction states including qdot, so the plan's qdot is continuous there;
only u = psiddot may jump.

Time scaling by lambda > 0 (P3): t -> t / lambda, q(t) -> q(lambda t), qdot -> lambda qdot,
u -> lambda^2 u, tau -> lambda^2 tau. A lambda whose torques exceed the motor limits is refused.

Tracking gains go along (Theorem 1; swim_controller.time_scaling): each sample carries K = lambda R^-1 (G'P)
Gamma(lambda) and G_l'P_l = (G'P) Gamma(lambda) of its primitive, so the tracker's law is u = u_des - K x.

A slowly varying lambda (Sec. 4.3): with s the nominal (lambda = 1) plan time and lambda(s) given,
the plan runs t(s) = int_0^s ds' / lambda(s'), q(t) = q_nom(s), qdot = lambda qdot_nom(s),
u = lambda^2 u_nom(s) + lambdadot qdot_nom and tau = lambda^2 tau_nom(s); the torque the lambdadot term
would need (lambdadot Mm qdot_nom) is left to feedback, as in the paper.
"""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Callable, Protocol, Sequence

import numpy as np
import numpy.typing as npt

from swim_controller.riccati import LqrWeights
from swim_controller.time_scaling import retime_feedback, scale_feedback
from swim_model import RigParameters
from swim_model.vehicle import JOINT_NAMES_CONSTRAINED, JOINT_NAMES_UNCONSTRAINED
from swim_planner.errors import LibraryError, ManeuverError
from swim_planner.primitives import Primitive, PrimitiveSpec

Array = npt.NDArray[np.float64]

#: largest junction mismatch accepted: rad, m, rad/s, m/s
JUNCTION_TOLERANCE = 1e-5


@dataclasses.dataclass(frozen=True)
class Segment:
    primitive_id: str
    primitive_type: str
    repeat_index: int
    start_time_s: float
    duration_s: float
    time_scale: float
    alpha_offset_rad: float
    first_sample: int
    sample_count: int


@dataclasses.dataclass
class Plan:
    """A concatenated, time-scaled plan on its sample grid."""

    constrained: bool
    lane_radius_m: float
    joint_names: tuple[str, ...]
    time_s: Array
    q: Array
    qdot: Array
    foil_acceleration: Array
    torque: Array
    lqr_gain: Array       # (N, 2, n) K of eq. 33, time-scaled
    sliding_gain: Array   # (N, 2, n) G_l' P_l (eq. 24), time-scaled
    segments: list[Segment]
    library_digest: str

    @property
    def duration_s(self) -> float:
        return float(self.time_s[-1])


def scale_primitive(primitive: Primitive, time_scale: float) -> tuple[Array, Array, Array, Array, Array]:
    """(t, q, qdot, u, tau) of a primitive run lambda times faster (P3)."""
    return (primitive.time_s / time_scale, primitive.q, primitive.qdot * time_scale,
            primitive.foil_acceleration * time_scale ** 2, primitive.torque * time_scale ** 2)


def junction_mismatch(previous: Primitive, following: Primitive) -> float:
    """Largest difference between previous's end state and following's start state, alpha aside."""
    q_end, qdot_end = previous.end_state
    q_start, qdot_start = following.start_state
    return float(max(np.abs(q_end[1:] - q_start[1:]).max(), np.abs(qdot_end - qdot_start).max()))


class PlanLibrary(Protocol):
    """What concatenation reads of a library: a PrimitiveLibrary, or a gains.RetunedLibrary view of one."""

    path: Path
    lqr_weights: LqrWeights

    def __contains__(self, primitive_id: str) -> bool: ...

    def spec(self, primitive_id: str) -> PrimitiveSpec: ...

    def get(self, primitive_id: str) -> Primitive: ...

    def sample_count(self, primitive_id: str) -> int: ...

    def digest(self) -> str: ...


@dataclasses.dataclass(frozen=True)
class PlanBounds:
    """The largest plan a request may ask for. A request past a bound is refused by name before any work."""

    max_duration_s: float = 7200.0
    # assumed: two hours of swimming, longer than any run on the rig; a 1000-cruise plan (5008 s) fits
    max_samples: int = 1_000_000
    # assumed from memory: a free-vehicle sample is 52 float64 (416 B), so 1e6 samples hold ~0.4 GB in the plan
    # and as much again in its message
    max_abs_start_alpha_rad: float = 1.0e6
    # assumed: float64 keeps alpha to 1e-10 rad up to here (and swimming 1e6 rad would take weeks)

    def validate(self) -> None:
        """ValueError unless every bound is positive and finite."""
        for field in dataclasses.fields(self):
            value = getattr(self, field.name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"plan bound {field.name} must be a positive finite number, got {value!r}")


DEFAULT_BOUNDS = PlanBounds()


def check_plan_size(library: PlanLibrary, primitive_ids: Sequence[str], repeat_counts: Sequence[int],
                    time_scale: float, bounds: PlanBounds = DEFAULT_BOUNDS) -> None:
    """Refuse (ManeuverError) a sequence whose plan would pass bounds, from the library's specs alone: nothing
    is expanded or built. Unknown ids and mismatched lengths are left to concatenate and expand_sequence."""
    check_time_scale(time_scale)
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


def check_start_alpha(start_alpha_rad: float, bounds: PlanBounds = DEFAULT_BOUNDS) -> None:
    if not (math.isfinite(start_alpha_rad) and abs(start_alpha_rad) <= bounds.max_abs_start_alpha_rad):
        raise ManeuverError(f"start alpha must be finite and within +-{bounds.max_abs_start_alpha_rad:g} rad, "
                            f"got {start_alpha_rad!r}")


def check_time_scale(time_scale: float) -> None:
    if not (isinstance(time_scale, (int, float)) and math.isfinite(time_scale) and time_scale > 0.0):
        raise ManeuverError(f"time scale must be a positive finite number, got {time_scale!r}")


def expand_sequence(primitive_ids: Sequence[str], repeat_counts: Sequence[int]) -> list[tuple[str, int]]:
    """[(id, repeat_index), ...] from ids and repeat counts (an empty counts list means once each)."""
    counts = list(repeat_counts) or [1] * len(primitive_ids)
    if len(counts) != len(primitive_ids):
        raise ManeuverError(f"{len(primitive_ids)} primitive ids but {len(counts)} repeat counts")
    if not primitive_ids:
        raise ManeuverError("the sequence is empty")
    if any(int(c) < 1 for c in counts):
        raise ManeuverError("every repeat count must be at least 1")
    return [(pid, k) for pid, count in zip(primitive_ids, counts) for k in range(int(count))]


def concatenate(library: PlanLibrary, rig: RigParameters, sequence: Sequence[tuple[str, int]],
                time_scale: float = 1.0, start_alpha_rad: float = 0.0) -> Plan:
    """The plan that runs the primitives of ``sequence`` one after another at time scale lambda."""
    check_time_scale(time_scale)
    check_start_alpha(start_alpha_rad)
    unknown = sorted({pid for pid, _ in sequence if pid not in library})
    if unknown:
        raise ManeuverError(f"unknown primitives: {', '.join(unknown)} (see `swim-primitives list`)")
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
    for (pid_a, _), (pid_b, _), a, b in zip(sequence, sequence[1:], primitives, primitives[1:]):
        mismatch = junction_mismatch(a, b)
        if mismatch > JUNCTION_TOLERANCE:
            raise ManeuverError(f"'{pid_a}' does not end where '{pid_b}' starts (states differ by {mismatch:.3g}; "
                                f"tolerance {JUNCTION_TOLERANCE:g})")
    limits = np.array(rig.torque_limits_n_m)
    peak = max(float((np.abs(p.torque) / limits).max()) for p in primitives) * time_scale ** 2
    if peak > 1.0:
        raise ManeuverError(f"time scale {time_scale:g} needs {peak:.0%} of the motor torque limits; "
                            f"the largest feasible time scale for this sequence is {time_scale / math.sqrt(peak):.3f}")
    pieces: list[tuple[Array, ...]] = []
    segments: list[Segment] = []
    clock, alpha, sample = 0.0, float(start_alpha_rad), 0
    weights = library.lqr_weights
    input_weights = np.array([weights.heave_input_weight, weights.pitch_input_weight])
    ny, nq = primitives[0].q.shape[1] - 2, primitives[0].q.shape[1]
    for index, ((pid, repeat), primitive) in enumerate(zip(sequence, primitives)):
        t, q, qdot, u, tau = scale_primitive(primitive, time_scale)
        assert primitive.gains is not None   # checked above: ungained primitives are refused
        lqr_gain, sliding_gain = scale_feedback(primitive.gains.input_gain, input_weights, time_scale, ny, nq)
        q = q.copy()
        offset = alpha - q[0, 0]
        q[:, 0] += offset
        skip = 0 if index == 0 else 1  # the junction sample is the previous segment's last
        pieces.append((t[skip:] + clock, q[skip:], qdot[skip:], u[skip:], tau[skip:], lqr_gain[skip:],
                       sliding_gain[skip:]))
        count = len(t) - skip
        segments.append(Segment(pid, primitive.spec.primitive_type.value, repeat, clock, float(t[-1]), time_scale,
                                offset, sample, count))
        clock += float(t[-1])
        alpha = float(q[-1, 0])
        sample += count
    time_s, q, qdot, u, tau, lqr_gain, sliding_gain = (np.concatenate(parts) for parts in zip(*pieces))
    first = primitives[0]
    names = JOINT_NAMES_CONSTRAINED if first.spec.constrained else JOINT_NAMES_UNCONSTRAINED
    return Plan(constrained=first.spec.constrained, lane_radius_m=first.spec.lane_radius_m, joint_names=names,
                time_s=time_s, q=q, qdot=qdot, foil_acceleration=u, torque=tau, lqr_gain=lqr_gain,
                sliding_gain=sliding_gain, segments=segments, library_digest=library.digest())


def vary_time_scale(nominal: Plan, time_scale_of: Callable[[float], float], rig: RigParameters) -> Plan:
    """Re-time a plan made at lambda = 1 by a slowly varying lambda(s) of the nominal time s."""
    for segment in nominal.segments:
        if segment.time_scale != 1.0:
            raise ManeuverError("vary_time_scale re-times a plan made at time scale 1")
    nominal_time = nominal.time_s
    scale = np.array([float(time_scale_of(s)) for s in nominal_time])
    if not np.all(np.isfinite(scale)) or scale.min() <= 0.0:
        raise ManeuverError("lambda(s) must be positive and finite over the whole plan")
    limits = np.array(rig.torque_limits_n_m)
    peak = float((np.abs(nominal.torque) * scale[:, None] ** 2 / limits).max())
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
    nq = nominal.q.shape[1]
    lqr_gain, sliding_gain = retime_feedback(nominal.lqr_gain, nominal.sliding_gain, scale, nq - 2, nq)
    return dataclasses.replace(nominal, time_s=time_s, qdot=nominal.qdot * scale[:, None],
                               foil_acceleration=foil_acceleration,
                               torque=nominal.torque * scale[:, None] ** 2, lqr_gain=lqr_gain,
                               sliding_gain=sliding_gain, segments=segments)
