"""The I/O loop: one thread, absolute deadlines t_k = t_0 + k h (h = sample_period_s, time.monotonic()).

Each period: read the counters, unwrap and convert them (unwrap.py, conversions.py), estimate velocities by
filtered differences (swim_model.velocity_filter, published), apply the safety rules (safety.py) to the latest
command with the positions and the mean rates over the last sample interval (the plain difference quotient, no
filter lag: what the braking rule reads), write the currents, toggle the amplifier-enable line (while enabled
and no fault is latched), publish a snapshot. Then sleep until the next deadline. Nothing in the period logs,
blocks on ROS or builds more than a few small tuples.

A period whose work ends after the next deadline is an overrun: counted, the missed deadlines are skipped (the
grid t_0 + k h is kept), and overrun_limit overruns in a row latch FaultCode.OVERRUN. Each overrun is given its
cause (timing.py: a late wake-up, a slow read, a slow write or slow work) and the worst lateness, its cause and the
count of each cause are in every snapshot; the wake-up lateness of every period is counted in a histogram.

Real-time means (swim_ros.realtime, given as realtime and io_loop_priority): the thread sets itself to the
policy at io_loop_priority when it starts (the node sets the rest of the process a step below), and, with
collect_garbage_between_periods, the garbage collector is frozen and runs only at the end of a period, every
GC_INTERVAL_PERIODS periods (realtime.PeriodicCollector), in a period with GC_MIN_SLACK_S left: never inside one.
on_period, if given, is called by the thread after each period; it must not block (bridge_node triggers a guard
condition, so that the state is published right after the period that read it).

The ROS side talks to the loop through two lock-protected slots only: set_command() replaces the latest
timestamped command, snapshot() returns the latest Snapshot (immutable). E-stop and reset requests are flags
the loop takes at the start of its next period, so the SafetyLayer is only ever touched by the loop's thread.
A failed read writes zero current that period. Any unexpected exception in a period latches INTERNAL_ERROR
instead of ending the thread.
"""
from __future__ import annotations

import dataclasses
import math
import threading
import time
from typing import Callable, Optional

import numpy as np

from swim_hw_bridge.conversions import Conversions
from swim_hw_bridge.device import Device, DeviceError
from swim_hw_bridge.safety import Command, FaultCode, Motion, SafetyLayer, WatchdogState
from swim_hw_bridge.timing import LatencyHistogram, OverrunCause, overrun_cause
from swim_hw_bridge.unwrap import CounterUnwrapper
from swim_model.velocity_filter import VelocityEstimator
from swim_ros.realtime import (
    NO_REALTIME_MEANS,
    PeriodicCollector,
    RealtimeSettings,
    make_thread_realtime,
    thread_policy,
)

_RATE_SMOOTHING = 0.05   # weight of the newest interval in the loop-rate average (about 20 periods)
#: periods between two garbage collections at a period's end: 1 s at 8 ms; what a second of periods leaves
#: (a few hundred small objects) takes well under a millisecond to collect
GC_INTERVAL_PERIODS = 125
#: the slack a period must have left for a collection at its end, s: twenty times the longest collection measured
#: in a running bridge (0.1 ms, docs/realtime.md)
GC_MIN_SLACK_S = 2e-3


@dataclasses.dataclass(frozen=True)
class Snapshot:
    """The loop's state after one period.

    positions: (alpha rad, R m, phi rad, theta rad); velocities likewise per second;
    currents_a / torques_n_m: (heave, pitch) written to the device and the joint torques N Kt i they make;
    command_stamp_ns / command_received_s: the command those came from (0 / nan: none).
    """

    monotonic_s: float
    sequence: int
    positions: tuple[float, float, float, float]
    velocities: tuple[float, float, float, float]
    currents_a: tuple[float, float]
    torques_n_m: tuple[float, float]
    command_stamp_ns: int
    command_received_s: float
    faults: FaultCode
    watchdog: WatchdogState
    enable_toggling: bool
    periods: int
    overruns: int
    consecutive_overruns: int
    saturation_count: int
    loop_rate_hz: float
    jump_channels: int
    worst_lateness_s: float = 0.0   # the latest end of an overrun period past its deadline
    worst_lateness_cause: OverrunCause = OverrunCause.NONE
    overruns_by_cause: tuple[int, int, int, int] = (0, 0, 0, 0)   # late wake-up, slow read, slow write, slow work


class IoLoop:
    """Runs device I/O and the safety rules at a fixed period in its own thread."""

    def __init__(self, device: Device, conversions: Conversions, safety: SafetyLayer, sample_period_s: float,
                 overrun_limit: int, realtime: RealtimeSettings = NO_REALTIME_MEANS,
                 io_loop_priority: int = 80, on_period: Optional[Callable[[], None]] = None) -> None:
        if not (math.isfinite(sample_period_s) and sample_period_s > 0.0) or overrun_limit < 1:
            raise ValueError("sample_period_s must be positive and overrun_limit at least 1")
        self.device, self.conversions, self.safety = device, conversions, safety
        self.sample_period_s = sample_period_s
        self.overrun_limit = overrun_limit
        self.realtime, self.io_loop_priority, self.on_period = realtime, io_loop_priority, on_period
        #: what the thread runs with: ("fifo", 80) once started; and why it could not have its policy, if so
        self.thread_policy: tuple[str, int] = ("other", 0)
        self.policy_refused: Optional[str] = None
        self.collector: Optional[PeriodicCollector] = None
        self.wake_lateness = LatencyHistogram()   # every period's start past its place on the grid
        self.worst_lateness_s = 0.0
        self.worst_lateness_cause = OverrunCause.NONE
        self._overruns_by_cause = [0, 0, 0, 0]
        self._read_s = self._write_s = 0.0   # the last period's read and write, s
        self.unwrapper = CounterUnwrapper(device.counter_bits,
                                          [v * n for v, n in zip(conversions.config.rig.limits.max_speeds,
                                                                 conversions.config.counts_per_unit)])
        self.velocity = VelocityEstimator(conversions.config.velocity_cutoff_hz)
        self._lock = threading.Lock()
        self._command: Command | None = None
        self._snapshot: Snapshot | None = None
        self._estop_requested = False
        self._reset_requested_at_s: float | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.enable_toggling = False
        self.periods = 0
        self.overruns = 0
        self.consecutive_overruns = 0
        self._rate_interval_s = sample_period_s
        self._last_start_s = math.nan
        self._positions = conversions.home_positions
        self._velocities = (0.0, 0.0, 0.0, 0.0)
        self._mean_rates = (0.0, 0.0, 0.0, 0.0)   # (q_k - q_(k-1)) / (t_k - t_(k-1)) of the last two samples
        self._sample_interval_s = 0.0             # t_k - t_(k-1); 0 until two samples are in
        self._sample_time_s = math.nan
        self._sequence = -1
        self._jumps = 0

    # --- the ROS side's interface (any thread) ------------------------------------------------------------
    def set_command(self, command: Command) -> None:
        """Hand the loop the latest torque command."""
        with self._lock:
            self._command = command

    def snapshot(self) -> Snapshot | None:
        """The latest period's snapshot (None before the first)."""
        with self._lock:
            return self._snapshot

    def emergency_stop(self) -> None:
        """Latch the emergency stop at the loop's next period."""
        with self._lock:
            self._estop_requested = True

    def reset(self, now_s: float) -> None:
        """Clear latched faults (and the e-stop); torque resumes with a command received after now_s."""
        with self._lock:
            self._estop_requested = False
            self._reset_requested_at_s = now_s

    def start(self, enable_toggling: bool = True) -> None:
        """Start the thread; torque waits for a command received after now."""
        if self._thread is not None:
            raise RuntimeError("the I/O loop is already running")
        self.safety.arm(time.monotonic())
        self.enable_toggling = enable_toggling
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name="swim_hw_bridge_io", daemon=True)
        self._thread.start()

    def stop(self, timeout_s: float = 1.0) -> bool:
        """Stop the thread (within a period); True when it ended. The caller then zeroes and disables."""
        self._stop.set()
        thread, self._thread = self._thread, None
        if thread is None:
            return True
        thread.join(timeout_s)
        return not thread.is_alive()

    @property
    def running(self) -> bool:
        """Whether the loop's thread is alive."""
        return self._thread is not None and self._thread.is_alive()

    # --- the loop's thread ---------------------------------------------------------------------------------
    def _run(self) -> None:
        self.policy_refused = make_thread_realtime(self.realtime, self.io_loop_priority)
        self.thread_policy = thread_policy()
        if self.realtime.collect_garbage_between_periods:
            self.collector = PeriodicCollector(GC_INTERVAL_PERIODS)
        try:
            self._periods()
        finally:
            if self.collector is not None:
                self.collector.stop()

    def _periods(self) -> None:
        period_s = self.sample_period_s
        clock = time.monotonic
        deadline_s = clock()   # the next period's place on the grid
        while not self._stop.is_set():
            start_s = clock()
            wake_lateness_s = start_s - deadline_s
            self.wake_lateness.add(wake_lateness_s)
            self.run_period(start_s)
            deadline_s += period_s
            end_s = clock()
            if end_s > deadline_s:
                self._overrun(end_s - deadline_s, wake_lateness_s, end_s - start_s)
                deadline_s += math.ceil((end_s - deadline_s) / period_s) * period_s   # stay on the grid
            else:
                self.consecutive_overruns = 0
            if self.on_period is not None:
                try:
                    self.on_period()
                except Exception:   # noqa: BLE001 - a notification (the node may be going down), never the end
                    pass
            if self.collector is not None and deadline_s - clock() > GC_MIN_SLACK_S:
                self.collector.after_period()   # a period without that slack leaves the collection to the next
            remaining_s = deadline_s - clock()
            if remaining_s > 0.0:
                time.sleep(remaining_s)

    def _overrun(self, lateness_s: float, wake_lateness_s: float, work_s: float) -> None:
        self.overruns += 1
        self.consecutive_overruns += 1
        cause = overrun_cause(max(wake_lateness_s, 0.0), self._read_s, self._write_s, work_s)
        self._overruns_by_cause[cause - 1] += 1
        if lateness_s > self.worst_lateness_s:
            self.worst_lateness_s, self.worst_lateness_cause = lateness_s, cause
        if self.consecutive_overruns >= self.overrun_limit:
            self.safety.latch(FaultCode.OVERRUN)

    def run_period(self, now_s: float) -> None:
        """One period's work (public for tests that step the loop by hand)."""
        try:
            self._period(now_s)
        except Exception:   # noqa: BLE001 - the loop must outlive any bug: zero, latch, carry on
            self.safety.latch(FaultCode.INTERNAL_ERROR)
            try:
                self.device.write_currents(0.0, 0.0)
            except Exception:   # noqa: BLE001
                pass

    def _period(self, now_s: float) -> None:
        safety = self.safety
        with self._lock:
            command = self._command
            estop, reset_at_s = self._estop_requested, self._reset_requested_at_s
            self._reset_requested_at_s = None
        if reset_at_s is not None:
            safety.reset(reset_at_s)
        if estop:
            safety.emergency_stop()
        self._rate(now_s)
        currents = torques = (0.0, 0.0)
        sample_time_s = now_s
        clock = time.monotonic
        read_start_s = clock()
        try:
            sample = self.device.read_counters()
        except DeviceError:
            sample = None
        self._read_s = clock() - read_start_s
        safety.check_read(None if sample is None else sample.sequence)
        if sample is not None:
            sample_time_s = sample.monotonic_s
            self._take_sample(sample.counts, sample.monotonic_s, sample.sequence)
            phi, theta = self._positions[2], self._positions[3]
            safety.check_positions(phi, theta)
            motion = Motion(self._positions, self._mean_rates, self._sample_interval_s)
            heave_a, pitch_a, heave_n_m, pitch_n_m = safety.output(now_s, command, phi, theta, motion)
            currents, torques = (heave_a, pitch_a), (heave_n_m, pitch_n_m)
        toggling = self.enable_toggling and not safety.faults
        write_start_s = clock()
        try:
            self.device.write_currents(currents[0], currents[1])
            if toggling:
                self.device.toggle_enable()
        except DeviceError:
            safety.latch(FaultCode.DEVICE_FAILED)
            currents = torques = (0.0, 0.0)
            toggling = False
        self._write_s = clock() - write_start_s
        self.periods += 1
        by_cause = self._overruns_by_cause
        snapshot = Snapshot(
            sample_time_s, self._sequence, self._positions, self._velocities, currents, torques,
            command.stamp_ns if command is not None else 0,
            command.received_monotonic_s if command is not None else math.nan,
            safety.faults, safety.watchdog, toggling, self.periods, self.overruns, self.consecutive_overruns,
            safety.saturation_count, 1.0 / self._rate_interval_s, self._jumps, self.worst_lateness_s,
            self.worst_lateness_cause, (by_cause[0], by_cause[1], by_cause[2], by_cause[3]))
        with self._lock:
            self._snapshot = snapshot

    def _take_sample(self, counts: tuple[int, ...], time_s: float, sequence: int) -> None:
        if sequence == self._sequence:
            return   # a repeated sample: nothing new to unwrap or differentiate
        self._sequence = sequence
        self._jumps = self.unwrapper.update(counts, time_s)
        if self._jumps:
            self.safety.latch(FaultCode.ENCODER_JUMP)
        previous, self._positions = self._positions, self.conversions.counts_to_positions(self.unwrapper.unwrapped)
        interval_s, self._sample_time_s = time_s - self._sample_time_s, time_s
        if interval_s > 0.0:   # false for the first sample (nan)
            p, q = self._positions, previous
            self._mean_rates = ((p[0] - q[0]) / interval_s, (p[1] - q[1]) / interval_s,
                                (p[2] - q[2]) / interval_s, (p[3] - q[3]) / interval_s)
            self._sample_interval_s = interval_s
        rates = self.velocity.update(time_s, np.array(self._positions))
        self._velocities = (float(rates[0]), float(rates[1]), float(rates[2]), float(rates[3]))

    def _rate(self, now_s: float) -> None:
        interval_s = now_s - self._last_start_s
        self._last_start_s = now_s
        if interval_s > 0.0:   # false for the first period (nan)
            self._rate_interval_s += _RATE_SMOOTHING * (interval_s - self._rate_interval_s)
