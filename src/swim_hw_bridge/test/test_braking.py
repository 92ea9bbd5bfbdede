"""Limits that stop the link in time, on the emulated rig stepped on a virtual clock (deterministic): full torque
held from anywhere in the range never passes a hard limit; a link past its limit at a reset is brought back."""
import dataclasses
import math

import numpy as np
import pytest

from conftest import PERIOD_S, READ_FAILURE_LIMIT, STALE_READ_LIMIT, WATCHDOG_PERIODS
from swim_hw_bridge.backends.emulated import EmulatedDevice
from swim_hw_bridge.braking import joint_accelerations
from swim_hw_bridge.conversions import Conversions
from swim_hw_bridge.device import CounterSample
from swim_hw_bridge.io_loop import IoLoop
from swim_hw_bridge.safety import (RECOVERY_TORQUE_FRACTION, Command, FaultCode, SafetyLayer, SafetyLimits,
                                   braking_speed_limit)
from swim_model import load_rig

#: periods of full torque per case: 2 s, longer than any link takes to cross its range at full torque
HELD_PERIODS = 250
JOINTS = {"heave": 2, "pitch": 3}


class VirtualClockDevice(EmulatedDevice):
    """The emulated rig advanced to a virtual clock the test sets, amplifiers on while enabled."""

    def __init__(self, config):
        super().__init__(config)
        self.now_s = 0.0

    def open(self):
        super().open()
        self._time_s = 0.0

    def amplifiers_enabled(self, now_s=None):
        return self.enable_requested

    def read_counters(self):
        self._advance(self.now_s)
        self._sequence += 1
        return CounterSample(self.counts(), self.now_s, self._sequence)


@pytest.fixture(scope="module")
def braking(config, limits):
    """The shipped limits with the braking bound the bridge computes from the model at configure."""
    hard = ((config.heave_lower_hard_limit_rad, config.heave_upper_hard_limit_rad),
            (config.pitch_lower_hard_limit_rad, config.pitch_upper_hard_limit_rad))
    decelerations, accelerations = joint_accelerations(load_rig(), hard, config.torque_limits_n_m)
    return SafetyLimits.from_config(config, PERIOD_S, WATCHDOG_PERIODS, STALE_READ_LIMIT, READ_FAILURE_LIMIT,
                                    decelerations, accelerations)


def rig_at(config, limits, joint, position_rad):
    """A loop on the emulated rig standing at rest with the joint at position_rad: the rig is switched on there
    (incremental encoders count from where it stands, so the bridge's home is that position)."""
    placed = dataclasses.replace(config, **{f"{joint}_home_position_rad": position_rad})
    device = VirtualClockDevice(config.device_config("emulated"))
    device.open()
    device.enable()
    device.home = np.array(placed.home_positions)
    device.q, device.qdot = device.home.copy(), np.zeros(4)
    return IoLoop(device, Conversions(placed), SafetyLayer(limits), PERIOD_S, 3), device


def hold(loop, device, torques_n_m, periods):
    """Step the loop on the virtual clock with the command refreshed every period; the positions read."""
    positions = []
    for _ in range(periods):
        device.now_s += PERIOD_S
        loop.set_command(Command(torques_n_m[0], torques_n_m[1], device.now_s - 0.5 * PERIOD_S))
        loop.run_period(device.now_s)
        positions.append(loop.snapshot().positions)
    return np.array(positions)


def test_the_speed_bound_is_the_stopping_distance_with_one_period_of_latency():
    for distance, deceleration in [(0.01, 10.0), (0.3, 13.9), (1.0, 172.0)]:
        v = braking_speed_limit(distance, deceleration, PERIOD_S)
        assert v * PERIOD_S + v * v / (2 * deceleration) == pytest.approx(distance, rel=1e-12)
    assert braking_speed_limit(0.0, 10.0, PERIOD_S) == 0.0 and braking_speed_limit(-1.0, 10.0, PERIOD_S) == 0.0
    assert math.isinf(braking_speed_limit(0.1, math.inf, PERIOD_S))


def test_decelerations_bound_what_full_torque_gives_everywhere_in_the_range(config, braking):
    """a = fraction tau / max M_jj is at most tau (M^-1)_jj (the acceleration torque alone gives) anywhere, and
    the drive bound A = max tau (M^-1)_jj at least that."""
    decelerations, accelerations = braking.braking_decelerations_rad_s2, braking.drive_accelerations_rad_s2
    from swim_model import VehicleModel
    model = VehicleModel(load_rig(), constrained=False)
    rng = np.random.default_rng(4)
    for _ in range(50):
        q = [0.0, rng.uniform(0.43, 0.48), rng.uniform(config.heave_lower_hard_limit_rad,
                                                       config.heave_upper_hard_limit_rad),
             rng.uniform(config.pitch_lower_hard_limit_rad, config.pitch_upper_hard_limit_rad)]
        inverse = np.linalg.inv(model.mass_matrix(q))
        for j, (deceleration, torque) in enumerate(zip(decelerations, config.torque_limits_n_m)):
            assert deceleration <= torque * inverse[2 + j, 2 + j] <= accelerations[j] * (1 + 1e-9)


@pytest.mark.parametrize("joint", ["heave", "pitch"])
@pytest.mark.parametrize("start_fraction", [-0.9, -0.3, 0.0, 0.5, 0.9])
@pytest.mark.parametrize("direction", [1.0, -1.0])
def test_full_torque_held_never_passes_a_hard_limit(config, braking, joint, start_fraction, direction):
    lower, upper = ((config.heave_lower_hard_limit_rad, config.heave_upper_hard_limit_rad) if joint == "heave"
                    else (config.pitch_lower_hard_limit_rad, config.pitch_upper_hard_limit_rad))
    loop, device = rig_at(config, braking, joint, start_fraction * upper)
    full = [0.0, 0.0]
    full[JOINTS[joint] - 2] = direction * 50.0        # far past the motor's limit: clipped to it
    positions = hold(loop, device, full, HELD_PERIODS)[:, JOINTS[joint]]
    assert lower <= positions.min() and positions.max() <= upper
    assert not loop.safety.faults
    reached = positions.max() if direction > 0 else -positions.min()
    assert reached > 0.8 * upper                      # it did go toward the limit: the limiter is not a wall


def test_without_the_braking_bound_full_torque_passes_the_heave_limit(config, limits):
    loop, device = rig_at(config, limits, "heave", 0.0)   # limits: no braking deceleration given
    positions = hold(loop, device, [50.0, 0.0], HELD_PERIODS)[:, 2]
    assert positions.max() > config.heave_upper_hard_limit_rad and loop.safety.faults & FaultCode.HARD_LIMIT


def test_a_link_past_its_limit_is_brought_back_after_a_reset(config, braking):
    upper = config.heave_upper_hard_limit_rad
    loop, device = rig_at(config, braking, "heave", upper + 0.1)
    hold(loop, device, [0.0, 0.0], 2)
    assert loop.safety.faults & FaultCode.HARD_LIMIT                          # latched, torque zero
    loop.reset(device.now_s)
    outward = hold(loop, device, [1.0, 0.0], 5)
    assert loop.snapshot().torques_n_m[0] == 0.0 and not loop.safety.faults   # outward: refused, no re-latch
    assert outward[-1, 2] > upper
    back = hold(loop, device, [-50.0, 0.0], 125)[:, 2]                       # 1 s of full inward command
    inside = np.flatnonzero(back <= upper)
    assert inside.size and not loop.safety.faults
    torques_outside = loop.safety.limits.torque_limits_n_m[0] * RECOVERY_TORQUE_FRACTION
    assert torques_outside < loop.safety.limits.torque_limits_n_m[0]
    hold(loop, device, [0.5, 0.0], 3)                                         # inside again: commands as usual
    assert loop.snapshot().torques_n_m[0] == pytest.approx(0.5) and not loop.safety.faults
