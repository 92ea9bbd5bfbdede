"""The mf624 backend against emulations: EmulatedComedi for comedilib, a file-backed counter BAR for uio_mf624.

The backend maps the emulated register file exactly as it maps /dev/uioN (UIO map 2 at offset 2 pages, BADR2
an in-page offset into it from the emulated sysfs), so the offset arithmetic is exercised, not bypassed.
"""
from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swim_hw_bridge.backends import mf624_registers as registers
from swim_hw_bridge.backends.mf624 import Mf624Device
from swim_hw_bridge.device import DeviceError
from swim_hw_bridge.testing.mf624_emulation import EmulatedComedi, EmulatedCounterRegisters

GAIN_A_PER_V = 0.2
AO_SUBDEVICE, DO_SUBDEVICE = 1, 3  # mf6x4's layout, found by type by the backend


@pytest.fixture
def counters(tmp_path):
    return EmulatedCounterRegisters(tmp_path)


@pytest.fixture
def comedi():
    return EmulatedComedi()


@pytest.fixture
def device(counters, comedi):
    device = Mf624Device({**counters.config, "heave_amplifier_gain_a_per_v": GAIN_A_PER_V,
                          "pitch_amplifier_gain_a_per_v": GAIN_A_PER_V}, comedi_module=comedi)
    device.open()
    yield device
    device.close()


def volts_written(comedi: EmulatedComedi) -> tuple[float, float]:
    return comedi.ao_volts(0), comedi.ao_volts(1)


def test_open_leaves_zero_volts_enable_low_and_quadrature_counting(counters, comedi):
    counters.write_register(registers.IRC_CONTROL_OFFSET, 0x7F7F7F7F)  # whatever an earlier program left
    device = Mf624Device(counters.config, comedi_module=comedi)
    device.open()
    assert comedi.analog_writes[-2:] == [(AO_SUBDEVICE, 0, 0, comedi.AREF_GROUND, 8192),
                                         (AO_SUBDEVICE, 1, 0, comedi.AREF_GROUND, 8192)]  # 0 V, 14-bit offset binary
    assert volts_written(comedi) == pytest.approx((0.0, 0.0), abs=20 / 0x3FFF)
    assert comedi.digital_writes == [(DO_SUBDEVICE, 0, 0)]
    assert counters.read_register(registers.IRC_CONTROL_OFFSET) == registers.IRCCTRL_QUADRATURE_COUNTING
    device.close()
    assert not comedi.open_handles


def test_counters_come_from_each_channels_register(counters, device):
    for irc_input, count in enumerate((11, 22_222, 3_333_333, 444_444_444)):
        counters.set_irc(irc_input, count)
    sample = device.read_counters()
    assert sample.counts == (11, 22_222, 3_333_333, 444_444_444)  # hub, rail, heave, pitch = IRC0..IRC3
    counters.set_irc(2, 7)
    second = device.read_counters()
    assert second.counts == (11, 22_222, 7, 444_444_444)
    assert second.sequence == sample.sequence + 1 and second.monotonic_s >= sample.monotonic_s


def test_32_bit_wrap_values_pass_through_raw(counters, device):
    counters.set_irc(0, -1)  # the hardware's signed count -1 is the register 0xFFFFFFFF
    counters.set_irc(1, 2**31)
    counters.set_irc(2, 2**32 - 2)
    counters.set_irc(3, 0)
    assert device.read_counters().counts == (2**32 - 1, 2**31, 2**32 - 2, 0)


def test_encoder_to_irc_input_wiring_is_configurable(counters, comedi):
    device = Mf624Device({**counters.config, "encoder_irc_inputs": [3, 2, 1, 0]}, comedi_module=comedi)
    device.open()
    for irc_input in range(4):
        counters.set_irc(irc_input, 100 + irc_input)
    assert device.read_counters().counts == (103, 102, 101, 100)
    device.close()


def test_a_plain_file_maps_from_offset_zero_like_a_pci_resource_file(tmp_path, comedi):
    bar = tmp_path / "resource4"  # /sys/bus/pci/devices/<bdf>/resource4: BAR4 at offset 0, file size = BAR size
    registers_bytes = bytearray(registers.COUNTER_BAR_MIN_BYTES)
    registers_bytes[0x70:0x74] = (123456).to_bytes(4, "little")
    registers_bytes[0x7C:0x80] = (2**32 - 5).to_bytes(4, "little")
    bar.write_bytes(bytes(registers_bytes))
    device = Mf624Device({"irc_device_path": str(bar)}, comedi_module=comedi)
    device.open()
    assert device.read_counters().counts == (123456, 0, 0, 2**32 - 5)
    device.close()


def test_currents_become_volts_through_the_amplifier_gain(comedi, device):
    device.write_currents(0.5, -0.3)  # 0.5 A / 0.2 A/V = 2.5 V; -1.5 V
    assert device.last_volts == pytest.approx((2.5, -1.5))
    heave_raw = comedi.ao_raw[0]
    assert heave_raw == int((2.5 + 10) / 20 * 0x3FFF + 0.5)  # comedilib's comedi_from_phys
    assert volts_written(comedi) == pytest.approx((2.5, -1.5), abs=20 / 0x3FFF)
    assert device.clipped_writes == 0


def test_currents_beyond_the_dac_range_are_clipped(comedi, device):
    device.write_currents(5.0, -100.0)  # 25 V and -500 V
    assert device.last_volts == (10.0, -10.0)
    assert (comedi.ao_raw[0], comedi.ao_raw[1]) == (0x3FFF, 0)
    assert device.clipped_writes == 1


@settings(max_examples=200, deadline=None)
@given(st.floats(-1e6, 1e6), st.floats(-1e6, 1e6))
def test_no_current_command_reaches_beyond_the_dac_range(heave_a, pitch_a):
    comedi = EmulatedComedi()
    device = Mf624Device({"write_irc_control_on_open": False}, comedi_module=comedi)
    device._open_comedi()  # the analog side only: this property needs no counter mapping
    device.write_currents(heave_a, pitch_a)
    for volts, current in zip(volts_written(comedi), (heave_a, pitch_a)):
        assert -10.0 - 1e-9 <= volts <= 10.0 + 1e-9
        assert volts == pytest.approx(max(-10.0, min(10.0, current / 0.2)), abs=20 / 0x3FFF)


def test_non_finite_current_writes_zero_volts_and_raises(comedi, device):
    device.write_currents(1.0, 1.0)
    with pytest.raises(DeviceError, match="non-finite"):
        device.write_currents(float("nan"), 0.1)
    assert device.last_volts == (0.0, 0.0)


def test_enable_line_toggles_once_per_call_while_enabled(comedi, device):
    device.toggle_enable()  # not enabled: the line stays low
    assert comedi.do_bits[0] == 0 and len(comedi.digital_writes) == 1
    device.enable()
    assert comedi.do_bits[0] == 1
    levels = []
    for _ in range(6):
        device.toggle_enable()
        levels.append(comedi.do_bits[0])
    assert levels == [0, 1, 0, 1, 0, 1]


def test_disable_writes_zero_volts_then_stops_toggling(comedi, device):
    device.enable()
    device.write_currents(0.4, 0.4)
    device.toggle_enable()
    writes_before = len(comedi.digital_writes)
    events_before = len(comedi.events)
    device.disable()
    # zero volts first, then the enable line low
    assert comedi.events[events_before:] == [("ao", 0, 8192), ("ao", 1, 8192), ("do", 0, 0)]
    assert volts_written(comedi) == pytest.approx((0.0, 0.0), abs=20 / 0x3FFF)
    for _ in range(5):
        device.toggle_enable()
    assert len(comedi.digital_writes) == writes_before + 1 and comedi.do_bits[0] == 0


def test_a_dio_subdevice_is_configured_as_output_for_the_enable_line(counters, comedi):
    comedi.subdevices[3].type = comedi.COMEDI_SUBD_DIO  # a card whose digital lines are bidirectional
    device = Mf624Device(counters.config, comedi_module=comedi)
    device.open()
    assert comedi.dio_directions == {(3, 0): comedi.COMEDI_OUTPUT}
    device.enable()
    assert comedi.do_bits[0] == 1
    device.close()


def test_close_is_idempotent_and_zeroes_outputs(comedi, device):
    device.enable()
    device.write_currents(1.0, -1.0)
    device.close()
    device.close()
    assert volts_written(comedi) == pytest.approx((0.0, 0.0), abs=20 / 0x3FFF)
    assert comedi.do_bits[0] == 0 and not comedi.open_handles
    with pytest.raises(DeviceError, match="not mapped"):
        device.read_counters()
    with pytest.raises(DeviceError, match="not open"):
        device.write_currents(0.0, 0.0)


def test_failed_comedi_write_is_a_device_error_and_disable_still_drops_enable(comedi, device):
    device.enable()
    comedi.fail_writes = True
    with pytest.raises(DeviceError, match="comedi_data_write to AO 0 failed: Input/output error"):
        device.write_currents(0.1, 0.1)
    device.disable()  # never raises; records why
    assert "failed" in device.last_error


def test_open_failures_are_device_errors_with_a_clear_message(tmp_path, counters, comedi):
    comedi.fail_open = True
    with pytest.raises(DeviceError, match="cannot open /dev/comedi0: No such device. Is the mf6x4 driver loaded"):
        Mf624Device(counters.config, comedi_module=comedi).open()
    comedi.fail_open = False
    with pytest.raises(DeviceError, match="cannot open the counter mapping .*uio3.*uio_mf624 loaded"):
        Mf624Device({"irc_device_path": str(tmp_path / "uio3")}, comedi_module=comedi).open()
    small = tmp_path / "resource2"
    small.write_bytes(bytes(0x40))
    with pytest.raises(DeviceError, match="64 bytes, the IRC registers need 128"):
        Mf624Device({"irc_device_path": str(small)}, comedi_module=comedi).open()
    with pytest.raises(DeviceError, match="narrower than dac_range_v"):
        Mf624Device({**counters.config, "dac_range_v": 12.0}, comedi_module=comedi).open()
    with pytest.raises(DeviceError, match="amplifier gains"):
        Mf624Device({"heave_amplifier_gain_a_per_v": 0.0}, comedi_module=comedi)
    assert not comedi.open_handles  # every failed open released what it had opened


def test_missing_comedilib_is_a_device_error_naming_the_package(counters, monkeypatch):
    import sys
    monkeypatch.setitem(sys.modules, "comedi", None)  # makes `import comedi` raise ImportError
    with pytest.raises(DeviceError, match="python3-comedilib"):
        Mf624Device(counters.config).open()


def test_bridge_config_values_reach_the_backend(counters, comedi):
    """make_device passes the bridge's whole device_config: the backend takes its keys and ignores the rest."""
    device = Mf624Device({**counters.config, "heave_amplifier_gain_a_per_v": 0.5, "velocity_cutoff_hz": 30.0,
                          "comedi_module": comedi})
    device.open()
    device.write_currents(1.0, 0.2)
    assert device.last_volts == (2.0, 1.0)
    device.close()
