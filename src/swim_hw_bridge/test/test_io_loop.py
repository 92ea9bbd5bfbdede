"""The I/O loop with the emulated rig: absolute deadlines and isolated overruns on a virtual clock (exact, whatever
the host's load), the period in real time, overruns and their latch, device faults, the safety rules end to end,
counters across the wrap, and the amplifier-enable line."""
import itertools
import math
import time

import numpy as np
import pytest
from conftest import PERIOD_S, READ_FAILURE_LIMIT, STALE_READ_LIMIT

from swim_hw_bridge import io_loop
from swim_hw_bridge.backends.emulated import EmulatedDevice
from swim_hw_bridge.io_loop import IoLoop
from swim_hw_bridge.safety import Command, FaultCode, SafetyLayer, WatchdogState
from swim_model.plant import PlantSettings

OVERRUN_LIMIT = 3


class RecordingDevice(EmulatedDevice):
    """The emulated rig, noting when each read starts."""

    def __init__(self, config):
        super().__init__(config)
        self.read_starts = []

    def read_counters(self):
        self.read_starts.append(time.monotonic())
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


class VirtualClock:
    """Stands in for the I/O loop's clock (its module's ``time``): sleep advances the time by what was asked plus
    the next of the given wake-up latenesses, s, and keeps them, so each period's start is known exactly."""

    def __init__(self, latenesses_s):
        self.now_s = 1000.0
        self._latenesses_s = iter(latenesses_s)
        self.applied_s = [0.0]     # the first period starts at once

    def monotonic(self):
        return self.now_s

    def sleep(self, seconds):
        lateness_s = next(self._latenesses_s, 0.0)
        self.now_s += seconds + lateness_s
        self.applied_s.append(lateness_s)


class VirtualTimeDevice(EmulatedDevice):
    """The emulated rig, noting each read's start on the virtual clock and taking the next of works_s (cycled)
    of it."""

    def __init__(self, config, clock, works_s):
        super().__init__(config)
        self.clock, self.works_s, self.read_starts = clock, itertools.cycle(works_s), []

    def read_counters(self):
        self.read_starts.append(self.clock.now_s)
        self.clock.now_s += next(self.works_s)
        return super().read_counters()


class RelativeSleepLoop(IoLoop):
    """The mistake the deadlines prevent: sleeping one period after the work."""

    def _run(self):
        while not self._stop.is_set():
            self.run_period(io_loop.time.monotonic())
            io_loop.time.sleep(self.sample_period_s)


def starts_off_the_grid_s(monkeypatch, config, conversions, limits, loop_class, latenesses_s, works_s=(0.45e-3,)):
    """Run loop_class on the virtual clock for len(latenesses_s) periods, the reads taking works_s in turn; return,
    for each period, how far its start less its wake-up lateness lies from the grid t_0 + k h (s; 0 for absolute
    deadlines), the grid index of each start, and the loop."""
    clock = VirtualClock(latenesses_s)
    monkeypatch.setattr(io_loop, "time", clock)
    device = VirtualTimeDevice({**config.device_config("emulated"), "charge_pump_timeout_s": 0.03}, clock, works_s)
    device.open()
    device.enable()
    loop = loop_class(device, conversions, SafetyLayer(limits), PERIOD_S, OVERRUN_LIMIT)
    loop.start()
    while len(device.read_starts) < len(latenesses_s) and loop.running:
        time.sleep(0.01)
    assert loop.stop()
    count = len(latenesses_s)
    on_time_s = np.array(device.read_starts[:count]) - np.array(clock.applied_s[:count])
    periods = (on_time_s - on_time_s[0]) / PERIOD_S
    return np.abs(periods - np.round(periods)) * PERIOD_S, np.round(periods), loop


def test_periods_follow_absolute_deadlines(monkeypatch, config, conversions, limits):
    """Each period starts at t_0 + k h plus its own wake-up lateness, however late the wake-ups before it (on the
    virtual clock, so exactly): nothing accumulates. A wake-up later than the period skips to the next grid point
    (no burst to catch up). A relative sleep drifts by its work time every period."""
    rng = np.random.default_rng(3)
    latenesses_s = rng.uniform(0.0, 0.6 * PERIOD_S, 200)
    latenesses_s[[50, 120]] = 1.7 * PERIOD_S, 2.4 * PERIOD_S    # two wake-ups whole periods late
    off_grid_s, grid_index, loop = starts_off_the_grid_s(monkeypatch, config, conversions, limits, IoLoop,
                                                         latenesses_s)
    assert np.max(off_grid_s) < 1e-9
    steps = np.diff(grid_index)
    assert steps.min() == 1 and sorted(steps[steps > 1]) == [2, 3]
    assert loop.overruns == 2 and not loop.safety.faults & FaultCode.OVERRUN
    drift_s, _, _ = starts_off_the_grid_s(monkeypatch, config, conversions, limits, RelativeSleepLoop,
                                          np.zeros(40))
    assert drift_s[1] == pytest.approx(0.45e-3, rel=1e-6) and np.max(drift_s) > 0.1 * PERIOD_S


def test_the_loop_keeps_its_period_in_real_time(config, conversions, limits):
    """On the host's clock: the usual interval is the period and the reported rate is the loop's (a 20-period
    average, which one period skipped on a loaded host moves by 5 %)."""
    loop, device = make_loop(config, conversions, limits)
    run_for(loop, 0.8)
    starts = np.array(device.read_starts)
    assert len(starts) >= 90
    assert np.median(np.diff(starts)) == pytest.approx(PERIOD_S, abs=0.5e-3)
    snapshot = loop.snapshot()
    assert snapshot.loop_rate_hz == pytest.approx(1 / PERIOD_S, rel=0.15)
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


def test_isolated_overruns_are_counted_without_a_latch(monkeypatch, config, conversions, limits):
    """Every other read takes 1.25 periods (on the virtual clock): each of those periods overruns and the next
    starts on the grid with time to spare, so overruns are never consecutive and nothing latches."""
    off_grid_s, grid_index, loop = starts_off_the_grid_s(monkeypatch, config, conversions, limits, IoLoop,
                                                         np.zeros(40), works_s=(1.25 * PERIOD_S, 0.45e-3))
    assert np.max(off_grid_s) < 1e-9 and set(np.diff(grid_index)) == {1.0, 2.0}
    assert loop.overruns >= 20 and loop.consecutive_overruns <= 1 and not loop.safety.faults & FaultCode.OVERRUN


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
        device.plant.reset(home + np.array([0.6, 0.02, 0.1, -0.9]) * math.sin(math.pi * s), np.zeros(4))
        snapshot = step(loop, sleep_s=0.02)
        assert np.allclose(snapshot.positions, device.q, atol=1.01 * max(1 / np.array(config.counts_per_unit)))
    assert not snapshot.faults and snapshot.jump_channels == 0


def test_an_impossible_encoder_jump_faults(config, conversions, limits):
    loop, device = make_loop(config, conversions, limits)
    step(loop)
    device.plant.reset(device.q + np.array([0.0, 0.0, 0.0, 1.0]), np.zeros(4))   # 1 rad of pitch in one period:
    # 125 rad/s
    snapshot = step(loop)
    assert snapshot.faults == FaultCode.ENCODER_JUMP and snapshot.jump_channels == 0b1000


def test_soft_limit_then_hard_limit_through_the_loop(config, conversions, limits):
    # the link is placed past the limit: the emulated rig without its stops
    loop, device = make_loop(config, conversions, limits, plant=PlantSettings(hard_stops=False))
    upper, margin = config.rig.hard_limits_rad[0][1], config.rig.limits.heave.soft_margin_rad
    home = np.array(config.home_positions)
    heave_currents = []
    for phi in np.arange(0.0, upper + 0.05, 0.02):   # 0.02 rad per 8 ms: well below the jump bound
        device.plant.reset(home + np.array([0.0, 0.0, phi, 0.0]), np.zeros(4))
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
        self.plant.reset(self.home + self.rate * (now_s - self.start_s), self.rate)


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


class SlowWriteDevice(VirtualTimeDevice):
    """The virtual-clock rig whose writes take write_s each, and whose reads take works_s once each in turn, then
    10 us (the loop runs on until stopped)."""

    write_s = 0.0

    def __init__(self, config, clock, works_s):
        super().__init__(config, clock, works_s)
        self.works_s = itertools.chain(works_s, itertools.repeat(1e-5))

    def write_currents(self, heave_a, pitch_a):
        self.clock.now_s += self.write_s
        super().write_currents(heave_a, pitch_a)


def run_on_virtual_clock(monkeypatch, config, conversions, limits, latenesses_s, works_s, write_s=0.0):
    """The loop on the virtual clock for len(latenesses_s) periods (reads taking works_s in turn, writes write_s);
    the loop, stopped."""
    clock = VirtualClock(latenesses_s)
    monkeypatch.setattr(io_loop, "time", clock)
    device = SlowWriteDevice({**config.device_config("emulated"), "charge_pump_timeout_s": 0.03}, clock, works_s)
    device.write_s = write_s
    device.open()
    device.enable()
    loop = IoLoop(device, conversions, SafetyLayer(limits), PERIOD_S, 10_000)
    loop.start()
    while len(device.read_starts) < len(latenesses_s) and loop.running:
        time.sleep(0.01)
    assert loop.stop()
    return loop


@pytest.mark.parametrize("case", ["late_wakeup", "slow_read", "slow_write"])
def test_each_overrun_is_given_its_cause_and_the_worst_its_lateness(monkeypatch, config, conversions, limits,
                                                                    case):
    """On the virtual clock: 40 periods, of which three overrun by a known amount, each through one part of the
    period. The worst lateness is the largest of the three exactly, the cause is that part's, every overrun is
    counted under it, and the wake-up histogram holds the late wake-ups."""
    from swim_hw_bridge.timing import OverrunCause
    work_s = 0.45e-3
    excess_s = np.zeros(40)
    excess_s[[10, 20, 30]] = 0.3 * PERIOD_S, 0.7 * PERIOD_S, 0.5 * PERIOD_S   # past the next deadline
    # a wake-up h - work late ends its period on the next deadline: excess_s later ends it excess_s past it
    late = np.where(excess_s > 0, excess_s + PERIOD_S - work_s, 0.0) if case == "late_wakeup" else np.zeros(40)
    reads = list(PERIOD_S + excess_s if case == "slow_read" else np.full(40, work_s))
    write_s = 0.0
    if case == "slow_write":   # every write slow, three of them past the period: the clock moves in the write
        write_s = 0.9 * PERIOD_S
        reads = list(np.where(excess_s > 0, 0.1 * PERIOD_S + excess_s, 1e-5))
    loop = run_on_virtual_clock(monkeypatch, config, conversions, limits, late, reads, write_s)
    cause = {"late_wakeup": OverrunCause.LATE_WAKEUP, "slow_read": OverrunCause.SLOW_READ,
             "slow_write": OverrunCause.SLOW_WRITE}[case]
    snapshot = loop.snapshot()
    assert loop.overruns == 3 and loop.worst_lateness_cause is cause
    assert loop._overruns_by_cause[cause - 1] == loop.overruns
    assert loop.worst_lateness_s == pytest.approx(0.7 * PERIOD_S, abs=1e-9)
    if case == "late_wakeup":
        assert loop.wake_lateness.largest_s == pytest.approx(max(late), abs=1e-9)
        assert snapshot.worst_lateness_cause is cause   # the snapshot carries it (the period after it)


def test_overrun_causes_are_the_largest_part():
    from swim_hw_bridge.timing import OverrunCause, overrun_cause
    assert overrun_cause(5e-3, 1e-3, 1e-3, 4e-3) is OverrunCause.LATE_WAKEUP
    assert overrun_cause(1e-3, 7e-3, 1e-3, 9e-3) is OverrunCause.SLOW_READ
    assert overrun_cause(1e-3, 1e-3, 7e-3, 9e-3) is OverrunCause.SLOW_WRITE
    assert overrun_cause(1e-3, 1e-3, 1e-3, 9e-3) is OverrunCause.SLOW_WORK


def test_the_histograms_percentiles_are_exact_to_one_bin():
    from swim_hw_bridge.timing import HISTOGRAM_BIN_S, HISTOGRAM_RANGE_S, LatencyHistogram
    rng = np.random.default_rng(7)
    samples = rng.gamma(2.0, 0.4e-3, 20_000)
    histogram = LatencyHistogram()
    for value in samples:
        histogram.add(float(value))
    histogram.add(float("nan"))
    histogram.add(-1.0)   # neither is a duration: not counted
    assert histogram.count == len(samples)
    for percent in (50, 90, 99):
        exact = np.percentile(samples, percent)
        assert exact <= histogram.percentile_s(percent) <= exact + HISTOGRAM_BIN_S + 1e-12
    histogram.add(2 * HISTOGRAM_RANGE_S)   # past the range: the last bin, and the largest is kept
    assert histogram.percentile_s(100) == pytest.approx(2 * HISTOGRAM_RANGE_S)
    assert math.isnan(LatencyHistogram().percentile_s(50))
