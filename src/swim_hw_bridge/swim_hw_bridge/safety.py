"""The bridge's safety rules, pure and ROS-free: what current may reach the motors this period.

Per period, in this order (SafetyLayer.output):
1. any latched fault (FaultCode, including the e-stop): zero current, whatever the rules below say;
2. no command newer than the last reset or activation (WatchdogState.WAITING): zero torque asked;
3. command watchdog on the monotonic clock: the latest command older than watchdog_timeout_s
   (N sample periods): zero torque asked (WatchdogState.EXPIRED); a newer command resumes;
4. a non-finite torque: zero and the NONFINITE_OUTPUT fault;
5. torque saturation |tau| <= tau_max (Sec. 2 limits), counted;
6. braking: a joint moving toward a hard limit faster than it can still stop by it gets the full braking torque
   instead of what is asked, zero included (braking protects the rig whether or not a command is in: a link the
   watchdog left at zero torque would coast through its limit). Its speed toward the limit at the sample is the
   mean rate over the last sample interval h_s (Motion: the encoders' difference quotient, the speed at the
   interval's middle, with no filter lag) plus the most it can have gained over the half after,
   (A_last + D) h_s / 2. The bound at distance d from the limit is braking_speed_limit: within the latency L (one
   period: a loop that keeps missing its deadlines latches OVERRUN) the link may still be driven at up to A + D,
   then brakes at a - D. Here (JointDynamicsBounds, braking.py, from the model) a = BRAKING_TORQUE_FRACTION
   tau_max / max M_jj over the joints' ranges is what its own motor surely gives (a lower bound on tau (M^-1)_jj,
   with room left for the other motor's torque through the off-diagonal inertia), A = max tau_max (M^-1)_jj the
   most it gives, A_last what the last period's torque toward the limit gave at most, and D the velocity terms'
   acceleration toward the limit at the present state, -(M^-1 Cm qdot)_j when it points there (else 0): the
   heave's swing throws the light foil, at 5 rad/s of heave up to 160 rad/s^2 of pitch acceleration, half of what
   the pitch motor gives. Once braking, a joint brakes until stopped. As ros2_control's soft joint limits bound
   velocity by position;
7. soft limits: with p the joint position, [lo, hi] its hard limits and m the margin, torque pushing outward
   is scaled by s = clamp((hi - p) / m, 0, 1) near the upper limit (tau > 0) and by
   s = clamp((p - lo) / m, 0, 1) near the lower one (tau < 0); torque back inward is never scaled;
8. current i = tau / (N Kt), saturated |i| <= i_max, counted.
Past a hard limit (p < lo or p > hi) the HARD_LIMIT fault latches (check_positions).
Faults latch until reset(); after a reset the output stays zero until a command received after it. A joint past
its hard limit at a reset is recovering: it does not latch HARD_LIMIT again, and accepts only torque back toward
its range, at most RECOVERY_TORQUE_FRACTION of its limit, until it is inside; so the rig recovers without a
restart.

Device reads: the same sample sequence stale_read_limit times in a row latches STALE_READ; read_failure_limit
failed reads in a row latch READ_FAILED (check_read).

Commands reach the layer already decoded (swim_ros.codecs.torque_from_command: names exactly {phi, theta} once
each, as many efforts as names, all finite; the node counts and drops anything else).
"""
from __future__ import annotations

import dataclasses
import enum
import math
from typing import Callable

from swim_hw_bridge.conversions import BridgeConfig
from swim_model.limits import HardLimits


class FaultCode(enum.IntFlag):
    """Latched faults, a bit each (several may be latched at once)."""

    NONE = 0
    EMERGENCY_STOP = 1
    NONFINITE_OUTPUT = 2
    HARD_LIMIT = 4
    READ_FAILED = 8
    STALE_READ = 16
    ENCODER_JUMP = 32
    OVERRUN = 64
    DEVICE_FAILED = 128
    INTERNAL_ERROR = 256


def fault_names(faults: FaultCode) -> str:
    """'NONE' or the latched faults' names joined by '|' (stable across Python versions)."""
    names = [member.name for member in FaultCode if member and member & faults]
    return "|".join(n for n in names if n) or "NONE"


class WatchdogState(enum.IntEnum):
    """The command watchdog's state."""

    WAITING = 0   # no command received since the last reset or activation
    OK = 1
    EXPIRED = 2   # the latest command is older than the timeout: torque zero


@dataclasses.dataclass(frozen=True)
class Command:
    """The latest torque command as the I/O loop sees it.

    received_monotonic_s: time.monotonic() when the node received it (the watchdog's clock).
    stamp_ns: the message's header stamp, carried to snapshots for tracing.
    """

    heave_torque_n_m: float
    pitch_torque_n_m: float
    received_monotonic_s: float
    stamp_ns: int = 0


def soft_limit_scale(position: float, torque: float, lower: float, upper: float, margin: float) -> float:
    """Factor in [0, 1] for torque at position.

    It is 1 away from the limits and for torque pointing inward, falling linearly to 0 at the hard limit for
    torque pointing outward (see the module docstring).
    """
    if torque > 0.0:
        return min(max((upper - position) / margin, 0.0), 1.0)
    if torque < 0.0:
        return min(max((position - lower) / margin, 0.0), 1.0)
    return 1.0


#: the share of a motor's torque limit the braking bound counts on. Assumed: three quarters, leaving a quarter for
#: friction and for the other motor's full torque through the off-diagonal inertia (which that quarter covers over
#: the whole range: test_braking checks it); the velocity terms are counted on their own (rule 6). With half, the
#: shipped plans' pitch rates would reach the bound and the limiter would brake planned motion
BRAKING_TORQUE_FRACTION = 0.75
#: the torque a joint past its hard limit may get back toward its range after a reset. Assumed: a third of the
#: limit brings the link back in well under a second without slamming it into the opposite side
RECOVERY_TORQUE_FRACTION = 1.0 / 3.0

#: (alpha, R, phi, theta) positions and rates -> the (heave, pitch) accelerations of the velocity terms, rad/s^2
VelocityTerms = Callable[[tuple[float, float, float, float], tuple[float, float, float, float]], tuple[float, float]]


def braking_speed_limit(distance_rad: float, deceleration_rad_s2: float, latency_s: float,
                        drive_acceleration_rad_s2: float = 0.0) -> float:
    """The largest speed v toward a limit distance_rad away from which a joint still stops by the limit.

    The joint may still be driven at drive_acceleration_rad_s2 for latency_s, then brakes at deceleration_rad_s2:
    with u = v + A L the speed when braking starts, d = v L + A L^2 / 2 + u^2 / (2 a), so
    u = a (sqrt(L^2 + (2 d + A L^2) / a) - L) and v = u - A L; 0 at or past the limit, when even v = 0 is too
    fast, or when the joint cannot be braked at all (a <= 0).
    """
    if distance_rad <= 0.0 or deceleration_rad_s2 <= 0.0:
        return 0.0
    if math.isinf(deceleration_rad_s2):
        return math.inf
    a, t, drive = deceleration_rad_s2, latency_s, drive_acceleration_rad_s2
    braking_speed = a * (math.sqrt(t * t + (2.0 * distance_rad + drive * t * t) / a) - t)
    return max(braking_speed - drive * t, 0.0)


@dataclasses.dataclass(frozen=True)
class JointDynamicsBounds:
    """What the braking rule counts on for each joint (heave, pitch).

    braking.py builds it from the model; the defaults: no braking bound.

    decelerations_rad_s2: a, what its own motor surely gives, BRAKING_TORQUE_FRACTION tau_max / max M_jj;
    drive_accelerations_rad_s2: A, the most its own motor gives, max tau_max (M^-1)_jj;
    velocity_terms: the velocity terms' accelerations -(M^-1 Cm(q, qdot) qdot) of the joints at a state (None:
        none counted).
    """

    decelerations_rad_s2: tuple[float, float] = (math.inf, math.inf)
    drive_accelerations_rad_s2: tuple[float, float] = (0.0, 0.0)
    velocity_terms: VelocityTerms | None = None


@dataclasses.dataclass(frozen=True)
class Motion:
    """What the braking rule reads of the rig's motion at a sample.

    The (alpha rad, R m, phi rad, theta rad) positions, their mean rates over the last sample interval (the
    difference quotient of the last two samples, rad/s and m/s) and that interval, s (0: none yet, rates zero).
    """

    positions: tuple[float, float, float, float]
    mean_rates: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    interval_s: float = 0.0


@dataclasses.dataclass(frozen=True)
class SafetyLimits:
    """Everything the rules need, in SI units; joint pairs are (heave, pitch)."""

    torque_limits_n_m: tuple[float, float]
    current_limits_a: tuple[float, float]
    torque_gains_n_m_per_a: tuple[float, float]
    hard_limits_rad: HardLimits
    soft_limit_margins_rad: tuple[float, float]
    watchdog_timeout_s: float
    stale_read_limit: int
    read_failure_limit: int
    dynamics: JointDynamicsBounds = JointDynamicsBounds()   # the default: no braking bound
    latency_s: float = 0.0   # from a state's read to the torque it sets: one period

    @classmethod
    def from_config(cls, config: BridgeConfig, sample_period_s: float, watchdog_periods: int,
                    stale_read_limit: int, read_failure_limit: int,
                    dynamics: JointDynamicsBounds = JointDynamicsBounds()) -> "SafetyLimits":
        """The limits of a bridge configuration, its period and fault counts."""
        return cls(
            torque_limits_n_m=config.rig.torque_limits_n_m, current_limits_a=config.current_limits_a,
            torque_gains_n_m_per_a=config.motor_torque_gains_n_m_per_a,
            hard_limits_rad=config.rig.hard_limits_rad,
            soft_limit_margins_rad=config.rig.limits.soft_margins_rad,
            watchdog_timeout_s=watchdog_periods * sample_period_s, stale_read_limit=stale_read_limit,
            read_failure_limit=read_failure_limit, dynamics=dynamics, latency_s=sample_period_s)


class SafetyLayer:
    """State of the rules across periods: latched faults, watchdog, read health, saturation count."""

    def __init__(self, limits: SafetyLimits) -> None:
        self.limits = limits
        self.faults = FaultCode.NONE
        self.watchdog = WatchdogState.WAITING
        self.saturation_count = 0         # periods in which a torque or a current was clipped
        self.braking_count = 0            # periods in which a joint was braked short of a hard limit
        self.braking = [0, 0]             # per joint: +1 braking toward its upper limit, -1 its lower, 0 not
        self._last_torques = [0.0, 0.0]   # the joint torques of the period before, N m
        self.recovering = [False, False]  # a joint past its hard limit at the last reset, not yet back inside
        self._resume_after_s = -math.inf  # only commands received after this time are used
        self._last_sequence: int | None = None
        self._stale_reads = 0
        self._failed_reads = 0

    # --- latches ---------------------------------------------------------------------------------------
    def latch(self, fault: FaultCode) -> None:
        """Latch a fault: zero output until a reset."""
        self.faults |= fault

    def emergency_stop(self) -> None:
        """Latch the emergency stop."""
        self.latch(FaultCode.EMERGENCY_STOP)

    def reset(self, now_s: float) -> None:
        """Clear every latched fault; output resumes only with a command received after now_s.

        A joint found past its hard limit at the next check_positions is recovering (see the module docstring).
        """
        self.faults = FaultCode.NONE
        self.recovering = [True, True]
        self.arm(now_s)

    def arm(self, now_s: float) -> None:
        """Require a command received after now_s before any torque (on activation and reset)."""
        self._resume_after_s = now_s
        self.watchdog = WatchdogState.WAITING

    # --- device health ----------------------------------------------------------------------------------
    def check_read(self, sequence: int | None) -> None:
        """After each read: sequence of the sample, or None when the read failed."""
        if sequence is None:
            self._failed_reads += 1
            if self._failed_reads >= self.limits.read_failure_limit:
                self.latch(FaultCode.READ_FAILED)
            return
        self._failed_reads = 0
        self._stale_reads = self._stale_reads + 1 if sequence == self._last_sequence else 0
        self._last_sequence = sequence
        if self._stale_reads >= self.limits.stale_read_limit:
            self.latch(FaultCode.STALE_READ)

    def check_positions(self, heave_rad: float, pitch_rad: float) -> None:
        """Latch HARD_LIMIT when a joint is past (or cannot be placed within) its hard limits.

        A joint recovering from a reset does not latch; a NaN position always latches.
        """
        for joint, (position, (lower, upper)) in enumerate(zip((heave_rad, pitch_rad), self.limits.hard_limits_rad)):
            inside = lower <= position <= upper   # false for NaN
            if inside or math.isnan(position):
                self.recovering[joint] = False
            if not inside and not self.recovering[joint]:
                self.latch(FaultCode.HARD_LIMIT)

    # --- the output --------------------------------------------------------------------------------------
    def output(self, now_s: float, command: Command | None, heave_rad: float, pitch_rad: float,
               motion: Motion | None = None) -> tuple[float, float, float, float]:
        """The currents to write and the joint torques they make: (heave_a, pitch_a, heave_n_m, pitch_n_m).

        For the joints' positions (rad) and the rig's motion (None: at rest as far as is known).
        """
        requested = self._requested(now_s, command)
        if requested is None:
            self._last_torques = [0.0, 0.0]
            return 0.0, 0.0, 0.0, 0.0
        velocity_terms = self.limits.dynamics.velocity_terms
        if motion is None:
            motion, accelerations = Motion((0.0, 0.0, heave_rad, pitch_rad)), (0.0, 0.0)
        else:
            accelerations = velocity_terms(motion.positions, motion.mean_rates) if velocity_terms else (0.0, 0.0)
        heave_a, heave_n_m, heave_clipped = self._joint(0, requested[0], heave_rad, motion, accelerations[0])
        pitch_a, pitch_n_m, pitch_clipped = self._joint(1, requested[1], pitch_rad, motion, accelerations[1])
        if not (math.isfinite(heave_a) and math.isfinite(pitch_a)):
            self.latch(FaultCode.NONFINITE_OUTPUT)
            self._last_torques = [0.0, 0.0]
            return 0.0, 0.0, 0.0, 0.0
        if heave_clipped or pitch_clipped:
            self.saturation_count += 1
        self._last_torques = [heave_n_m, pitch_n_m]
        return heave_a, pitch_a, heave_n_m, pitch_n_m

    def _requested(self, now_s: float, command: Command | None) -> tuple[float, float] | None:
        """The (heave, pitch) torque asked of the joints before the limits.

        The command's, or zero while waiting for one or with the watchdog expired; None for zero output whatever
        the braking rule says (a latched fault).
        """
        if command is None or command.received_monotonic_s <= self._resume_after_s:
            self.watchdog = WatchdogState.WAITING
            return None if self.faults else (0.0, 0.0)
        expired = now_s - command.received_monotonic_s > self.limits.watchdog_timeout_s
        self.watchdog = WatchdogState.EXPIRED if expired else WatchdogState.OK
        if self.faults:
            return None
        if expired:
            return 0.0, 0.0
        if not (math.isfinite(command.heave_torque_n_m) and math.isfinite(command.pitch_torque_n_m)):
            self.latch(FaultCode.NONFINITE_OUTPUT)   # infinity is a fault too, not a saturation
            return None
        return command.heave_torque_n_m, command.pitch_torque_n_m

    def _joint(self, joint: int, torque_n_m: float, position: float, motion: Motion,
               velocity_term_rad_s2: float) -> tuple[float, float, bool]:
        """The current (A), joint torque (N m) and whether it was clipped, for one motor.

        A NaN position gives a NaN current, which the caller catches.
        """
        limits = self.limits
        torque_limit = limits.torque_limits_n_m[joint]
        clipped = abs(torque_n_m) > torque_limit
        torque_n_m = min(max(torque_n_m, -torque_limit), torque_limit)
        lower, upper = limits.hard_limits_rad[joint]
        if position > upper or position < lower:   # recovering: only back toward the range, bounded
            recovery = RECOVERY_TORQUE_FRACTION * torque_limit
            torque_n_m = min(max(torque_n_m, -recovery), 0.0) if position > upper else \
                min(max(torque_n_m, 0.0), recovery)
            self.braking[joint] = 0
        elif self._braking(joint, position, motion, velocity_term_rad_s2):
            torque_n_m = -self.braking[joint] * torque_limit
            self.braking_count += 1
        else:
            torque_n_m *= soft_limit_scale(position, torque_n_m, lower, upper, limits.soft_limit_margins_rad[joint])
        gain = limits.torque_gains_n_m_per_a[joint]
        current_a = torque_n_m / gain
        current_limit = limits.current_limits_a[joint]
        if abs(current_a) > current_limit:
            clipped = True
            current_a = min(max(current_a, -current_limit), current_limit)
        return current_a, current_a * gain, clipped

    def _braking(self, joint: int, position: float, motion: Motion, velocity_term_rad_s2: float) -> int:
        """Rule 6 for a joint within its limits, whose velocity terms accelerate it by velocity_term_rad_s2.

        +1 braking it short of its upper limit, -1 of its lower one, 0 not (kept in self.braking: once braking,
        until stopped).
        """
        limits, dynamics = self.limits, self.limits.dynamics
        lower, upper = limits.hard_limits_rad[joint]
        drive, deceleration = dynamics.drive_accelerations_rad_s2[joint], dynamics.decelerations_rad_s2[joint]
        latency, half_interval = limits.latency_s, 0.5 * motion.interval_s
        last_share = self._last_torques[joint] / limits.torque_limits_n_m[joint]
        rate = motion.mean_rates[2 + joint]
        # per limit: the velocity terms' push toward it (D), and the speed toward it at the sample: the mean rate
        # is the speed at the interval's middle; over the half after, the last period's torque toward that limit
        # and the push added at most this much
        push_up, push_down = max(velocity_term_rad_s2, 0.0), max(-velocity_term_rad_s2, 0.0)
        toward_upper = rate + (max(last_share, 0.0) * drive + push_up) * half_interval
        toward_lower = -rate + (max(-last_share, 0.0) * drive + push_down) * half_interval
        # once braking, brake until stopped: switching back to the command at the bound would drive the link on
        # for a period each time and creep past the bound
        braking = self.braking[joint]
        if braking > 0 and toward_upper <= 0.0 or braking < 0 and toward_lower <= 0.0:
            braking = 0
        if braking == 0 and toward_upper > braking_speed_limit(upper - position, deceleration - push_up, latency,
                                                               drive + push_up):
            braking = 1
        elif braking == 0 and toward_lower > braking_speed_limit(position - lower, deceleration - push_down,
                                                                 latency, drive + push_down):
            braking = -1
        self.braking[joint] = braking
        return braking
