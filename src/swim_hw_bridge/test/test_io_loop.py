"""The I/O loop with the emulated rig: absolute deadlines, overruns and their latch, device faults, the safety
rules end to end, counters across the wrap, and the amplifier-enable line."""
import math
import time

import numpy as np
import pytest

from conftest import PERIOD_S, READ_FAILURE_LIMIT, STALE_READ_LIMIT
from swim_hw_bridge.backends.emulated import EmulatedDevice
from swim_hw_bridge.io_loop import IoLoop
from swim_hw_bridge.safety import Command, FaultCode, SafetyLayer, WatchdogState

OVERRUN_LIMIT = 3


class RecordingDevice(EmulatedDevice):
    """The emulated rig, noting when each read starts; optionally slow on every other read."""

    def __init__(self, config):
        super().__init__(config)
        self.read_starts = []
        self.slow_every_other_s = 0.0

    def read_counters(self):
        self.read_starts.append(time.monotonic())
        if self.slow_every_other_s and len(self.read_starts) % 2:
            time.sleep(self.slow_every_other_s)
        return super().read_counters()


def make_loop(config, conversions, limits, **emulated):
    device = RecordingDevice({**config.device_config("emulated"), "charge_pump_timeout_s": 0.03, **emulated})
    device.open()
    device.enable()
    return IoLoop(device, conversions, SafetyLayer(limits), PERIOD_S, OVERRUN_LIMIT), device


def run_for(loop, seconds):
    loop.start()
    try:
        time.sleep(seconds)
    finally:
        assert loop.stop()


def test_periods_follow_absolute_deadlines(config, conversions, limits):
    loop, device = make_loop(config, conversions, limits)
    run_for(loop, 0.8)
    starts = np.array(device.read_starts)
    intervals = np.diff(starts)
    assert len(starts) >= 90
    # absolute deadlines: no drift, the average interval is the period (a relative sleep would add work time)
    assert (starts[-1] - starts[0]) / (len(starts) - 1) == pytest.approx(PERIOD_S, rel=0.01)
    assert np.median(intervals) == pytest.approx(PERIOD_S, abs=0.5e-3)
    snapshot = loop.snapshot()
    assert snapshot.loop_rate_hz == pytest.approx(1 / PERIOD_S, rel=0.05)
    assert not snapshot.faults & FaultCode.OVERRUN


def test_a_slow_device_overruns_every_period_and_latches(config, conversions, limits):
    loop, device = make_loop(config, conversions, limits)
    device.read_delay_s = 1.5 * PERIOD_S
    loop.set_command(Command(0.3, 0.0, time.monotonic() + 0.5))
    run_for(loop, 0.2)
    snapshot = loop.snapshot()
    assert snapshot.overruns >= OVERRUN_LIMIT and snapshot.faults & FaultCode.OVERRUN
    assert snapshot.currents_a == (0.0, 0.0) and not snapshot.enable_toggling
    # missed deadlines are skipped, not caught up in a burst: reads stay >= one delay apart
    assert np.min(np.diff(device.read_starts)) >= 1.5 * PERIOD_S - 1e-4
    time.sleep(0.05)
    assert not device.amplifiers_enabled()   # the enable line stopped: the charge pump dropped


def test_isolated_overruns_are_counted_without_a_latch(config, conversions, limits):
    loop, device = make_loop(config, conversions, limits)
    device.slow_every_other_s = 1.25 * PERIOD_S   # the next period still has 6 ms to spare
    run_for(loop, 0.3)
    snapshot = loop.snapshot()
    assert snapshot.overruns >= 5
    assert snapshot.consecutive_overruns <= 1 and not snapshot.faults & FaultCode.OVERRUN


def step(loop, periods=1, sleep_s=PERIOD_S):
    for _ in range(periods):
        time.sleep(sleep_s)
        loop.run_period(time.monotonic())
    return loop.snapshot()


def test_stale_reads_fault_and_zero(config, conversions, limits):
    loop, device = make_loop(config, conversions, limits)
    loop.enable_toggling = True
    loop.set_command(Command(0.3, 0.1, time.monotonic()))
    assert step(loop, 2).currents_a[0] > 0.0
    device.repeat_samples = True
    snapshot = step(loop, STALE_READ_LIMIT - 1)
    assert not snapshot.faults
    loop.set_command(Command(0.3, 0.1, time.monotonic()))
    snapshot = step(loop)
    assert snapshot.faults == FaultCode.STALE_READ and snapshot.currents_a == (0.0, 0.0)
    assert not snapshot.enable_toggling


def test_failing_reads_write_zero_then_fault(config, conversions, limits):
    loop, device = make_loop(config, conversions, limits)
    loop.set_command(Command(0.3, 0.1, time.monotonic()))
    step(loop)
    device.fail_reads = True
    snapshot = step(loop)
    assert snapshot.currents_a == (0.0, 0.0) and device.commanded_currents_a == (0.0, 0.0)
    assert not snapshot.faults
    snapshot = step(loop, READ_FAILURE_LIMIT - 1)
    assert snapshot.faults == FaultCode.READ_FAILED


def test_watchdog_estop_and_reset_through_the_loop(config, conversions, limits):
    loop, device = make_loop(config, conversions, limits)
    loop.enable_toggling = True
    loop.set_command(Command(0.2, 0.0, time.monotonic(), stamp_ns=42))
    snapshot = step(loop)
    assert snapshot.currents_a[0] > 0.0 and snapshot.command_stamp_ns == 42
    snapshot = step(loop, 6)   # no command for more than 5 periods
    assert snapshot.watchdog is WatchdogState.EXPIRED and snapshot.currents_a == (0.0, 0.0)
    loop.set_command(Command(0.2, 0.0, time.monotonic()))
    assert step(loop).currents_a[0] > 0.0
    loop.emergency_stop()
    loop.set_command(Command(0.2, 0.0, time.monotonic()))
    snapshot = step(loop)
    assert snapshot.faults == FaultCode.EMERGENCY_STOP and snapshot.currents_a == (0.0, 0.0)
    assert not snapshot.enable_toggling
    loop.reset(time.monotonic())
    snapshot = step(loop)   # the last command predates the reset
    assert not snapshot.faults and snapshot.watchdog is WatchdogState.WAITING and snapshot.currents_a == (0.0, 0.0)
    loop.set_command(Command(0.2, 0.0, time.monotonic()))
    assert step(loop).currents_a[0] > 0.0


def test_positions_follow_the_rig_across_the_counter_wrap(config, conversions, limits):
    loop, device = make_loop(config, conversions, limits, counter_bits=12, initial_counts=(4000, 100, 4090, 5))
    home = np.array(config.home_positions)
    path = np.linspace(0.0, 1.0, 40)
    for s in path:   # both directions: out and back, through several 4096-count wraps on alpha and theta
        device.q = home + np.array([0.6, 0.02, 0.1, -0.9]) * math.sin(math.pi * s)
        device.qdot = np.zeros(4)
        snapshot = step(loop, sleep_s=0.02)
        assert np.allclose(snapshot.positions, device.q, atol=1.01 * max(1 / np.array(config.counts_per_unit)))
    assert not snapshot.faults and snapshot.jump_channels == 0


def test_an_impossible_encoder_jump_faults(config, conversions, limits):
    loop, device = make_loop(config, conversions, limits)
    step(loop)
    device.q = device.q + np.array([0.0, 0.0, 0.0, 1.0])   # 1 rad of pitch in one period: 125 rad/s
    snapshot = step(loop)
    assert snapshot.faults == FaultCode.ENCODER_JUMP and snapshot.jump_channels == 0b1000


def test_soft_limit_then_hard_limit_through_the_loop(config, conversions, limits):
    loop, device = make_loop(config, conversions, limits, hard_stops=False)   # the link is placed past the limit
    upper, margin = config.heave_upper_hard_limit_rad, config.heave_soft_limit_margin_rad
    home = np.array(config.home_positions)
    heave_currents = []
    for phi in np.arange(0.0, upper + 0.05, 0.02):   # 0.02 rad per 8 ms: well below the jump bound
        device.q, device.qdot = home + np.array([0.0, 0.0, phi, 0.0]), np.zeros(4)
        loop.set_command(Command(0.5, 0.0, time.monotonic()))
        snapshot = step(loop)
        heave_currents.append((snapshot.positions[2], snapshot.currents_a[0]))
    full = 0.5 / (43 * 0.0335)
    for phi, current in heave_currents:
        if phi <= upper - margin:
            assert current == pytest.approx(full)
        elif phi <= upper:
            assert current == pytest.approx(full * (upper - phi) / margin, abs=1e-9)
    assert heave_currents[-1][0] > upper
    assert snapshot.faults == FaultCode.HARD_LIMIT and snapshot.currents_a == (0.0, 0.0)


class RampDevice(RecordingDevice):
    """Every joint moving at a constant rate: positions evaluated at each read's own instant."""

    rate = np.array([0.1, 0.01, 1.0, -2.0])

    def _advance(self, now_s):
        self.q = self.home + self.rate * (now_s - self.start_s)


def test_velocities_from_filtered_differences(config, conversions, limits):
    device = RampDevice(config.device_config("emulated"))
    device.open()
    device.start_s = time.monotonic()
    loop = IoLoop(device, conversions, SafetyLayer(limits), PERIOD_S, OVERRUN_LIMIT)
    snapshot = step(loop, 40)
    # the 30 Hz filter has settled after 40 periods; what is left is quantization: one count per period at most
    one_count_per_period = 1.0 / (np.array(config.counts_per_unit) * PERIOD_S)
    assert np.all(np.abs(np.array(snapshot.velocities) - RampDevice.rate) <= 1.1 * one_count_per_period)
    assert np.all(one_count_per_period < 0.4 * np.abs(RampDevice.rate))   # so the check has teeth


class MotionRecordingLayer(SafetyLayer):
    """The safety layer, keeping the Motion each period hands it."""

    def __init__(self, limits):
        super().__init__(limits)
        self.motions = []

    def output(self, now_s, command, heave_rad, pitch_rad, motion=None):
        self.motions.append(motion)
        return super().output(now_s, command, heave_rad, pitch_rad, motion)


def test_the_braking_rule_reads_the_plain_difference_quotient(config, conversions, limits):
    """The mean rates the safety layer gets are the difference quotient of the last two samples over their own
    interval: the ramp's rates within one count per interval from the first pair of samples on (no filter to
    settle), and the positions those of the sample."""
    device = RampDevice(config.device_config("emulated"))
    device.open()
    device.start_s = time.monotonic()
    safety = MotionRecordingLayer(limits)
    loop = IoLoop(device, conversions, safety, PERIOD_S, OVERRUN_LIMIT)
    for _ in range(3):
        snapshot = step(loop)
    first, last = safety.motions[0], safety.motions[-1]
    assert first.interval_s == 0.0 and first.mean_rates == (0.0, 0.0, 0.0, 0.0)   # one sample: no rate yet
    assert last.positions == snapshot.positions and last.interval_s > 0.0
    one_count = 1.0 / (np.array(config.counts_per_unit) * last.interval_s)
    assert np.all(np.abs(np.array(last.mean_rates) - RampDevice.rate) <= 1.01 * one_count)
