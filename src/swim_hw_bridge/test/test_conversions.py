"""Conversions against closed forms by hand (paper Sec. 2 resolutions, x4 quadrature) and the config checks."""
import math

import pytest
import yaml

from swim_hw_bridge.conversions import BridgeConfigError, config_from_mapping, default_config_path, load_bridge_config
from swim_model import load_rig
from swim_model.rig import default_rig_path, rig_from_mapping

INCH_M = 0.0254
OZ_IN_N_M = 0.0283495231 * 9.80665 * 0.0254


def test_one_revolution_of_each_encoder_in_counts(conversions):
    # 4 counts per line: hub 4*6144 per rev; heave 4*512 per motor rev, 43 motor revs per joint rev; pitch 25
    alpha, _, phi, theta = conversions.counts_to_positions((4 * 6144, 0, 4 * 512 * 43, 4 * 512 * 25))
    assert alpha == pytest.approx(2 * math.pi, rel=1e-12)
    assert phi == pytest.approx(2 * math.pi, rel=1e-12)
    assert theta == pytest.approx(2 * math.pi, rel=1e-12)


def test_rail_counts_to_metres_from_the_home_lane(conversions):
    # 1024 lines per inch, 4 counts per line: 4096 counts = 1 inch; R counted from the 0.43 m lane
    _, radius, _, _ = conversions.counts_to_positions((0, 4096, 0, 0))
    assert radius == pytest.approx(0.43 + INCH_M, rel=1e-12)
    _, radius, _, _ = conversions.counts_to_positions((0, -1, 0, 0))
    assert radius == pytest.approx(0.43 - INCH_M / 4096, rel=1e-12)


def test_single_count_resolution(conversions):
    alpha, _, phi, theta = conversions.counts_to_positions((1, 0, 1, 1))
    assert alpha == pytest.approx(2 * math.pi / 24576, rel=1e-12)
    assert phi == pytest.approx(2 * math.pi / 88064, rel=1e-12)
    assert theta == pytest.approx(2 * math.pi / 51200, rel=1e-12)


def test_torque_to_current_through_gear_and_torque_constant(conversions):
    heave_a, pitch_a = conversions.torques_to_currents(1.0, -0.5)
    assert heave_a == pytest.approx(1.0 / (43 * 0.0335), rel=1e-12)
    assert pitch_a == pytest.approx(-0.5 / (25 * 0.030), rel=1e-12)
    assert conversions.currents_to_torques(heave_a, pitch_a) == pytest.approx((1.0, -0.5), rel=1e-12)
    assert conversions.currents_to_volts(0.2, -1.0) == pytest.approx((1.0, -5.0), rel=1e-12)


def test_limits_are_the_papers_torque_limits_and_the_currents_reach_them(config):
    assert config.rig.torque_limits_n_m == pytest.approx((177 * OZ_IN_N_M, 74.2 * OZ_IN_N_M), rel=1e-9)
    # the current limits leave the paper's torque limits reachable (the torque limit binds first)
    for torque, gain, current in zip(config.rig.torque_limits_n_m, config.motor_torque_gains_n_m_per_a,
                                     config.current_limits_a):
        assert torque / gain <= current


def shipped_document():
    return yaml.safe_load(default_config_path().read_text())


def test_every_entry_is_sourced_or_assumed():
    for key, entry in shipped_document()["parameters"].items():
        assert ("source" in entry) != ("assumed" in entry), key


@pytest.mark.parametrize("edit, message", [
    (lambda p: p.pop("heave_torque_constant"), "missing"),
    (lambda p: p.update(bogus={"value": 1, "unit": "1", "assumed": "x"}), "unknown"),
    (lambda p: p["heave_torque_constant"].update(unit="A"), "unit"),
    (lambda p: p["quadrature_counts_per_line"].pop("assumed"), "exactly one"),
    (lambda p: p["pitch_current_limit"].update(value=float("nan")), "finite"),
    (lambda p: p["pitch_current_limit"].update(value=-1.0), "positive"),
    (lambda p: p["heave_home_position"].update(value=90, unit="deg"), "home_position"),
    (lambda p: p["heave_current_limit"].update(value=5.0), "full scale"),
])
def test_bad_files_are_refused_with_a_reason(edit, message):
    document = shipped_document()
    edit(document["parameters"])
    with pytest.raises(BridgeConfigError, match=message):
        config_from_mapping(document, "edited.yaml")


def test_device_config_round_trips_and_carries_backend_options(config):
    from swim_hw_bridge.conversions import BridgeConfig
    values = config.device_config("emulated")
    assert values["counter_bits"] == 32
    assert BridgeConfig.from_dict(values) == config


def test_the_bridge_file_holds_no_fact_of_the_rig_file():
    """Every fact in one file: no key of the rig file's parameters or limits appears in the bridge file."""
    rig_document = yaml.safe_load(default_rig_path().read_text())
    rig_keys = set(rig_document["parameters"]) | set(rig_document["limits"])
    assert not rig_keys & set(shipped_document()["parameters"])


def test_encoder_lines_gear_ratios_and_limits_are_the_rigs_the_bridge_is_loaded_for():
    """Another rig's encoder lines, gear ratios, stops and torque limits reach the conversions and limits."""
    document = yaml.safe_load(default_rig_path().read_text())
    parameters, limits = document["parameters"], document["limits"]
    parameters["heave_encoder_lines"]["value"] = 1024
    parameters["pitch_gear_ratio"]["value"] = 50
    limits["pitch_hard_stop"]["value"] = 90
    limits["heave_torque_limit"].update(value=1.0, unit="N*m")
    rig = rig_from_mapping(document, "other_rig.yaml")
    config = load_bridge_config(None, rig)
    shipped = load_bridge_config(None)
    assert config.counts_per_unit[2] == pytest.approx(2 * shipped.counts_per_unit[2], rel=1e-12)
    assert config.counts_per_unit[3] == pytest.approx(2 * shipped.counts_per_unit[3], rel=1e-12)
    assert config.motor_torque_gains_n_m_per_a[1] == pytest.approx(2 * shipped.motor_torque_gains_n_m_per_a[1])
    assert config.rig.hard_limits_rad[1] == pytest.approx((-math.pi / 2, math.pi / 2), rel=1e-12)
    assert config.rig.torque_limits_n_m[0] == 1.0
    assert load_rig().hard_limits_rad[1] == pytest.approx((-math.radians(80), math.radians(80)), rel=1e-12)
