"""A planned trajectory and its tracking gains: what the planner concatenates and the tracker executes.

A trajectory is N samples of q, qdot, u = psiddot and the feed-forward torque tau (and, planned with the
circulatory flow model, the flow's n_lag = 2 lag states z; swim_model.flow), with the tracking gains of
eq. 33 at each sample: K = lambda R^-1 (G'P) Gamma(lambda) and the Riccati input gain G_l'P_l = (G'P) Gamma(lambda)
(eq. 24), already time-scaled (swim_control.time_scaling). Its segments say which primitive each run of samples
came from (paper Sec. 4.2); a trajectory is checked when it is made, so one that exists is well formed.

Time scaling by lambda > 0 (paper P3, Sec. 4.3; Theorem 1, Sec. 6.4) is ``Trajectory.time_scaled``, the one place
it is done: t -> t / lambda, q(t) -> q(lambda t), qdot -> lambda qdot, u -> lambda^2 u, tau -> lambda^2 tau, the
lag states (velocities) z -> lambda z (docs/flow_model.md, "Smoothness and P3"), the gains by Theorem 1, and the
sliding mode's disturbance bound D -> lambda^2 D (below).
Scalings compose (lambda2 after lambda1 is lambda1 lambda2), and a lambda whose torques exceed the motor limits
is refused with the largest feasible one named.

The disturbance bound D(t) (N m; planned with the circulatory flow, swim_planner.disturbance) bounds the matched
torque d = B(q)' dQ by which the flow's real force differs from the planned one, dQ = Q2(q)' df. Along the plan run
lambda times faster, q_l(t) = q(lambda t) and every velocity (qdot, Q2 qdot, and z) is lambda times the nominal
one; both flow forces are homogeneous of degree 2 in those velocities (the reduced model: f(lambda nu, lambda z) =
lambda^2 f(nu, z); the wake: vortex strengths scale as lambda, its force as lambda^2, on the same geometry), and
Q2 and B depend on q alone, so d_l(t) = lambda^2 d(lambda t) and D_l(t) = lambda^2 D(lambda t): a torque, like tau.
Without a stored bound (an ideal-flow plan, a library without one) the tracker's constant bound applies.
"""
from __future__ import annotations

import bisect
import dataclasses
import math
from typing import Optional

import numpy as np
import numpy.typing as npt

from swim_control.errors import PlanError
from swim_control.riccati import error_state_size
from swim_control.time_scaling import retime_feedback
from swim_model.flow import FLOW_MODELS, LAG_STATE_NAMES
from swim_model.vehicle import JOINT_NAMES_CONSTRAINED, JOINT_NAMES_UNCONSTRAINED

Array = npt.NDArray[np.float64]

#: the largest trajectory the tracker accepts, in samples. Assumed from memory: a free-vehicle sample is 53 float64
#: (t, q, qdot, u, tau and two 2 x 10 gains: 424 B), so 1e6 samples are ~0.4 GB, held about three times over by
#: the tracker (the message's arrays, the interpolation rows and their slopes; q's Hermite terms and the times as
#: Python floats add 80-96 B a sample); a 1000-cruise plan (0.8 M samples) fits. The planner serves no larger plan by
#: default (swim_planner.maneuver.PlanBounds.max_samples).
MAX_TRACKED_SAMPLES = 1_000_000
#: the largest |alpha| a plan may start from, rad: the planner's request bound and the simulator's set_state bound.
#: Assumed: float64 keeps alpha to 1e-10 rad up to here (and swimming 1e6 rad would take weeks).
MAX_ABS_START_ALPHA_RAD = 1.0e6


@dataclasses.dataclass(frozen=True)
class Segment:
    """One primitive as it was placed in a trajectory (swim_interfaces/PrimitiveSegment).

    Attributes
    ----------
    primitive_id : str
        The library's id of the primitive.
    primitive_type : str
        Its type (swim_planner.primitives.PrimitiveType's value).
    repeat_index : int
        Which repeat of the primitive in its run, from 0.
    start_time_s : float
        Trajectory time at which the segment starts, s.
    duration_s : float
        Its duration after time scaling, s, >= 0.
    time_scale : float
        lambda > 0; > 1 runs faster than stored.
    alpha_offset_rad : float
        Added to the stored alpha, rad (Prop. 1).
    first_sample : int
        Index of the segment's first sample in the trajectory's arrays.
    sample_count : int
        Samples that belong to the segment.
    """

    primitive_id: str
    primitive_type: str
    repeat_index: int
    start_time_s: float       # trajectory time at which the segment starts, s
    duration_s: float         # after time scaling, s
    time_scale: float         # lambda, > 0; > 1 runs faster than stored
    alpha_offset_rad: float   # added to the stored alpha, rad
    first_sample: int         # index of the segment's first sample in the trajectory's arrays
    sample_count: int         # samples that belong to the segment

    def validate(self) -> None:
        """Check the segment's times and time scale.

        Raises
        ------
        PlanError
            Unless the times and lambda are finite, lambda positive and the duration non-negative.
        """
        if not (math.isfinite(self.time_scale) and self.time_scale > 0.0):
            raise PlanError(f"segment '{self.primitive_id}': time scale must be positive and finite, "
                            f"got {self.time_scale!r}")
        if not (math.isfinite(self.start_time_s) and math.isfinite(self.duration_s) and self.duration_s >= 0.0
                and math.isfinite(self.alpha_offset_rad)):
            raise PlanError(f"segment '{self.primitive_id}': start, duration and alpha offset must be finite "
                            f"(duration >= 0)")


@dataclasses.dataclass
class TrajectoryPoint:
    """A trajectory sampled at one time: the reference of one control period.

    Attributes
    ----------
    time_s : float
        Trajectory time, s.
    q : (nq,) array
        Positions, rad and m.
    qdot : (nq,) array
        Velocities, rad/s and m/s.
    foil_acceleration : (2,) array
        u_des = psiddot (heave, pitch), rad/s^2.
    torque : (2,) array
        Feed-forward torque (heave, pitch), N m.
    lqr_gain : (2, n) array
        K of eq. 33, time-scaled.
    riccati_input_gain : (2, n) array
        G_l' P_l of eq. 24, time-scaled.
    lag : (n_lag,) array
        The flow's planned lag states, m/s; empty for the ideal flow.
    disturbance_bound_n_m : float or None
        D(t), N m; None: the plan has none (the tracker's constant bound).
    """

    time_s: float
    q: Array                   # (nq,)
    qdot: Array                # (nq,)
    foil_acceleration: Array   # (2,) u_des, rad/s^2
    torque: Array              # (2,) feed-forward torque, N m
    lqr_gain: Array            # (2, n) K
    riccati_input_gain: Array  # (2, n) G_l' P_l
    lag: Array                 # (n_lag,) the flow's planned lag states, m/s; empty for the ideal flow
    disturbance_bound_n_m: Optional[float] = None   # D(t), N m; None: the plan has none (the constant bound)


@dataclasses.dataclass(frozen=True, eq=False)
class Trajectory:
    """A concatenated, time-scaled trajectory on its sample grid, N samples, nq = 3 (constrained) or 4 (free).

    The gains act on the error state x = (int e_y, e_q, edot_q, e_z) of n = ny + 2 nq + n_lag entries. Every field
    is checked when the trajectory is made.

    Parameters
    ----------
    time_s : (N,) array
        Trajectory time, s, strictly increasing, N >= 2.
    q : (N, nq) array
        Positions, rad and m.
    qdot : (N, nq) array
        Velocities, rad/s and m/s.
    foil_acceleration : (N, 2) array
        u_des = psiddot (heave, pitch), rad/s^2.
    torque : (N, 2) array
        Feed-forward torque, N m (reported, not used by the law).
    lqr_gain : (N, 2, n) array
        K of eq. 33, time-scaled.
    riccati_input_gain : (N, 2, n) array
        G_l' P_l of eq. 24, time-scaled.
    segments : tuple of Segment
        In order, tiling the samples (a junction sample belongs to the earlier one).
    lane_radius_m : float
        R of the locked rails (constrained), or the starting lane (free), m, > 0.
    library_digest : str, optional
        The primitive library the trajectory came from.
    flow_model : str, optional
        The flow model the plan was made with: "ideal" (the paper's) or "circulatory"
        (swim_model.flow.FLOW_MODELS).
    lag : (N, n_lag) array, optional
        The planned lag states, m/s: required with the circulatory flow (n_lag = 2), None with the ideal one.
    disturbance_bound : (N,) array, optional
        The sliding mode's bound D(t), N m, finite and >= 0, or None (the tracker's constant bound).

    Raises
    ------
    PlanError
        If a field has the wrong shape, a non-finite value, or does not fit the others (module docstring).

    References
    ----------
    Saimek & Li 2004, Secs. 4.2-4.3 and 6.4, eqs. 24 and 33; docs/model_and_method.md sections 4 and 5.4.
    """

    time_s: Array              # (N,) trajectory time, s, strictly increasing
    q: Array                   # (N, nq) rad, m
    qdot: Array                # (N, nq) rad/s, m/s
    foil_acceleration: Array   # (N, 2) u_des = psiddot, rad/s^2
    torque: Array              # (N, 2) feed-forward torque, N m (reported, not used by the law)
    lqr_gain: Array            # (N, 2, n) K of eq. 33, time-scaled
    riccati_input_gain: Array  # (N, 2, n) G_l' P_l of eq. 24, time-scaled
    segments: tuple[Segment, ...]   # in order, tiling the samples (a junction sample belongs to the earlier one)
    lane_radius_m: float       # R of the locked rails (constrained), or the starting lane (free), m
    library_digest: str = ""   # the primitive library the trajectory came from
    flow_model: str = "ideal"  # "ideal" | "circulatory" (swim_model.flow.FLOW_MODELS)
    lag: Optional[Array] = None   # (N, n_lag) the flow's lag states, m/s; None for the ideal flow
    disturbance_bound: Optional[Array] = None   # (N,) the sliding mode's bound D(t), N m; None: the constant bound
    _segment_start_s: Array = dataclasses.field(init=False, repr=False)   # (segments,) their start times, s
    _rows: Array = dataclasses.field(init=False, repr=False)     # (N, m) every sampled quantity, one row a sample
    _slopes: Array = dataclasses.field(init=False, repr=False)   # (N - 1, m) the rows' slopes between samples
    #: (N - 1, 2 nq) per interval k, qdot_k - s_k and qdot_(k+1) - s_k with s_k the secant slope of q: the Hermite
    #: correction's terms (sample)
    _hermite: Array = dataclasses.field(init=False, repr=False)
    #: time_s as Python floats (N,), s: bisect finds a sample interval in a fraction of numpy's per-call overhead
    _times: list[float] = dataclasses.field(init=False, repr=False)
    _sizes: tuple[int, int, int] = dataclasses.field(init=False, repr=False)   # (nq, n_lag, n), read per sample

    def __post_init__(self) -> None:  # noqa: C901 - one guard per field, read as one checklist of a valid plan
        """Check every field and build the interpolation rows (Raises, above)."""
        set_field = object.__setattr__   # frozen: fields are set here once, checked
        set_field(self, "time_s", np.asarray(self.time_s, dtype=float))
        samples = len(self.time_s)
        if samples < 2 or self.time_s.ndim != 1:
            raise PlanError("a plan needs at least two samples")
        if not np.all(np.diff(self.time_s) > 0.0):
            raise PlanError("plan sample times must be strictly increasing")
        nq = np.shape(self.q)[-1] if np.ndim(self.q) == 2 else 0
        if nq not in (3, 4):
            raise PlanError(f"positions must be (N, 3) or (N, 4), got shape {np.shape(self.q)}")
        if not (isinstance(self.flow_model, str) and self.flow_model in FLOW_MODELS):
            raise PlanError(f"plan flow model must be one of {FLOW_MODELS}, got {self.flow_model!r}")
        n_lag = self.n_lag
        if n_lag and self.lag is None:
            raise PlanError(f"a plan made with the circulatory flow model needs its lag states "
                            f"({', '.join(LAG_STATE_NAMES)}, m/s)")
        if not n_lag and self.lag is not None:
            raise PlanError("a plan made with the ideal flow model has no lag states (lag must be None)")
        n = error_state_size(nq, nq - 2, n_lag)
        shapes = {"q": (samples, nq), "qdot": (samples, nq), "foil_acceleration": (samples, 2),
                  "torque": (samples, 2), "lqr_gain": (samples, 2, n), "riccati_input_gain": (samples, 2, n)}
        if n_lag:
            shapes["lag"] = (samples, n_lag)
        if self.disturbance_bound is not None:
            shapes["disturbance_bound"] = (samples,)
        for name, shape in shapes.items():
            value = np.asarray(getattr(self, name), dtype=float)
            if value.shape != shape:
                raise PlanError(f"plan {name} must have shape {shape}, got {value.shape}")
            if not np.all(np.isfinite(value)):
                raise PlanError(f"plan {name} has non-finite values")
            set_field(self, name, value)
        if self.disturbance_bound is not None and np.any(self.disturbance_bound < 0.0):
            raise PlanError("plan disturbance_bound has negative values (a bound on a norm, N m)")
        if not (isinstance(self.lane_radius_m, (int, float)) and math.isfinite(self.lane_radius_m)
                and self.lane_radius_m > 0.0):
            raise PlanError(f"plan lane radius must be positive and finite, got {self.lane_radius_m!r} m")
        set_field(self, "lane_radius_m", float(self.lane_radius_m))
        set_field(self, "segments", tuple(self.segments))
        self._check_segments(samples)
        set_field(self, "_segment_start_s", np.array([s.start_time_s for s in self.segments]))
        # one row per sample, interpolated in one operation per control period
        lag_rows = [self.lag] if self.lag is not None else []
        if self.disturbance_bound is not None:
            lag_rows.append(self.disturbance_bound[:, None])
        rows = np.concatenate([self.q, self.qdot, self.foil_acceleration, self.torque, *lag_rows,
                               self.lqr_gain.reshape(samples, -1), self.riccati_input_gain.reshape(samples, -1)],
                              axis=1)
        set_field(self, "_rows", rows)
        set_field(self, "_slopes", np.diff(rows, axis=0) / np.diff(self.time_s)[:, None])
        secant = self._slopes[:, :nq]
        set_field(self, "_hermite", np.concatenate([self.qdot[:-1] - secant, self.qdot[1:] - secant], axis=1))
        set_field(self, "_times", self.time_s.tolist())
        set_field(self, "_sizes", (nq, n_lag, n))

    def _check_segments(self, samples: int) -> None:
        if not self.segments:
            raise PlanError("a plan needs at least one segment")
        first = 0
        for segment in self.segments:
            segment.validate()
            if segment.first_sample != first or segment.sample_count < 1:
                raise PlanError(f"segment '{segment.primitive_id}' covers samples from {segment.first_sample} "
                                f"({segment.sample_count} samples); the segments must tile the samples in order, "
                                f"this one from {first}")
            first += segment.sample_count
        if first != samples:
            raise PlanError(f"the segments cover {first} samples, the plan has {samples}")
        if np.any(np.diff([s.start_time_s for s in self.segments]) < 0.0):
            raise PlanError("segment start times must not decrease")

    @property
    def nq(self) -> int:
        """Generalized coordinates: 3 (constrained) or 4 (free)."""
        return int(self.q.shape[1])

    @property
    def ny(self) -> int:
        """Unactuated coordinates with an integral error: 1 (constrained) or 2 (free)."""
        return self.nq - 2

    @property
    def n_lag(self) -> int:
        """The flow's lag states: 0 (ideal flow) or 2 (circulatory)."""
        return len(LAG_STATE_NAMES) if self.flow_model == "circulatory" else 0

    @property
    def constrained(self) -> bool:
        """The laterally constrained vehicle (q = alpha, phi, theta), else the free one (alpha, R, phi, theta)."""
        return self.nq == len(JOINT_NAMES_CONSTRAINED)

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The names of q's entries, in order (swim_model.vehicle's joint names)."""
        return JOINT_NAMES_CONSTRAINED if self.constrained else JOINT_NAMES_UNCONSTRAINED

    @property
    def duration_s(self) -> float:
        """The last sample's time T, s."""
        return self._times[-1]

    def segment_index(self, time_s: float) -> int:
        """Index of the segment running at a time.

        Parameters
        ----------
        time_s : float
            Trajectory time, s.

        Returns
        -------
        int
            Index into ``segments`` (0 before the first segment's start).
        """
        return max(int(np.searchsorted(self._segment_start_s, time_s, side="right")) - 1, 0)

    def time_scale_at(self, time_s: float) -> float:
        """The time scale of the segment running at a time.

        Parameters
        ----------
        time_s : float
            Trajectory time, s (clamped as in ``segment_index``).

        Returns
        -------
        float
            lambda of that segment.
        """
        return self.segments[self.segment_index(time_s)].time_scale

    def sample(self, time_s: float) -> TrajectoryPoint:
        """The trajectory at a time: linear in every row, cubic Hermite in q (uses qdot).

        Parameters
        ----------
        time_s : float
            Trajectory time, s, clamped to [0, T].

        Returns
        -------
        TrajectoryPoint
            The reference at that time.
        """
        t, k, offset = self._interval(time_s)
        row = self._rows[k] + offset * self._slopes[k]
        nq, n_lag, n = self._sizes
        # the Hermite correction to linear interpolation of q, on Python floats (a few scalars: numpy's per-call
        # overhead would dominate): h w (1 - w) ((qdot0 - slope) (1 - w) - (qdot1 - slope) w) with w = offset / h
        times = self._times
        step = times[k + 1] - times[k]
        w = offset / step
        hermite_scale = step * w * (1.0 - w)
        hermite = self._hermite[k].tolist()
        q = np.array([linear + hermite_scale * (before * (1.0 - w) - after * w)
                      for linear, before, after in zip(row[:nq].tolist(), hermite[:nq], hermite[nq:])])
        bound = None if self.disturbance_bound is None else float(row[2 * nq + 4 + n_lag])
        gains = row[2 * nq + 4 + n_lag + (bound is not None):]
        return TrajectoryPoint(
            time_s=t, q=q, qdot=row[nq:2 * nq], foil_acceleration=row[2 * nq:2 * nq + 2],
            torque=row[2 * nq + 2:2 * nq + 4], lqr_gain=gains[:2 * n].reshape(2, n),
            riccati_input_gain=gains[2 * n:].reshape(2, n), lag=row[2 * nq + 4:2 * nq + 4 + n_lag],
            disturbance_bound_n_m=bound)

    def foil_acceleration_at(self, time_s: float) -> tuple[float, float]:
        """u_des = psiddot at a time, without interpolating the rest of the row (the tracker's mid-period feed-forward).

        Parameters
        ----------
        time_s : float
            Trajectory time, s, clamped to [0, T] (a period's midpoint, for the feed-forward).

        Returns
        -------
        tuple of float
            (heave, pitch) rad/s^2: sample(time_s).foil_acceleration, the same numbers.
        """
        _, k, offset = self._interval(time_s)
        first = 2 * self._sizes[0]
        heave, pitch = self._rows[k, first:first + 2].tolist()
        heave_slope, pitch_slope = self._slopes[k, first:first + 2].tolist()
        return heave + offset * heave_slope, pitch + offset * pitch_slope

    def _interval(self, time_s: float) -> tuple[float, int, float]:
        """(t, k, t - t_k): time_s clamped to [0, T] as t, and the sample interval [t_k, t_(k+1)] holding it.

        k is in 0..N-2: the last interval holds T, the first a time before the first sample.
        """
        times = self._times
        t = min(max(time_s, 0.0), times[-1])
        k = max(min(bisect.bisect_right(times, t) - 1, len(times) - 2), 0)
        return t, k, t - times[k]

    def time_scaled(self, time_scale: float, torque_limits_n_m: npt.ArrayLike) -> Trajectory:
        """The trajectory run time_scale (lambda) times faster: P3 and Theorem 1 (module docstring).

        Parameters
        ----------
        time_scale : float
            lambda > 0; scalings compose (lambda2 after lambda1 is lambda1 lambda2).
        torque_limits_n_m : (2,) array_like
            The (heave, pitch) motor limits, N m (the rig's).

        Returns
        -------
        Trajectory
            The re-timed trajectory: t / lambda, lambda qdot, lambda^2 u, lambda^2 tau, lambda z, lambda^2 D and the
            gains by Theorem 1.

        Raises
        ------
        PlanError
            For a lambda that is not positive and finite, or whose torques lambda^2 tau exceed the limits (naming
            the largest feasible one).

        References
        ----------
        Saimek & Li 2004, Sec. 4.3 (P3) and Sec. 6.4 (Theorem 1); docs/model_and_method.md sections 4 and 5.4.
        """
        if not (isinstance(time_scale, (int, float)) and math.isfinite(time_scale) and time_scale > 0.0):
            raise PlanError(f"time scale must be a positive finite number, got {time_scale!r}")
        peak = motor_limit_fraction(self.torque, torque_limits_n_m) * time_scale ** 2
        if peak > 1.0:
            raise PlanError(f"time scale {time_scale:g} needs {peak:.0%} of the motor torque limits; the largest "
                            f"feasible time scale for this plan is {time_scale / math.sqrt(peak):.3f}")
        lqr_gain, riccati_input_gain = retime_feedback(self.lqr_gain, self.riccati_input_gain, time_scale,
                                                       self.ny, self.nq, self.n_lag)
        segments = tuple(dataclasses.replace(s, start_time_s=s.start_time_s / time_scale,
                                             duration_s=s.duration_s / time_scale,
                                             time_scale=s.time_scale * time_scale) for s in self.segments)
        return dataclasses.replace(self, time_s=self.time_s / time_scale, qdot=self.qdot * time_scale,
                                   foil_acceleration=self.foil_acceleration * time_scale ** 2,
                                   torque=self.torque * time_scale ** 2, lqr_gain=lqr_gain,
                                   riccati_input_gain=riccati_input_gain, segments=segments,
                                   lag=None if self.lag is None else self.lag * time_scale,
                                   disturbance_bound=None if self.disturbance_bound is None
                                   else self.disturbance_bound * time_scale ** 2)


def motor_limit_fraction(torque_n_m: Array, torque_limits_n_m: npt.ArrayLike) -> float:
    """The largest share of the motor limits a plan's torques use.

    Parameters
    ----------
    torque_n_m : (N, 2) array
        (heave, pitch) torques, N m.
    torque_limits_n_m : (2,) array_like
        (heave, pitch) motor limits, N m, positive and finite.

    Returns
    -------
    float
        max over samples and motors of |tau| / limit: 1.0 is at the limits.

    Raises
    ------
    PlanError
        If the limits are not two positive finite numbers.
    """
    limits = np.asarray(torque_limits_n_m, dtype=float)
    if limits.shape != (2,) or not np.all(np.isfinite(limits)) or np.any(limits <= 0.0):
        raise PlanError(f"torque limits must be two positive finite numbers (heave, pitch), got {limits!r}")
    return float((np.abs(torque_n_m) / limits).max())

