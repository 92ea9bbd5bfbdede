"""The sliding mode's disturbance bound D(t) along a primitive, measured off-line.

How far the reduced flow model's force is from the vortex wake's (paper eqs. 24-25; docs/circulatory_primitives.md, "The
sliding mode's bound from the wake").

What is compared. Both flow models split the fluid's force on the foil the same way: the added-mass (Kirchhoff)
force of eq. 46 is in the equations of motion through Mm, and each adds only the rest, in foil axes at the foil
frame's origin F (fx N, fy N, mz N m, whole span):

* the reduced model (``swim_model.flow``, what the primitives were planned with): ``f_r = f(Q2 qdot, z)`` with the
  primitive's own lag states z, i.e. ``VehicleModel.flow_force``;
* the wake (``swim_model.wake``): ``f_w = F_v + profile drag``, the vortical force of the point-vortex wake shed by
  the foil moving along the primitive's prescribed motion, plus the reduced model's attached-flow profile drag
  (``CirculatoryFlow.profile_drag``), as ``towed_foil.py`` does for its ``model="wake"``: the wake is inviscid.

The wake needs the foil's history: it is started with no vortices at the start of the motion, and a primitive that
does not start from rest is given a lead-in (the primitives it joins, run before it: a cruise for a lane change),
or is measured on its last cycles only (``DisturbanceProfile.window``). The motion between the primitive's samples
is the cubic Hermite interpolant of q (slopes qdot) and the cubic spline of qdot (both fourth-order in the sample
spacing, and exact for a motion at constant velocity), stepped at ``max_wake_step_s`` or at the sample spacing if
finer; the wake's force, valid at the middle of each step, is interpolated linearly to the samples.

The mapping to the sliding mode's disturbance. The force difference ``df = f_w - f_r`` acts on the vehicle as the
generalized force ``dQ = Q2(q)' df`` (virtual work, as the flow and the wake enter the model). Split it as q is
split, ``dQ = (dQ_y, dQ_psi)`` (y: alpha [and R], psi: heave and pitch). Eliminating yddot from eqs. 14-15 with
dQ on the right-hand side gives

    Mio psiddot + Cio qdot = tau + d,      d = dQ_psi - Mm21 Mm11^-1 dQ_y = B' dQ,   B = [-Mm11^-1 Mm12; I],

so ``Mm^-1 dQ = B Mio^-1 d + [Mm11^-1 dQ_y; 0]``: the first term is exactly a torque d on the motors (the matched
disturbance of sliding_mode.py, entering the error system through G = [0; B]), the second is the acceleration dQ
gives the hub (and rails) with the foil held still, which no torque on the motors can cancel directly (the
unmatched part, reported beside d as ``unmatched_acceleration``). D(t) = ``margin`` ||d(t)||_2, the Euclidean
norm the sliding term uses (eps = -D s / max(||s||, phi)). d is in N m on the heave and pitch joints, the units
of the sliding mode's ``disturbance_bound_n_m``.

Time scaling: both flow models' forces are homogeneous of degree 2 in the velocities (the wake's up to its core
radius and least shedding distance), so a plan run lambda times faster meets lambda^2 D(lambda t).

What the library stores (``disturbance_job``, run by swim_planner.build for every circulatory primitive): D(t)'s
running maximum over +-ENVELOPE_HALF_WIDTH_S of each of the primitive's samples, measured with the wake's history
``lead_in_ids`` gives, one scalar (N m) a sample: the Euclidean norm the sliding term uses, so one number a sample
is all the law needs (a per-joint bound would serve only a per-joint law).
"""
from __future__ import annotations

import dataclasses
import math
from typing import Sequence

import numpy as np
import numpy.typing as npt
from scipy.interpolate import CubicHermiteSpline, CubicSpline

from swim_model import RigParameters, VehicleModel
from swim_model.wake import Wake, WakeParameters
from swim_planner.errors import ManeuverError
from swim_planner.maneuver import JUNCTION_TOLERANCE, junction_mismatch
from swim_planner.primitives import Primitive, PrimitiveSpec, PrimitiveType

Array = npt.NDArray[np.float64]

MAX_WAKE_STEP_S = 0.008
# the tracker's control period: sim_node steps its wake once a period, the step at which the wake was validated
# (Wagner, Garrick: swim_model/test/test_wake.py); the primitive's sample spacing is divided into equal steps of at
# most this
DISTURBANCE_MARGIN = 1.0
# no margin: D(t) is the measured mismatch itself; a caller sizing the sliding mode adds its own (named) margin
ENVELOPE_HALF_WIDTH_S = 0.05
# the stored bound at a sample is D's largest value within +-0.05 s of it (two samples of the primitives' 0.025 s
# fine grid each side, about six control periods): the tracked vehicle is not exactly where and when the plan is,
# and D peaks sharply (the accelerate's D falls from 0.09 to 0.005 N m within 0.2 s), so a bound read at the plan's
# time must cover the mismatch a little before and after it


@dataclasses.dataclass(frozen=True)
class DisturbanceStatistics:
    """Max, 95th percentile and mean of D(t) over a window, N m."""

    max_n_m: float
    p95_n_m: float
    mean_n_m: float


@dataclasses.dataclass(frozen=True)
class DisturbanceProfile:
    """The two flow models' forces along a primitive and the matched disturbance they differ by (module docstring).

    Per sample of the primitive (n samples, at its own times): ``time_s`` (n,); ``wake_force`` and
    ``reduced_force`` (n, 3): (fx N, fy N, mz N m), foil axes at F, beyond the Kirchhoff added mass;
    ``generalized_force_difference`` (n, nq): Q2' (f_w - f_r), N m on angles, N on R; ``matched_torque`` (n, 2):
    d = B' dQ, N m on (heave, pitch); ``unmatched_acceleration`` (n, ny): Mm11^-1 dQ_y, rad/s^2 (m/s^2 on R);
    ``disturbance_bound_n_m`` (n,): D = margin ||d||.
    """

    primitive_id: str
    margin: float
    wake_step_s: float
    time_s: Array
    wake_force: Array
    reduced_force: Array
    generalized_force_difference: Array
    matched_torque: Array
    unmatched_acceleration: Array
    disturbance_bound_n_m: Array

    @property
    def force_difference(self) -> Array:
        """f_w - f_r, (n, 3): N, N, N m."""
        return self.wake_force - self.reduced_force

    def window(self, start_s: float | None = None, end_s: float | None = None) -> npt.NDArray[np.bool_]:
        """Boolean mask (n,) of the samples with start_s <= time_s <= end_s (None: unbounded)."""
        lower = -math.inf if start_s is None else start_s
        upper = math.inf if end_s is None else end_s
        return (self.time_s >= lower - 1e-9) & (self.time_s <= upper + 1e-9)

    def statistics(self, start_s: float | None = None, end_s: float | None = None) -> DisturbanceStatistics:
        """D(t)'s max, 95th percentile and mean over the samples in [start_s, end_s], N m."""
        bound = self.disturbance_bound_n_m[self.window(start_s, end_s)]
        if bound.size == 0:
            raise ValueError(f"no sample of {self.primitive_id} in [{start_s}, {end_s}]")
        return DisturbanceStatistics(float(np.max(bound)), float(np.percentile(bound, 95.0)), float(np.mean(bound)))


def _foil_velocity_maps(model: VehicleModel, q: Array) -> Array:
    """Q2(q) at n positions q (n, nq): (n, 3, nq)."""
    maps = model.numeric["foil_velocity_map"].map(len(q))(np.asarray(q, dtype=float).T)
    return np.asarray(maps, dtype=float).reshape(3, len(q), model.nq).transpose(1, 0, 2)


def generalized_force(model: VehicleModel, q: npt.ArrayLike, foil_force: npt.ArrayLike) -> Array:
    """Q = Q2(q)' f at n samples.

    q (n, nq), f (n, 3) = (fx N, fy N, mz N m) in foil axes at F; Q (n, nq), N m on the angles, N on R (virtual work: Q
    . qdot = f . (U, V, Omega)).
    """
    return np.einsum("nij,ni->nj", _foil_velocity_maps(model, np.atleast_2d(q)), np.atleast_2d(foil_force))


def matched_disturbance(model: VehicleModel, q: npt.ArrayLike, force_q: npt.ArrayLike) -> tuple[Array, Array]:
    """(d, unmatched): a generalized force mismatch dQ split into the motors' torque that acts as it does, and the rest.

    d = dQ_psi - Mm21 Mm11^-1 dQ_y (N m, heave and pitch), the torque on the motors that moves the foil as dQ does;
    unmatched = Mm11^-1 dQ_y (rad/s^2, m/s^2), the rest of Mm^-1 dQ (module docstring).
    """
    mass = model.mass_matrix(q)
    force = np.asarray(force_q, dtype=float).reshape(-1)
    ny = model.n_unactuated
    unmatched = np.linalg.solve(mass[:ny, :ny], force[:ny])
    return force[ny:] - mass[ny:, :ny] @ unmatched, unmatched


def _motion(lead_in: Sequence[Primitive], primitive: Primitive) -> tuple[Array, Array, Array, Array]:
    """(t, q, qdot, lag) of the lead-in primitives run one after another, then ``primitive``.

    On one time axis where ``primitive`` keeps its own times (the lead-in at negative times) and alpha is continuous
    (P1).
    """
    chain = [*lead_in, primitive]
    for previous, following in zip(chain, chain[1:]):
        mismatch = junction_mismatch(previous, following)
        if mismatch > JUNCTION_TOLERANCE:
            raise ManeuverError(f"lead-in '{previous.spec.primitive_id}' does not end where "
                                f"'{following.spec.primitive_id}' starts (states differ by {mismatch:.3g})")
    times, positions, velocities, lags = [], [], [], []
    clock = float(primitive.time_s[0]) - sum(float(p.time_s[-1] - p.time_s[0]) for p in lead_in)
    alpha = None
    for index, part in enumerate(chain):
        if part.lag is None:
            raise ManeuverError(f"'{part.spec.primitive_id}' has no lag states: not a circulatory-flow primitive")
        skip = 0 if index == 0 else 1   # the junction sample is the previous part's last
        q = part.q.copy()
        if alpha is not None:
            q[:, 0] += alpha - q[0, 0]
        times.append(part.time_s[skip:] - part.time_s[0] + clock)
        positions.append(q[skip:])
        velocities.append(part.qdot[skip:])
        lags.append(part.lag[skip:])
        clock += float(part.time_s[-1] - part.time_s[0])
        alpha = float(q[-1, 0])
    # the primitive keeps its own alpha, the lead-in is shifted to end there
    q_all = np.concatenate(positions)
    q_all[:, 0] += primitive.q[0, 0] - q_all[len(q_all) - len(primitive.time_s), 0]
    return np.concatenate(times), q_all, np.concatenate(velocities), np.concatenate(lags)


def measuring_wake(rig: RigParameters) -> WakeParameters:
    """The wake D(t) is measured in: the default WakeParameters at the rig's water density."""
    return dataclasses.replace(WakeParameters(), rho_kg_m3=rig.water_density_kg_m3)


def wake_record(rig: RigParameters) -> dict:
    """measuring_wake's parameters as the manifest records them (JSON values).

    A D(t) measured in another wake is measured again (PrimitiveLibrary.needs_disturbance_bound).
    """
    return dataclasses.asdict(measuring_wake(rig))


def flow_force_mismatch(model: VehicleModel, primitive: Primitive, *, lead_in: Sequence[Primitive] = (),
                        wake_parameters: WakeParameters | None = None, max_wake_step_s: float = MAX_WAKE_STEP_S,
                        margin: float = DISTURBANCE_MARGIN) -> DisturbanceProfile:
    """The wake's and the reduced model's forces along ``primitive`` and D(t) (module docstring).

    Args:
        model: the circulatory-flow vehicle model of the primitive (constrained or free, its lane radius).
        primitive: a primitive planned with the circulatory flow (its samples of q, qdot and the lag states).
        lead_in: primitives run before it, in order, each ending where the next starts (alpha aside): the wake's
            history. Empty: the wake starts with no vortices at the primitive's first sample.
        wake_parameters: the wake's numerical parameters (default: WakeParameters() at the rig's water density).
        max_wake_step_s: the largest wake step, s.
        margin: D = margin ||d|| (>= 1).
    """
    flow = model.circulatory_flow
    if flow is None:
        raise ValueError("flow_force_mismatch: needs the model with flow='circulatory'")
    if not (math.isfinite(margin) and margin >= 1.0):
        raise ValueError(f"flow_force_mismatch: margin must be finite and >= 1, got {margin!r}")
    if not (math.isfinite(max_wake_step_s) and max_wake_step_s > 0.0):
        raise ValueError(f"flow_force_mismatch: max_wake_step_s must be positive, got {max_wake_step_s!r}")
    params = (measuring_wake(model.rig) if wake_parameters is None
              else dataclasses.replace(wake_parameters, rho_kg_m3=model.rig.water_density_kg_m3))
    time_s, q, qdot, lag = _motion(lead_in, primitive)

    # the motion between samples: cubic Hermite of q (slopes qdot), cubic spline of qdot
    position = CubicHermiteSpline(time_s, q, qdot, axis=0)
    velocity = CubicSpline(time_s, qdot, axis=0)
    spacing = float(np.min(np.diff(time_s)))
    steps = max(1, math.ceil(float(time_s[-1] - time_s[0]) / min(spacing, max_wake_step_s) - 1e-9))
    wake_step_s = float(time_s[-1] - time_s[0]) / steps
    step_end_s = time_s[0] + wake_step_s * np.arange(1, steps + 1)
    q_end, qdot_end = position(step_end_s), velocity(step_end_s)
    poses = np.asarray(model.foil_pose_function().map(steps)(q_end.T), dtype=float).T
    nu_end = np.einsum("nij,nj->ni", _foil_velocity_maps(model, q_end), qdot_end)
    wake = Wake(model.foil, params)
    vortical = np.zeros((steps, 3))
    for k in range(steps):
        force = wake.step(wake_step_s, (poses[k, 0], poses[k, 1], poses[k, 2]),
                          (nu_end[k, 0], nu_end[k, 1], nu_end[k, 2]))
        vortical[k] = (force.fx_n, force.fy_n, force.moment_n_m)
    step_mid_s = step_end_s - 0.5 * wake_step_s

    # at the primitive's own samples
    mine = slice(len(time_s) - len(primitive.time_s), len(time_s))
    t, q, qdot, lag = time_s[mine], q[mine], qdot[mine], lag[mine]
    q2 = _foil_velocity_maps(model, q)
    nu = np.einsum("nij,nj->ni", q2, qdot)
    drag = np.asarray(flow.functions["profile_drag"].map(len(t))(nu.T), dtype=float).T
    wake_force = np.column_stack([np.interp(t, step_mid_s, vortical[:, i]) for i in range(3)]) + drag
    reduced_force = np.array([model.flow_force(qk, vk, zk)[0] for qk, vk, zk in zip(q, qdot, lag)])
    generalized = generalized_force(model, q, wake_force - reduced_force)
    split = [matched_disturbance(model, qk, gk) for qk, gk in zip(q, generalized)]
    matched = np.array([d for d, _ in split])
    unmatched = np.array([a for _, a in split])
    return DisturbanceProfile(primitive_id=primitive.spec.primitive_id, margin=float(margin),
                              wake_step_s=wake_step_s, time_s=primitive.time_s.copy(), wake_force=wake_force,
                              reduced_force=reduced_force, generalized_force_difference=generalized,
                              matched_torque=matched, unmatched_acceleration=unmatched,
                              disturbance_bound_n_m=margin * np.linalg.norm(matched, axis=1))


def bound_envelope(time_s: npt.ArrayLike, bound_n_m: npt.ArrayLike, half_width_s: float) -> Array:
    """The maximum of bound_n_m (N,) over the samples within +-half_width_s (s) of each of the N times time_s: (N,)."""
    time = np.asarray(time_s, dtype=float)
    bound = np.asarray(bound_n_m, dtype=float)
    if not (math.isfinite(half_width_s) and half_width_s >= 0.0):
        raise ValueError(f"bound_envelope: half width must be finite and >= 0, got {half_width_s!r}")
    first = np.searchsorted(time, time - half_width_s - 1e-9, side="left")
    last = np.searchsorted(time, time + half_width_s + 1e-9, side="right")
    return np.array([bound[a:b].max() for a, b in zip(first, last)])


def lead_in_ids(spec: PrimitiveSpec) -> list[str]:
    """The primitives whose motion before ``spec``'s gives the wake its history.

    The primitive its start joins (a cruise for a decelerate, cruise-to-cruise or lane change), a cruise itself once (a
    cruise follows a cruise in every maneuver but the first, and the accelerate before that one ends on the cruise's
    stroke), none from rest (an accelerate: the water is still).
    """
    if spec.start_from is not None:
        return [spec.start_from]
    return [spec.primitive_id] if spec.primitive_type is PrimitiveType.CRUISE else []


def disturbance_job(rig: RigParameters, primitive: Primitive, lead_in: Sequence[Primitive],
                    half_width_s: float = ENVELOPE_HALF_WIDTH_S) -> tuple[str, Array, dict]:
    """(primitive id, stored bound (N,) N m, measurement record) of a circulatory primitive, in a worker process.

    ``flow_force_mismatch`` along it after ``lead_in`` (``lead_in_ids``), D's envelope (``bound_envelope``), and what
    the manifest records of how it was measured (JSON values).
    """
    spec = primitive.spec
    model = VehicleModel(rig, constrained=spec.constrained, lane_radius_m=spec.lane_radius_m, flow="circulatory")
    profile = flow_force_mismatch(model, primitive, lead_in=lead_in)
    envelope = bound_envelope(profile.time_s, profile.disturbance_bound_n_m, half_width_s)
    stats = profile.statistics()
    record = {"lead_in": [p.spec.primitive_id for p in lead_in], "envelope_half_width_s": float(half_width_s),
              "margin": profile.margin, "wake_step_s": profile.wake_step_s, "measured_max_n_m": stats.max_n_m,
              "measured_p95_n_m": stats.p95_n_m, "measured_mean_n_m": stats.mean_n_m, "wake": wake_record(rig)}
    return spec.primitive_id, envelope, record
