"""The emulated rig: encoder quantization and wrap, torque from current, and its charge-pump enable line."""
import math
import time

import numpy as np
import pytest

from swim_hw_bridge.backends import UnknownBackend, make_device
from swim_hw_bridge.backends.emulated import EmulatedDevice
from swim_hw_bridge.device import DeviceError


@pytest.fixture()
def device(config):
    device = make_device("emulated", {**config.device_config("emulated"), "charge_pump_timeout_s": 0.03})
    device.open()
    yield device
    device.close()


def test_registry_names_the_backends(config):
    assert isinstance(make_device("emulated", config.device_config("emulated")), EmulatedDevice)
    with pytest.raises(UnknownBackend, match="choose one of"):
        make_device("ethercat", {})


def test_counts_are_floor_quantized_and_wrap(config):
    device = EmulatedDevice({**config.device_config("emulated"), "counter_bits": 12,
                             "initial_counts": (4090, 0, 0, 0)})
    assert device.counts() == (4090, 0, 0, 0)   # before open(): at the home pose
    device.open()
    per_rad = config.counts_per_unit
    device.plant.reset(np.array(config.home_positions) + np.array([10.5 / per_rad[0], 2.5 / per_rad[1],
                                                                   -0.5 / per_rad[2], -3.2 / per_rad[3]]), np.zeros(4))
    assert device.counts() == ((4090 + 10) % 4096, 2, 4095, 4092)   # floor: -0.5 -> -1, -3.2 -> -4


def test_enable_line_must_keep_toggling(device):
    assert not device.amplifiers_enabled()
    device.enable()
    assert not device.amplifiers_enabled()   # enable alone is not enough: no edge yet
    device.toggle_enable()
    device.write_currents(0.5, -0.3)
    assert device.amplifiers_enabled() and device.motor_currents_a() == (0.5, -0.3)
    for _ in range(5):   # toggling every 10 ms keeps the charge pump up
        time.sleep(0.01)
        device.toggle_enable()
        assert device.amplifiers_enabled()
    time.sleep(0.045)   # toggling stops (a hung or dead bridge): off after the 30 ms timeout
    assert not device.amplifiers_enabled()
    assert device.motor_currents_a() == (0.0, 0.0)
    device.toggle_enable()
    device.disable()
    assert not device.amplifiers_enabled() and device.commanded_currents_a == (0.0, 0.0)


def test_current_moves_the_joint_only_while_enabled(device):
    device.enable()
    device.write_currents(0.0, 0.3)
    device.read_counters()
    time.sleep(0.02)   # enable never toggled: the amplifiers are off and the pitch stays at rest
    sample = device.read_counters()
    assert sample.counts[3] == 0
    for _ in range(10):
        device.toggle_enable()
        time.sleep(0.005)
        sample = device.read_counters()
    assert device.plant.qdot[3] > 0.0 and sample.counts[3] > 0   # positive current: positive pitch torque


def test_sequence_and_fault_injection(device):
    first, second = device.read_counters(), device.read_counters()
    assert second.sequence == first.sequence + 1 and second.monotonic_s >= first.monotonic_s
    device.repeat_samples = True
    assert device.read_counters() is second
    device.fail_reads = True
    with pytest.raises(DeviceError):
        device.read_counters()


def test_reads_before_open_fail(config):
    with pytest.raises(DeviceError):
        EmulatedDevice(config.device_config("emulated")).read_counters()


def test_free_vehicle_moves_alpha_by_shape_change(device):
    """Sanity of the coupling: driving the heave joint rocks the hub (momentum conservation)."""
    device.enable()
    alpha = []
    for k in range(40):
        device.toggle_enable()
        device.write_currents(0.6 * math.copysign(1.0, math.sin(k / 3.0)), 0.0)
        time.sleep(0.004)
        device.read_counters()
        alpha.append(device.q[0])
    assert np.ptp(alpha) > 0.0


def test_write_log_keeps_the_last_writes_with_their_times(config):
    device = EmulatedDevice({**config.device_config("emulated"), "write_log_size": 3})
    device.open()
    before = time.monotonic()
    for k in range(5):
        device.write_currents(0.1 * k, -0.1 * k)
    assert device.write_count == 5
    rows = sorted(device.write_log.tolist())
    assert [r[1] for r in rows] == pytest.approx([0.2, 0.3, 0.4])
    assert all(before <= r[0] <= time.monotonic() for r in rows)
