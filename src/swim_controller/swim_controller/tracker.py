"""The cascade tracker (paper Sec. 6, Fig. 18): LQ feedback on u = psiddot, I/O linearization, sliding mode.

At each control period, with the plan (a trajectory.Trajectory) sampled at the current plan time t (gains
already time-scaled and concatenated by the planner, see time_scaling):

    x     = (int (y - y_des) dt, q - q_des, qdot - qdot_des[, z^ - z_des])   error state (riccati)
    u     = u_des(t + h/2) - K(t) x,    K = R_l^-1 G_l' P_l             LQ stage (eqs. 19, 33)
            bounded near the heave's and the pitch's stops, if a FoilRangeGuard is given
    tau1  = Mio(q) u + Cio(q, qdot[, z^]) qdot                          I/O linearization (eqs. 22-23)
    s     = Mio^-1 G_l' P_l x,  eps = -D s / max(||s||, phi)            sliding mode (eqs. 24-25)
            D = margin D_plan(t) if the plan carries its disturbance bound, else the constant (sliding_mode)
    tau   = sat(tau1 + eps)                                             motor limits, saturation reported

After the plan ends the tracker holds the foil still at the plan's last heave and pitch: a PD law on psi
through the same I/O linearization. The torque is held over the period h (zero-order hold), so the feed-forward
u_des is taken at the period's midpoint (on the ideal model: worst pitch error 0.041 rad, 0.043 with u_des at the
period's start).
The hold law: (u = -kp (psi - psi_end) - kd psidot), alpha and R left free.

A plan made with the circulatory flow model (swim_model.flow) adds the flow's n_lag = 2 lag states z (m/s). They
are not measured, but they are driven by the foil's motion alone (zdot = g(q, qdot, z)), so the tracker
estimates them from the measured motion (LagEstimator) and uses the estimate z^ in the I/O linearization (the
flow's force is part of Cio qdot) and in the error state's lag block. With an ideal-flow plan there are none and
the law is the paper's, unchanged.
"""
from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, Callable, Optional, Sequence

import numpy as np
import numpy.typing as npt
from numpy.linalg import _umath_linalg

from swim_control.errors import PlanError
from swim_control.trajectory import Trajectory, TrajectoryPoint
from swim_controller.sliding_mode import SlidingMode
from swim_model.flow import LAG_STATE_NAMES
from swim_model.limits import HardLimits

if TYPE_CHECKING:
    from swim_model import VehicleModel

Array = npt.NDArray[np.float64]
#: (q, qdot, lag) -> (Mio 2x2, Cio qdot 2): the I/O linearization of the vehicle model (eqs. 22-23); lag: the
#: flow's lag states (n_lag,), m/s, empty (0,) for the ideal flow (the force of the circulatory flow is in Cio qdot)
IoLinearization = Callable[[Array, Array, Array], tuple[Array, Array]]
#: (q, qdot, lag) -> zdot (n_lag,), m/s^2: the circulatory flow's lag rate (swim_model.flow)
LagRate = Callable[[Array, Array, Array], Array]

HOLD_STIFFNESS_PER_S2 = 100.0   # assumed: kp of the hold law, a 10 rad/s, critically damped foil
HOLD_DAMPING_PER_S = 20.0       # assumed: kd = 2 sqrt(kp)
#: a lag-state offset (m/s) at which the lag rate is evaluated beside zero to read off its slope: any nonzero
#: value gives the same slope (the rate is affine in z); 1 m/s is of the size of the rig's normal velocities,
#: so neither evaluation loses digits to the other
LAG_PROBE_M_S = 1.0
#: the largest normal velocity Q (m/s) the lag estimate takes from a measured state: assumed, 5 m/s against the
#: 0.3-0.8 m/s of the rig's strokes (0.3-0.6 rad of heave at 1-1.5 Hz): a larger one is a glitch of the state, not
#: water the foil moved, and would set z^ off for seconds (the slow lag's 1/a is about 2 s)
MAX_NORMAL_VELOCITY_M_S = 5.0
NO_LAG = np.zeros(0)            # the ideal flow's (empty) lag states
#: FoilRangeGuard's braking acceleration a per joint (heave, pitch), rad/s^2. Assumed: the plans' own braking with
#: room to spare, so that the bound never binds on a plan followed exactly. Near the stops the shipped plans (both
#: libraries, every primitive, at time scales 0.8-1.67) brake the heave at up to 62 and the pitch at up to 337
#: (the free E = 0.10 accelerate at 1.67), faster than the motors alone surely do (21 and 258,
#: swim_hw_bridge.braking): the water and the other joint help. A guard slower than the plans holds them back and
#: itself makes the errors it is there to contain (docs/experiments.md)
GUARD_BRAKING_ACCELERATION_RAD_S2 = (80.0, 450.0)
#: FoilRangeGuard's margin short of each stop, rad. Assumed: 0.05 rad (3 deg), what a joint at 6 rad/s covers in
#: one 8 ms period, and inside the bridge's 5 deg soft-limit margin
GUARD_MARGIN_RAD = 0.05


class LagEstimator:
    """z^, the estimate of the circulatory flow's lag states (m/s), from the measured motion alone.

    The lag rate is affine in z, one first-order lag per state (swim_model.flow; docs/flow_model.md, section 2):

        zdot_i = g_i(q, qdot, z) = a_i (Q - z_i),   a_i = (|u| / b) b_i > 0,   Q: the normal velocity at 3/4 chord

    with a_i and Q functions of the measured (q, qdot) only. Each update integrates it over the time since the
    previous measurement with the coefficients averaged over the two measurements (a trapezoid of a and of c = a Q)
    and solved exactly for those (an exponential integrator):

        z^_k = Qbar + (z^_(k-1) - Qbar) exp(-abar dt),   abar = (a_(k-1) + a_k)/2,   Qbar = cbar / abar

    Why this one: it is exact for coefficients constant over the period and second order in dt when they vary
    (local error O(dt^3), as RK2); the new z^ lies between the old one and a weighted mean of the measured Q, so
    it never overshoots, whatever the period (a_fast dt is 0.08 at |u| = 1 m/s and 8 ms: not stiff, but a late
    state or a long gap cannot make it diverge); and it costs two evaluations of the compiled lag rate per period
    (at z = 0 and z = LAG_PROBE_M_S: c = g(0), a = (g(0) - g(probe)) / probe), where RK4 needs four, on motion
    interpolated between measurements (20 us a step here at load 4, most of it the two calls; the whole step's
    target is a 100 us median). The estimate converges to the true lag at the rates a_i whatever it starts from
    (the error obeys edot_i = -a_i e_i), and it is as good as the measured motion: noise in qdot passes through
    the lag's low-pass filter (corner a_i: 10 rad/s per m/s of |u| for the rig's fast state). A measurement
    whose lag rate is not finite, or whose normal velocity Q passes MAX_NORMAL_VELOCITY_M_S (a state no stroke
    makes: a glitch), leaves z^ as it was, and the next one restarts the integration from there.

    Parameters
    ----------
    lag_rate : LagRate
        (q, qdot, z) -> zdot (n_lag,), m/s^2: the circulatory flow's lag rate (``model_lag_rate``).
    n_lag : int
        The flow's lag states (2).

    Attributes
    ----------
    estimate : (n_lag,) array
        z^, m/s.

    References
    ----------
    docs/flow_model.md, section 2 (the lag states and their rate).
    """

    def __init__(self, lag_rate: LagRate, n_lag: int) -> None:
        self._lag_rate = lag_rate
        self._zero = np.zeros(n_lag)
        self._probe = np.full(n_lag, LAG_PROBE_M_S)
        self.estimate = np.zeros(n_lag)              # z^, m/s
        self._slope: Optional[list[float]] = None    # a at the previous measurement, 1/s
        self._forcing: Optional[list[float]] = None  # c = a Q at the previous measurement, m/s^2

    def reset(self, lag: Array) -> None:
        """Start from a given estimate at the next measurement.

        Parameters
        ----------
        lag : (n_lag,) array
            z^ to start from, m/s.
        """
        self.estimate = np.array(lag, dtype=float)
        self._slope = self._forcing = None

    def update(self, elapsed_s: float, q: Array, qdot: Array) -> Array:
        """z^ at a measurement, integrated from the previous one.

        Parameters
        ----------
        elapsed_s : float
            Time since the previous measurement, s.
        q, qdot : (nq,) array
            The measured state, rad and m, rad/s and m/s: the lag rate's coefficients are taken at it.

        Returns
        -------
        (n_lag,) array
            z^, m/s (the first after ``reset``: the reset value; after an implausible measurement: unchanged).
        """
        # a handful of scalars: Python floats cost a fraction of numpy's per-call overhead here
        forcing = self._lag_rate(q, qdot, self._zero).tolist()
        probed = self._lag_rate(q, qdot, self._probe).tolist()
        slope = [(c - p) * (1.0 / LAG_PROBE_M_S) for c, p in zip(forcing, probed)]
        previous_slope, previous_forcing = self._slope, self._forcing
        estimate = self.estimate.tolist()
        plausible = True
        for i, (a, c) in enumerate(zip(slope, forcing)):
            if previous_slope is not None and previous_forcing is not None and elapsed_s > 0.0:
                mean_slope = 0.5 * (previous_slope[i] + a)
                if not mean_slope > 0.0:   # a_i >= |u|_min b_i / b > 0: only a state past the model's range
                    plausible = False
                    break
                relaxed = -math.expm1(-mean_slope * elapsed_s)   # 1 - exp(-abar dt), in [0, 1]
                estimate[i] += relaxed * (0.5 * (previous_forcing[i] + c) / mean_slope - estimate[i])
            plausible = plausible and math.isfinite(estimate[i]) and abs(c) <= MAX_NORMAL_VELOCITY_M_S * a < math.inf
        if not plausible:
            self._slope = self._forcing = None
            return self.estimate
        self.estimate, self._slope, self._forcing = np.array(estimate), slope, forcing
        return self.estimate


@dataclasses.dataclass(frozen=True)
class FoilRangeGuard:
    """Keeps the law's foil acceleration from driving the heave or the pitch into its hard stop.

    For each foil joint (heave, pitch) at psi (rad) moving at psidot (rad/s), with stops (lower, upper) (rad), the
    commanded acceleration u (rad/s^2), held over the period h (s), is bounded so that at the period's end the
    joint can still come to rest margin (rad) short of the stop braking at a (rad/s^2). Toward the upper stop,
    with d = upper - margin - psi the room left (rad), that is

        psidot + u h <= sqrt(2 a (d - psidot h - u h^2 / 2)),    the largest such u:
        u_max h = -psidot - a h / 2 + sqrt(a^2 h^2 / 4 - a h psidot + 2 a d)

    and toward the lower one the same with psi and psidot mirrored. A joint that would cover its room within the
    period (psidot h >= 2 d) is asked to come to rest within it instead, u = -psidot / h, so it never bounces
    off the margin; one that followed the bound passes the margin by at most a h^2 / 2 then (3 mrad for the
    heave, 14 for the pitch). On the braking curve, psidot = sqrt(2 a d) >= a h, the bound is u = -a; far from
    it, the bound lies far outside what a motor gives. This is the braking distance of the bridge's braking rule
    (swim_hw_bridge.safety, rule 6) and of ros2_control's soft joint limits (joint_limits: a velocity bound set by
    the position, an acceleration bound set by the velocity), taken exactly over one zero-order-hold period. The
    two bounds never cross, and neither forbids accelerating away from its stop. The defaults brake as fast as
    the plans themselves do near the stops, so a plan followed exactly never meets the bound
    (GUARD_BRAKING_ACCELERATION_RAD_S2); feedback that drives a joint toward its stop does. A saturated motor
    may not brake as fast as the bound asks, so the guard keeps a joint off its stop without guaranteeing it:
    the bridge's braking rule does that.

    Why: the LQ stage's feedback grows with the error, and the I/O-linearized law asks the foil for whatever
    acceleration it gives; under a large error (a gust of the wake at a time scale whose plan already uses the
    motors' whole torque) it drove the heave onto its stop, where the foil makes no stroke at all and the hub,
    which only the strokes move, ran away from its plan. On the rig a stop latches the bridge's HARD_LIMIT fault.

    Parameters
    ----------
    hard_limits_rad : HardLimits
        ((heave lower, upper), (pitch lower, upper)), rad: the joints' hard stops; finite, with
        lower + 2 margin < upper.
    braking_acceleration_rad_s2 : tuple of float, optional
        a per joint (heave, pitch), rad/s^2, positive (``GUARD_BRAKING_ACCELERATION_RAD_S2``).
    margin_rad : float, optional
        How far short of each stop a joint is to come to rest, rad, >= 0 (``GUARD_MARGIN_RAD``).

    Raises
    ------
    ValueError
        If a stop, the margin or a braking acceleration is out of range.
    """

    hard_limits_rad: HardLimits   # ((heave lower, upper), (pitch lower, upper)), rad: the rig's hard stops
    braking_acceleration_rad_s2: tuple[float, float] = GUARD_BRAKING_ACCELERATION_RAD_S2
    margin_rad: float = GUARD_MARGIN_RAD

    def __post_init__(self) -> None:
        """Check the stops, the margin and the braking accelerations (Raises, above)."""
        if not (math.isfinite(self.margin_rad) and self.margin_rad >= 0.0):
            raise ValueError(f"FoilRangeGuard: margin_rad must be finite and >= 0, got {self.margin_rad!r}")
        for joint, ((lower, upper), braking) in zip(("heave", "pitch"),
                                                   zip(self.hard_limits_rad, self.braking_acceleration_rad_s2)):
            if not (math.isfinite(lower) and math.isfinite(upper) and lower + 2.0 * self.margin_rad < upper):
                raise ValueError(f"FoilRangeGuard: the {joint} stops must be finite with lower + 2 margin < upper, "
                                 f"got ({lower!r}, {upper!r}) and margin {self.margin_rad!r}")
            if not (math.isfinite(braking) and braking > 0.0):
                raise ValueError(f"FoilRangeGuard: the {joint} braking acceleration must be positive and finite, "
                                 f"got {braking!r}")

    def bound(self, u: Sequence[float], psi: Sequence[float], psi_rate: Sequence[float],
              period_s: float) -> tuple[list[float], tuple[bool, bool]]:
        """Bound the law's foil acceleration so that each joint can still stop short of its hard stops.

        Parameters
        ----------
        u : sequence of 2 float
            The (heave, pitch) acceleration the law asks for, rad/s^2.
        psi : sequence of 2 float
            The measured (heave, pitch) angles, rad.
        psi_rate : sequence of 2 float
            The measured (heave, pitch) rates psidot, rad/s.
        period_s : float
            The period h over which u is held, s.

        Returns
        -------
        bounded : list of 2 float
            u bounded, rad/s^2.
        limited : tuple of 2 bool
            Whether each joint's (heave, pitch) acceleration was bounded.
        """
        bounded, limited = [], []
        for acceleration, position, rate, (lower, upper), braking in zip(
                u, psi, psi_rate, self.hard_limits_rad, self.braking_acceleration_rad_s2):
            highest = _braking_bound(upper - self.margin_rad - position, rate, braking, period_s)
            lowest = -_braking_bound(position - lower - self.margin_rad, -rate, braking, period_s)
            value = min(max(acceleration, lowest), highest)
            bounded.append(value)
            limited.append(value != acceleration)
        return bounded, (limited[0], limited[1])


def _braking_bound(room_rad: float, rate_rad_s: float, braking_rad_s2: float, period_s: float) -> float:
    """The largest acceleration (rad/s^2) toward a stop after which the joint can still come to rest short of it.

    The stop is room_rad ahead (rad, clipped at 0) of a joint moving toward it at rate_rad_s; after the acceleration,
    held over period_s, it can still come to rest there braking at braking_rad_s2 (FoilRangeGuard); -rate / period_s
    (at rest at the period's end) where it would cover the room within the period.
    """
    a, h, room = braking_rad_s2, period_s, max(room_rad, 0.0)
    if rate_rad_s * h >= 2.0 * room:
        return -rate_rad_s / h
    return (-rate_rad_s - 0.5 * a * h + math.sqrt(0.25 * a * a * h * h - a * h * rate_rad_s + 2.0 * a * room)) / h


@dataclasses.dataclass
class ControlOutput:
    """One period's result: the command and what went into it.

    Attributes
    ----------
    torque : (2,) array
        Commanded (heave, pitch) torque after saturation, N m.
    saturated : tuple of 2 bool
        Whether each was clipped at its motor limit.
    unsaturated_torque : (2,) array
        tau1 + eps before saturation, N m.
    sliding_torque : (2,) array
        eps, N m (zero when the sliding mode is off).
    error_state : (n,) array
        x = (int e_y, e_q, edot_q[, e_z]), rad s, m s, rad, m, rad/s, m/s and m/s by block.
    reference : TrajectoryPoint
        The plan at this period.
    holding : bool
        The plan has ended: the hold law is in charge.
    lag_estimate : (n_lag,) array
        z^, the flow's lag states in the law, m/s; empty for the ideal flow.
    range_guarded : tuple of 2 bool
        Whether the range guard bounded the (heave, pitch) acceleration.
    """

    torque: Array               # commanded (heave, pitch) after saturation, N m
    saturated: tuple[bool, bool]
    unsaturated_torque: Array   # tau1 + eps before saturation, N m
    sliding_torque: Array       # eps, N m (zero when the sliding mode is off)
    error_state: Array          # x
    reference: TrajectoryPoint   # the plan at this period
    holding: bool               # the plan has ended: the hold law is in charge
    lag_estimate: Array         # z^, the flow's lag states (n_lag,) in the law, m/s; empty for the ideal flow
    range_guarded: tuple[bool, bool] = (False, False)   # the range guard bounded the (heave, pitch) acceleration


class CascadeTracker:
    """The tracking law for one plan at a time; no ROS (the tracker node wraps it).

    Parameters
    ----------
    io_linearization : IoLinearization
        (q, qdot, lag) -> (Mio (2, 2), Cio qdot (2,)): the vehicle's I/O linearization (``model_io_linearization``).
    torque_limits_n_m : (2,) array
        The (heave, pitch) motor limits, N m.
    sliding_mode : SlidingMode, optional
        The sliding mode's settings.
    sliding_mode_enabled : bool, optional
        Add the sliding-mode term eps (False: the LQ stage and the I/O linearization alone).
    sample_period_s : float, optional
        The control period h, s, positive and finite: the zero-order hold's.
    lag_rate : LagRate, optional
        The circulatory flow's lag rate (``model_lag_rate``) for a tracker of plans made with that model, whose
        lag states it estimates (``LagEstimator``); None (the ideal flow) for the paper's plans. A plan of the other
        flow model is refused by ``start``.
    range_guard : FoilRangeGuard, optional
        Bounds the law's foil acceleration near the joints' stops, in the tracking law, the hold law and ``hold``;
        None: no bound (the paper's law).

    Raises
    ------
    ValueError
        If the sample period is not positive and finite, or the sliding mode's settings are invalid.

    References
    ----------
    Saimek & Li 2004, Sec. 6, Fig. 18, eqs. 19, 22-25, 33; docs/model_and_method.md section 5.
    """

    def __init__(self, io_linearization: IoLinearization, torque_limits_n_m: Array,
                 sliding_mode: SlidingMode = SlidingMode(), sliding_mode_enabled: bool = True,
                 sample_period_s: float = 0.008, lag_rate: Optional[LagRate] = None,
                 range_guard: Optional[FoilRangeGuard] = None) -> None:
        self._io = io_linearization
        self.range_guard = range_guard
        self._lag_rate = lag_rate
        self.lag_estimator: Optional[LagEstimator] = None   # made by start() for a circulatory plan
        if not (math.isfinite(sample_period_s) and sample_period_s > 0.0):
            raise ValueError(f"sample period must be positive and finite, got {sample_period_s!r}")
        self.sample_period_s = sample_period_s
        self.torque_limits_n_m = np.asarray(torque_limits_n_m, dtype=float)
        sliding_mode.validate()
        self.sliding_mode = sliding_mode
        self.sliding_mode_enabled = sliding_mode_enabled
        self.trajectory: Optional[Trajectory] = None
        self._integral: list[float] = []   # int (y - y_des) dt (ny,), rad s or m s
        self._last_time_s: Optional[float] = None

    @property
    def flow_model(self) -> str:
        """The flow model of the plans this tracker follows: "ideal" or "circulatory"."""
        return "ideal" if self._lag_rate is None else "circulatory"

    def start(self, trajectory: Trajectory, initial_lag: Optional[Array] = None) -> None:
        """Track a plan from plan time 0; the integral error restarts at zero.

        Parameters
        ----------
        trajectory : Trajectory
            The plan, made with the tracker's flow model.
        initial_lag : (n_lag,) array, optional
            Where a circulatory plan's lag estimate starts at the first step, m/s; by default the plan's own lag
            states at t = 0: the tracker starts a plan with the vehicle taken to be on the plan's start, of which
            the lag states are part; a planned start from rest has z = 0 there, still water, so both readings
            agree, and a start elsewhere (a plan begun mid-stroke) is right where the plan is.

        Raises
        ------
        PlanError
            If the plan was made with another flow model than the tracker's.
        """
        if trajectory.flow_model != self.flow_model:
            raise PlanError(f"the plan was made with the {trajectory.flow_model} flow model, this tracker runs the "
                            f"{self.flow_model} one")
        self.trajectory = trajectory
        self._integral = [0.0] * trajectory.ny
        self._last_time_s = None
        if self._lag_rate is not None:
            assert trajectory.lag is not None   # a circulatory Trajectory has its lag states
            self.lag_estimator = LagEstimator(self._lag_rate, trajectory.n_lag)
            self.lag_estimator.reset(trajectory.lag[0] if initial_lag is None else initial_lag)

    def step(self, plan_time_s: float, q: Array, qdot: Array) -> ControlOutput:
        """The torque for one control period: the cascade law (module docstring), or the hold law after the plan.

        Parameters
        ----------
        plan_time_s : float
            Plan time at the period's start, s.
        q : (nq,) array
            Measured positions, rad and m.
        qdot : (nq,) array
            Measured velocities, rad/s and m/s.

        Returns
        -------
        ControlOutput
            The command and what went into it.

        Raises
        ------
        PlanError
            If no plan was started.
        """
        trajectory = self.trajectory
        if trajectory is None:
            raise PlanError("no plan: call start() first")
        ref = trajectory.sample(plan_time_s)
        holding = plan_time_s > trajectory.duration_s
        # the vectors of the law on Python floats: a handful of scalars each, where numpy's per-call overhead would
        # be most of the step; the products with matrices stay numpy's (its BLAS sums in an order of its own)
        error_q = [measured - planned for measured, planned in zip(q.tolist(), ref.q.tolist())]
        elapsed_s = 0.0 if self._last_time_s is None else plan_time_s - self._last_time_s
        if self._last_time_s is not None and not holding:
            integrated_s = max(elapsed_s, 0.0)
            self._integral = [total + error * integrated_s for total, error in zip(self._integral, error_q)]
        self._last_time_s = plan_time_s
        errors = self._integral + error_q + [measured - planned for measured, planned
                                             in zip(qdot.tolist(), ref.qdot.tolist())]
        lag = NO_LAG
        if self.lag_estimator is not None:
            lag = self.lag_estimator.update(elapsed_s, q, qdot)
            errors += [estimated - planned for estimated, planned in zip(lag.tolist(), ref.lag.tolist())]
        error_state = np.array(errors)
        mio, cio_qdot = self._io(q, qdot, lag)
        if holding:
            nq = trajectory.nq
            u = hold_acceleration(q[nq - 2:], qdot[nq - 2:], trajectory.q[-1, nq - 2:])
        else:
            # the torque is held for one period: feed forward u_des at the period's midpoint
            heave_des, pitch_des = trajectory.foil_acceleration_at(plan_time_s + 0.5 * self.sample_period_s)
            heave_feedback, pitch_feedback = (ref.lqr_gain @ error_state).tolist()
            u = np.array([heave_des - heave_feedback, pitch_des - pitch_feedback])
        guarded = (False, False)
        if self.range_guard is not None:
            nq = trajectory.nq
            bounded, guarded = self.range_guard.bound(u.tolist(), q[nq - 2:].tolist(), qdot[nq - 2:].tolist(),
                                                      self.sample_period_s)
            u = np.array(bounded)
        torque = [inertial + rest for inertial, rest in zip((mio @ u).tolist(), cio_qdot.tolist())]
        sliding = [0.0, 0.0]
        if self.sliding_mode_enabled and not holding:
            s_heave, s_pitch = solve(mio, ref.riccati_input_gain @ error_state).tolist()
            factor = self.sliding_mode.term_factor(math.hypot(s_heave, s_pitch), ref.disturbance_bound_n_m)
            sliding = [s_heave * factor, s_pitch * factor]
            torque = [law + term for law, term in zip(torque, sliding)]
        command, saturated = saturate(torque, self.torque_limits_n_m)
        return ControlOutput(torque=command, saturated=saturated, unsaturated_torque=np.array(torque),
                             sliding_torque=np.array(sliding), error_state=error_state, reference=ref,
                             holding=holding, lag_estimate=lag, range_guarded=guarded)

    def hold(self, q: Array, qdot: Array, psi_target: Array) -> tuple[Array, tuple[bool, bool]]:
        """The torque that holds the foil still at a target, with no plan involved.

        A state comes without its time here, one a period: the lag estimate advances by ``sample_period_s``.

        Parameters
        ----------
        q, qdot : (nq,) array
            The measured positions (rad, m) and velocities (rad/s, m/s).
        psi_target : (2,) array
            The (heave, pitch) angles to hold, rad.

        Returns
        -------
        torque : (2,) array
            The saturated (heave, pitch) command, N m.
        saturated : tuple of 2 bool
            Whether each was clipped at its motor limit.
        """
        lag = NO_LAG
        if self.lag_estimator is not None:
            lag = self.lag_estimator.update(self.sample_period_s, q, qdot)
        elif self._lag_rate is not None:   # no plan started yet: the flow taken at rest
            lag = np.zeros(len(LAG_STATE_NAMES))
        mio, cio_qdot = self._io(q, qdot, lag)
        u = hold_acceleration(q[-2:], qdot[-2:], psi_target)
        if self.range_guard is not None:
            u = np.array(self.range_guard.bound(u.tolist(), q[-2:].tolist(), qdot[-2:].tolist(),
                                                self.sample_period_s)[0])
        torque = mio @ u + cio_qdot
        return saturate(torque, self.torque_limits_n_m)


def model_io_linearization(model: VehicleModel) -> IoLinearization:
    """The I/O linearization of a VehicleModel, called on its compiled C entry point directly.

    VehicleModel.native_function gives the same numbers; the checked numpy API costs ~15 us more per call and
    CasADi's own call ~45 us, too much at 1 kHz; the tracker validates states itself.

    Parameters
    ----------
    model : VehicleModel
        The vehicle, ideal or circulatory flow.

    Returns
    -------
    IoLinearization
        (q (nq,), qdot (nq,), lag (n_lag,) m/s) -> (Mio (2, 2), Cio qdot (2,) N m) of eqs. 22-23.
    """
    function = model.native_function("io_linearization")
    (q_input, qdot_input, *lag_input), (mio_output, cio_output) = function.inputs, function.outputs
    mio_shape = function.function.size_out(0)

    if not lag_input:   # the ideal flow: no lag states (lag is empty)
        def evaluate(q: Array, qdot: Array, lag: Array) -> tuple[Array, Array]:
            q_input[:], qdot_input[:] = q, qdot
            function()
            return mio_output.reshape(mio_shape, order="F").copy(), cio_output.copy()
        return evaluate
    lag_buffer, = lag_input

    def evaluate_with_lag(q: Array, qdot: Array, lag: Array) -> tuple[Array, Array]:
        q_input[:], qdot_input[:], lag_buffer[:] = q, qdot, lag
        function()
        return mio_output.reshape(mio_shape, order="F").copy(), cio_output.copy()
    return evaluate_with_lag


def model_lag_rate(model: VehicleModel) -> Optional[LagRate]:
    """The lag rate zdot = g(q, qdot, z) of a circulatory VehicleModel on its compiled C entry point.

    As ``model_io_linearization``; one buffer set per model: the value returned is a copy.

    Parameters
    ----------
    model : VehicleModel
        The vehicle.

    Returns
    -------
    LagRate or None
        (q, qdot, z) -> zdot (n_lag,), m/s^2; None for the ideal flow.
    """
    if model.n_lag == 0:
        return None
    function = model.native_function("lag_rate")
    (q_input, qdot_input, lag_input), (rate_output,) = function.inputs, function.outputs

    def evaluate(q: Array, qdot: Array, lag: Array) -> Array:
        q_input[:], qdot_input[:], lag_input[:] = q, qdot, lag
        function()
        return rate_output.copy()
    return evaluate


def hold_acceleration(psi: Array, psi_rate: Array, psi_target: Array) -> Array:
    """The hold law's foil acceleration: a critically damped return to psi_target.

    Parameters
    ----------
    psi : (2,) array
        Measured (heave, pitch), rad.
    psi_rate : (2,) array
        Measured psidot, rad/s.
    psi_target : (2,) array
        The angles to hold, rad.

    Returns
    -------
    (2,) array
        u = -kp (psi - psi_target) - kd psidot, rad/s^2 (``HOLD_STIFFNESS_PER_S2``, ``HOLD_DAMPING_PER_S``).
    """
    return -HOLD_STIFFNESS_PER_S2 * (psi - psi_target) - HOLD_DAMPING_PER_S * psi_rate


def saturate(torque: Sequence[float] | Array, limits: Array) -> tuple[Array, tuple[bool, bool]]:
    """Clip a (heave, pitch) torque to the motor limits; a non-finite torque becomes zero and counts as saturated.

    Parameters
    ----------
    torque : sequence of 2 float or (2,) array
        (heave, pitch), N m.
    limits : (2,) array
        The motor limits, N m, positive.

    Returns
    -------
    command : (2,) array
        The torque clipped to +-limits, N m.
    saturated : tuple of 2 bool
        Whether each was clipped.
    """
    heave, pitch = float(torque[0]), float(torque[1])
    heave_limit, pitch_limit = float(limits[0]), float(limits[1])
    if not (math.isfinite(heave) and math.isfinite(pitch)):
        return np.zeros(2), (True, True)
    command = np.array([min(max(heave, -heave_limit), heave_limit), min(max(pitch, -pitch_limit), pitch_limit)])
    return command, (abs(heave) > heave_limit, abs(pitch) > pitch_limit)


def solve(matrix: Array, rhs: Array) -> Array:
    """matrix^-1 rhs by numpy.linalg.solve's own LAPACK kernel (gesv), without its per-call checks.

    The same numbers, without the argument checks and floating-point error state numpy sets up per call (most of
    the ~8 us it takes for a 2 x 2). For a matrix that cannot be singular, as Mio (an inertia, positive definite at
    every finite state): a singular one gives non-finite entries and a RuntimeWarning, not LinAlgError.

    Parameters
    ----------
    matrix : (n, n) array
        Square, non-singular.
    rhs : (n,) array
        The right-hand side.

    Returns
    -------
    (n,) array
        The solution.
    """
    solution: Array = _umath_linalg.solve1(matrix, rhs, signature="dd->d")
    return solution
