"""Rig file: the shipped values, their sources, unit conversion and the loader's refusals."""
import copy
import math

import pytest
import yaml

from swim_model import load_rig
from swim_model.errors import RigConfigError
from swim_model.rig import default_rig_path, rig_from_mapping


@pytest.fixture()
def document():
    return yaml.safe_load(default_rig_path().read_text())


def test_paper_values_in_si():
    rig = load_rig()
    assert rig.foil_chord_m == 0.06 and rig.foil_max_thickness_m == 0.008 and rig.foil_span_m == 0.3
    assert rig.heave_link_length_m == 0.15
    assert rig.sample_period_s == pytest.approx(0.008)
    # 177 oz-in: 177 * 0.028349523125 kg * 9.80665 m/s^2 * 0.0254 m
    assert rig.heave_torque_limit_n_m == pytest.approx(177 * 0.028349523125 * 9.80665 * 0.0254, rel=1e-12)
    assert rig.pitch_torque_limit_n_m == pytest.approx(74.2 * 0.028349523125 * 9.80665 * 0.0254, rel=1e-12)
    assert rig.rail_encoder_lines_per_m == pytest.approx(1024 / 0.0254)
    assert rig.heave_rotor_inertia_kg_m2 == pytest.approx(120e-7)


def test_shipped_limits_in_si():
    limits = load_rig().limits
    degree = math.pi / 180
    assert (limits.heave.planning_range_rad, limits.heave.soft_margin_rad, limits.heave.hard_stop_rad) == \
        pytest.approx((50 * degree, 5 * degree, 60 * degree), rel=1e-12)
    assert (limits.pitch.planning_range_rad, limits.pitch.soft_margin_rad, limits.pitch.hard_stop_rad) == \
        pytest.approx((70 * degree, 5 * degree, 80 * degree), rel=1e-12)
    assert load_rig().hard_limits_rad == ((-limits.heave.hard_stop_rad, limits.heave.hard_stop_rad),
                                          (-limits.pitch.hard_stop_rad, limits.pitch.hard_stop_rad))
    assert limits.max_speeds == (3.0, 1.0, 30.0, 45.0)
    assert limits.torque_limits_n_m == load_rig().torque_limits_n_m


def test_the_digest_covers_the_torque_limits_and_not_the_other_limits(document):
    """A library records the rig digest: the torque limits it was solved against change it, the stops do not."""
    shipped = load_rig().digest()
    stops = copy.deepcopy(document)
    stops["limits"]["heave_hard_stop"]["value"] = 70
    assert rig_from_mapping(stops).digest() == shipped
    torque = copy.deepcopy(document)
    torque["limits"]["heave_torque_limit"]["value"] = 100
    assert rig_from_mapping(torque).digest() != shipped


def test_every_entry_is_sourced_or_assumed(document):
    for key, entry in {**document["parameters"], **document["limits"]}.items():
        assert ("source" in entry) != ("assumed" in entry), key
        assert str(entry.get("source", entry.get("assumed"))).strip(), key


def test_digest_tracks_values():
    rig = load_rig()
    assert rig.digest() == load_rig().digest()
    assert rig.replace(platform_mass_kg=2.0).digest() != rig.digest()


@pytest.mark.parametrize("mutate, message", [
    (lambda d: d["parameters"].pop("platform_mass"), "missing parameters: platform_mass"),
    (lambda d: d["parameters"].__setitem__("platfrom_mass", d["parameters"]["platform_mass"]), "unknown parameters"),
    (lambda d: d["parameters"]["foil_chord"].__setitem__("unit", "kg"), "not a length"),
    (lambda d: d["parameters"]["heave_link_mass"].__setitem__("value", -0.1), "must not be negative"),
    (lambda d: d["parameters"]["platform_mass"].__setitem__("value", 0.0), "must be positive"),
    (lambda d: d["parameters"]["foil_span"].__setitem__("value", "thirty"), "finite number"),
    (lambda d: d["parameters"]["foil_span"].__setitem__("value", math.nan), "finite number"),
    (lambda d: d["parameters"]["foil_span"].pop("source"), "exactly one of"),
    (lambda d: d["parameters"]["foil_max_thickness"].__setitem__("value", 0.07), "smaller than foil_chord"),
    (lambda d: d["parameters"]["lane_2_radius"].__setitem__("value", 0.9), "inside the tank"),
    (lambda d: d.__setitem__("format_version", 2), "format_version"),
    (lambda d: d.pop("limits"), "'limits' must be a mapping"),
    (lambda d: d["limits"].pop("rail_max_speed"), "missing limits: rail_max_speed"),
    (lambda d: d["limits"]["pitch_hard_stop"].__setitem__("unit", "m"), "not a angle"),
    (lambda d: d["limits"]["hub_max_speed"].__setitem__("value", 0.0), "must be positive"),
    (lambda d: d["limits"]["heave_soft_margin"].__setitem__("value", 11), "heave soft margin .* must fit in the gap"),
    (lambda d: d["limits"]["pitch_planning_range"].__setitem__("value", 80),
     "pitch soft margin .* must fit in the gap"),
])
def test_bad_files_are_refused_with_a_clear_message(document, mutate, message):
    bad = copy.deepcopy(document)
    mutate(bad)
    with pytest.raises(RigConfigError, match=message):
        rig_from_mapping(bad, origin="test.yaml")


def test_other_units_convert(document):
    changed = copy.deepcopy(document)
    changed["parameters"]["foil_chord"] = {"value": 6, "unit": "cm", "source": "test"}
    assert rig_from_mapping(changed).foil_chord_m == pytest.approx(0.06)


def test_unreadable_and_invalid_files(tmp_path):
    with pytest.raises(RigConfigError, match="cannot read"):
        load_rig(tmp_path / "absent.yaml")
    broken = tmp_path / "broken.yaml"
    broken.write_text("parameters: [unclosed\n")
    with pytest.raises(RigConfigError, match="not valid YAML"):
        load_rig(broken)
