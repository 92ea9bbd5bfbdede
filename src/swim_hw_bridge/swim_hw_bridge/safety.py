"""The bridge's safety rules, pure and ROS-free: what current may reach the motors this period.

Per period, in this order (SafetyLayer.output):
1. any latched fault (FaultCode, including the e-stop): zero current;
2. no command newer than the last reset or activation (WatchdogState.WAITING): zero;
3. command watchdog on the monotonic clock: the latest command older than watchdog_timeout_s
   (N sample periods): zero (WatchdogState.EXPIRED); a newer command resumes;
4. a non-finite torque: zero and the NONFINITE_OUTPUT fault;
5. torque saturation |tau| <= tau_max (Sec. 2 limits), counted;
6. braking: a joint moving toward a hard limit faster than it can still stop by it gets the full braking torque
   instead of its command. The speed bound at distance d from the limit, one period T of latency included, is
   braking_speed_limit: within the latency L (one period) the link may still be driven
   at up to A, the most its motor can accelerate it, and then brakes at a, the deceleration the motor can surely
   give: BRAKING_TORQUE_FRACTION of its torque limit over the largest diagonal entry of the joint-space inertia
   over the joint's range (braking.py, from the model), a lower bound on tau (M^-1)_jj. Once braking, a joint
   brakes until it stops. As ros2_control's soft joint limits bound velocity by position;
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

from swim_hw_bridge.conversions import BridgeConfig

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
    """Factor in [0, 1] for torque at position: 1 away from the limits and for torque pointing inward,
    falling linearly to 0 at the hard limit for torque pointing outward (see the module docstring)."""
    if torque > 0.0:
        return min(max((upper - position) / margin, 0.0), 1.0)
    if torque < 0.0:
        return min(max((position - lower) / margin, 0.0), 1.0)
    return 1.0


#: the share of a motor's torque limit the braking bound counts on. Assumed: three quarters, leaving a quarter for
#: the friction and coupling forces the inertia bound leaves out; with half, the shipped plans' pitch rates would
#: reach the bound (1.5 times it at worst) and the limiter would brake planned motion
BRAKING_TORQUE_FRACTION = 0.75
#: the torque a joint past its hard limit may get back toward its range after a reset. Assumed: a third of the
#: limit brings the link back in well under a second without slamming it into the opposite side
RECOVERY_TORQUE_FRACTION = 1.0 / 3.0


def braking_speed_limit(distance_rad: float, deceleration_rad_s2: float, latency_s: float,
                        drive_acceleration_rad_s2: float = 0.0) -> float:
    """The largest speed v toward a limit distance_rad away from which a joint that may still be driven at
    drive_acceleration_rad_s2 for latency_s, then brakes at deceleration_rad_s2, stops by the limit:
    with u = v + A L the speed when braking starts, d = v L + A L^2 / 2 + u^2 / (2 a), so
    u = a (sqrt(L^2 + (2 d + A L^2) / a) - L) and v = u - A L; 0 at or past the limit (or when even v = 0 is too
    fast)."""
    if distance_rad <= 0.0:
        return 0.0
    if math.isinf(deceleration_rad_s2):
        return math.inf
    a, t, drive = deceleration_rad_s2, latency_s, drive_acceleration_rad_s2
    braking_speed = a * (math.sqrt(t * t + (2.0 * distance_rad + drive * t * t) / a) - t)
    return max(braking_speed - drive * t, 0.0)


@dataclasses.dataclass(frozen=True)
class SafetyLimits:
    """Everything the rules need, in SI units; joint pairs are (heave, pitch)."""

    torque_limits_n_m: tuple[float, float]
    current_limits_a: tuple[float, float]
    torque_gains_n_m_per_a: tuple[float, float]
    hard_limits_rad: tuple[tuple[float, float], tuple[float, float]]
    soft_limit_margins_rad: tuple[float, float]
    watchdog_timeout_s: float
    stale_read_limit: int
    read_failure_limit: int
    braking_decelerations_rad_s2: tuple[float, float] = (math.inf, math.inf)   # inf: no braking bound
    drive_accelerations_rad_s2: tuple[float, float] = (0.0, 0.0)   # the most the motors can accelerate a link
    latency_s: float = 0.0   # from a state's read to the torque it sets: one period
    rate_lag_s: float = 0.0  # the rate filter's time constant: under an acceleration a its estimate lags by a lag

    @classmethod
    def from_config(cls, config: BridgeConfig, sample_period_s: float, watchdog_periods: int,
                    stale_read_limit: int, read_failure_limit: int,
                    braking_decelerations_rad_s2: tuple[float, float] = (math.inf, math.inf),
                    drive_accelerations_rad_s2: tuple[float, float] = (0.0, 0.0)) -> "SafetyLimits":
        return cls(
            torque_limits_n_m=config.torque_limits_n_m, current_limits_a=config.current_limits_a,
            torque_gains_n_m_per_a=config.motor_torque_gains_n_m_per_a,
            hard_limits_rad=((config.heave_lower_hard_limit_rad, config.heave_upper_hard_limit_rad),
                             (config.pitch_lower_hard_limit_rad, config.pitch_upper_hard_limit_rad)),
            soft_limit_margins_rad=(config.heave_soft_limit_margin_rad, config.pitch_soft_limit_margin_rad),
            watchdog_timeout_s=watchdog_periods * sample_period_s, stale_read_limit=stale_read_limit,
            read_failure_limit=read_failure_limit, braking_decelerations_rad_s2=braking_decelerations_rad_s2,
            drive_accelerations_rad_s2=drive_accelerations_rad_s2,
            latency_s=sample_period_s, rate_lag_s=1.0 / (2.0 * math.pi * config.velocity_cutoff_hz))


class SafetyLayer:
    """State of the rules across periods: latched faults, watchdog, read health, saturation count."""

    def __init__(self, limits: SafetyLimits) -> None:
        self.limits = limits
        self.faults = FaultCode.NONE
        self.watchdog = WatchdogState.WAITING
        self.saturation_count = 0         # periods in which a torque or a current was clipped
        self.braking_count = 0            # periods in which a joint was braked short of a hard limit
        self.braking = [0, 0]             # per joint: +1 braking toward its upper limit, -1 its lower, 0 not
        self._last_rates = [0.0, 0.0]     # the rate estimates of the period before, rad/s
        self.recovering = [False, False]  # a joint past its hard limit at the last reset, not yet back inside
        self._resume_after_s = -math.inf  # only commands received after this time are used
        self._last_sequence: int | None = None
        self._stale_reads = 0
        self._failed_reads = 0

    # --- latches ---------------------------------------------------------------------------------------
    def latch(self, fault: FaultCode) -> None:
        self.faults |= fault

    def emergency_stop(self) -> None:
        self.latch(FaultCode.EMERGENCY_STOP)

    def reset(self, now_s: float) -> None:
        """Clear every latched fault; output resumes only with a command received after now_s. A joint found past
        its hard limit at the next check_positions is recovering (see the module docstring)."""
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
        """Latch HARD_LIMIT when a joint is past (or cannot be placed within) its hard limits, unless it is
        recovering from a reset (a NaN position always latches)."""
        for joint, (position, (lower, upper)) in enumerate(zip((heave_rad, pitch_rad), self.limits.hard_limits_rad)):
            inside = lower <= position <= upper   # false for NaN
            if inside or math.isnan(position):
                self.recovering[joint] = False
            if not inside and not self.recovering[joint]:
                self.latch(FaultCode.HARD_LIMIT)

    # --- the output --------------------------------------------------------------------------------------
    def output(self, now_s: float, command: Command | None, heave_rad: float, pitch_rad: float,
               heave_rate_rad_s: float = 0.0, pitch_rate_rad_s: float = 0.0) -> tuple[float, float, float, float]:
        """(heave_a, pitch_a, heave_n_m, pitch_n_m): currents to write and the joint torques they make, for the
        joints' positions and rates (rad, rad/s)."""
        if command is None or command.received_monotonic_s <= self._resume_after_s:
            self.watchdog = WatchdogState.WAITING
            return 0.0, 0.0, 0.0, 0.0
        expired = now_s - command.received_monotonic_s > self.limits.watchdog_timeout_s
        self.watchdog = WatchdogState.EXPIRED if expired else WatchdogState.OK
        if self.faults or expired:
            return 0.0, 0.0, 0.0, 0.0
        if not (math.isfinite(command.heave_torque_n_m) and math.isfinite(command.pitch_torque_n_m)):
            self.latch(FaultCode.NONFINITE_OUTPUT)   # infinity is a fault too, not a saturation
            return 0.0, 0.0, 0.0, 0.0
        heave_a, heave_n_m, heave_clipped = self._joint(0, command.heave_torque_n_m, heave_rad, heave_rate_rad_s)
        pitch_a, pitch_n_m, pitch_clipped = self._joint(1, command.pitch_torque_n_m, pitch_rad, pitch_rate_rad_s)
        if not (math.isfinite(heave_a) and math.isfinite(pitch_a)):
            self.latch(FaultCode.NONFINITE_OUTPUT)
            return 0.0, 0.0, 0.0, 0.0
        if heave_clipped or pitch_clipped:
            self.saturation_count += 1
        return heave_a, pitch_a, heave_n_m, pitch_n_m

    def _joint(self, joint: int, torque_n_m: float, position: float, rate_rad_s: float) -> tuple[float, float, bool]:
        """(current A, joint torque N m, clipped?) for one motor; a NaN position gives a NaN current, which
        the caller catches."""
        limits = self.limits
        torque_limit = limits.torque_limits_n_m[joint]
        clipped = abs(torque_n_m) > torque_limit
        torque_n_m = min(max(torque_n_m, -torque_limit), torque_limit)
        lower, upper = limits.hard_limits_rad[joint]
        if position > upper or position < lower:   # recovering: only back toward the range, bounded
            recovery = RECOVERY_TORQUE_FRACTION * torque_limit
            torque_n_m = min(max(torque_n_m, -recovery), 0.0) if position > upper else \
                min(max(torque_n_m, 0.0), recovery)
        else:
            deceleration, latency = limits.braking_decelerations_rad_s2[joint], limits.latency_s
            # the filtered rate lags the link by its acceleration times the filter's time constant: add it back
            acceleration = (rate_rad_s - self._last_rates[joint]) / latency if latency > 0.0 else 0.0
            self._last_rates[joint] = rate_rad_s
            rate_rad_s += acceleration * limits.rate_lag_s
            # once braking, brake until stopped: switching back to the command at the bound would drive the
            # link on for a period each time and creep past the bound
            braking = self.braking[joint]
            if braking > 0 and rate_rad_s <= 0.0 or braking < 0 and rate_rad_s >= 0.0:
                braking = 0
            drive = limits.drive_accelerations_rad_s2[joint]
            if braking == 0 and rate_rad_s > braking_speed_limit(upper - position, deceleration, latency, drive):
                braking = 1
            elif braking == 0 and -rate_rad_s > braking_speed_limit(position - lower, deceleration, latency, drive):
                braking = -1
            self.braking[joint] = braking
            if braking:
                torque_n_m = -braking * torque_limit
                self.braking_count += 1
            else:
                torque_n_m *= soft_limit_scale(position, torque_n_m, lower, upper,
                                               limits.soft_limit_margins_rad[joint])
        gain = limits.torque_gains_n_m_per_a[joint]
        current_a = torque_n_m / gain
        current_limit = limits.current_limits_a[joint]
        if abs(current_a) > current_limit:
            clipped = True
            current_a = min(max(current_a, -current_limit), current_limit)
        return current_a, current_a * gain, clipped
