"""The bridge's safety rules, pure and ROS-free: what current may reach the motors this period.

Per period, in this order (SafetyLayer.output):
1. any latched fault (FaultCode, including the e-stop): zero current;
2. no command newer than the last reset or activation (WatchdogState.WAITING): zero;
3. command watchdog on the monotonic clock: the latest command older than watchdog_timeout_s
   (N sample periods): zero (WatchdogState.EXPIRED); a newer command resumes;
4. a non-finite torque: zero and the NONFINITE_OUTPUT fault;
5. torque saturation |tau| <= tau_max (Sec. 2 limits), counted;
6. soft limits: with p the joint position, [lo, hi] its hard limits and m the margin, torque pushing outward
   is scaled by s = clamp((hi - p) / m, 0, 1) near the upper limit (tau > 0) and by
   s = clamp((p - lo) / m, 0, 1) near the lower one (tau < 0); torque back inward is never scaled;
7. current i = tau / (N Kt), saturated |i| <= i_max, counted.
Past a hard limit (p < lo or p > hi) the HARD_LIMIT fault latches (check_positions).
Faults latch until reset(); after a reset the output stays zero until a command received after it.

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

    @classmethod
    def from_config(cls, config: BridgeConfig, sample_period_s: float, watchdog_periods: int,
                    stale_read_limit: int, read_failure_limit: int) -> "SafetyLimits":
        return cls(
            torque_limits_n_m=config.torque_limits_n_m, current_limits_a=config.current_limits_a,
            torque_gains_n_m_per_a=config.motor_torque_gains_n_m_per_a,
            hard_limits_rad=((config.heave_lower_hard_limit_rad, config.heave_upper_hard_limit_rad),
                             (config.pitch_lower_hard_limit_rad, config.pitch_upper_hard_limit_rad)),
            soft_limit_margins_rad=(config.heave_soft_limit_margin_rad, config.pitch_soft_limit_margin_rad),
            watchdog_timeout_s=watchdog_periods * sample_period_s, stale_read_limit=stale_read_limit,
            read_failure_limit=read_failure_limit)


class SafetyLayer:
    """State of the rules across periods: latched faults, watchdog, read health, saturation count."""

    def __init__(self, limits: SafetyLimits) -> None:
        self.limits = limits
        self.faults = FaultCode.NONE
        self.watchdog = WatchdogState.WAITING
        self.saturation_count = 0         # periods in which a torque or a current was clipped
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
        """Clear every latched fault; output resumes only with a command received after now_s."""
        self.faults = FaultCode.NONE
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
        """Latch HARD_LIMIT when a joint is past (or cannot be placed within) its hard limits."""
        for position, (lower, upper) in zip((heave_rad, pitch_rad), self.limits.hard_limits_rad):
            if not lower <= position <= upper:   # also true for NaN
                self.latch(FaultCode.HARD_LIMIT)

    # --- the output --------------------------------------------------------------------------------------
    def output(self, now_s: float, command: Command | None, heave_rad: float,
               pitch_rad: float) -> tuple[float, float, float, float]:
        """(heave_a, pitch_a, heave_n_m, pitch_n_m): currents to write and the joint torques they make."""
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
        heave_a, heave_n_m, heave_clipped = self._joint(0, command.heave_torque_n_m, heave_rad)
        pitch_a, pitch_n_m, pitch_clipped = self._joint(1, command.pitch_torque_n_m, pitch_rad)
        if not (math.isfinite(heave_a) and math.isfinite(pitch_a)):
            self.latch(FaultCode.NONFINITE_OUTPUT)
            return 0.0, 0.0, 0.0, 0.0
        if heave_clipped or pitch_clipped:
            self.saturation_count += 1
        return heave_a, pitch_a, heave_n_m, pitch_n_m

    def _joint(self, joint: int, torque_n_m: float, position: float) -> tuple[float, float, bool]:
        """(current A, joint torque N m, clipped?) for one motor; a NaN position gives a NaN current, which
        the caller catches."""
        limits = self.limits
        torque_limit = limits.torque_limits_n_m[joint]
        clipped = abs(torque_n_m) > torque_limit
        torque_n_m = min(max(torque_n_m, -torque_limit), torque_limit)
        lower, upper = limits.hard_limits_rad[joint]
        torque_n_m *= soft_limit_scale(position, torque_n_m, lower, upper, limits.soft_limit_margins_rad[joint])
        gain = limits.torque_gains_n_m_per_a[joint]
        current_a = torque_n_m / gain
        current_limit = limits.current_limits_a[joint]
        if abs(current_a) > current_limit:
            clipped = True
            current_a = min(max(current_a, -current_limit), current_limit)
        return current_a, current_a * gain, clipped
