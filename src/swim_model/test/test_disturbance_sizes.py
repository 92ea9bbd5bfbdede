"""The default disturbances are sized from physics: each size recomputed here from the rig file's raw entries and
the published coefficients it names (not through swim_model.disturbances' own arithmetic), and the paper's sizes
kept as the ideal-flow pipeline runs them."""
import dataclasses
import math

import pytest
import yaml

from swim_model.disturbances import Disturbances
from swim_model.rig import default_rig_path

G_M_S2 = 9.80665            # standard gravity
DEEP_GROOVE_MU = 0.0015     # SKF Rolling bearings catalogue, "Friction", Table 1: open deep groove ball bearings
LINEAR_BUSHING_MU = 0.0025  # Schaeffler linear ball bearings KN..-B, KS, KB (unsealed): 0.001-0.0025, upper end
HUB_BORE_M, HUB_SPACING_M, HUB_ARM_KG = 0.010, 0.05, 1.0   # the hub's assumed 6200 pair, its spacing, the rails


@pytest.fixture(scope="module")
def rig():
    """The shipped rig file's values, read raw (every entry used here is in SI units in the file)."""
    entries = yaml.safe_load(default_rig_path().read_text())["parameters"]
    names = ("platform_mass", "heave_link_mass", "foil_assembly_mass", "constrained_lane_radius", "foil_chord",
             "foil_max_thickness", "foil_span", "water_density")
    for name in names:
        assert entries[name]["unit"] in ("kg", "m", "kg/m^3"), name
    return {name: float(entries[name]["value"]) for name in names}


def platform_weight_n(rig) -> float:
    return G_M_S2 * (rig["platform_mass"] + rig["heave_link_mass"] + rig["foil_assembly_mass"])


def test_hub_friction_is_the_deep_groove_coefficient_times_the_bearing_loads_times_the_bore_radius(rig):
    weight = platform_weight_n(rig)
    thrust = G_M_S2 * HUB_ARM_KG + weight
    couple = 2.0 * weight * rig["constrained_lane_radius"] / HUB_SPACING_M   # radial, one on each bearing
    expected = DEEP_GROOVE_MU * (thrust + couple) * HUB_BORE_M / 2.0
    sizes = Disturbances()
    assert sizes.hub_coulomb_n_m == pytest.approx(expected, rel=1e-12)
    assert 2.0e-3 < sizes.hub_coulomb_n_m < 3.0e-3   # 1.77 kg at 0.43 m on a 10 mm bore pair 5 cm apart: 2.4 mN m
    assert sizes.hub_static_n_m == pytest.approx(2.0 * expected, rel=1e-12)   # start-up: up to twice running
    assert sizes.hub_viscous_n_m_s == 0.0


def test_rail_friction_is_the_linear_bushing_coefficient_times_the_platforms_weight(rig):
    sizes = Disturbances()
    expected = LINEAR_BUSHING_MU * platform_weight_n(rig)
    assert sizes.rail_coulomb_n == pytest.approx(expected, rel=1e-12)
    assert sizes.rail_coulomb_n == pytest.approx(0.0434, abs=1e-4)   # 2.5e-3 x 1.77 kg x g
    assert sizes.rail_static_n == sizes.rail_coulomb_n   # static and dynamic differ marginally (NB)
    assert sizes.rail_viscous_n_s_m == 0.0


def test_foil_drag_is_a_flat_plates_broadside_and_a_laminar_sections_profile_drag(rig):
    sizes = Disturbances()
    assert sizes.foil_normal_drag_coefficient == 1.2   # Hoerner, rectangular plate of aspect ratio ~5
    reynolds = 0.2 * rig["foil_chord"] / 1.0e-6        # 0.2 m/s, 6 cm chord, water at 20 C
    thickness_ratio = rig["foil_max_thickness"] / rig["foil_chord"]
    blasius_both_sides = 2.0 * 1.328 / math.sqrt(reynolds)
    form_factor = 1.0 + 2.0 * thickness_ratio + 60.0 * thickness_ratio ** 4
    assert reynolds == pytest.approx(1.2e4)
    assert sizes.foil_axial_drag_coefficient == pytest.approx(blasius_both_sides * form_factor, rel=1e-12)
    assert sizes.foil_axial_drag_coefficient == pytest.approx(0.0312, abs=1e-4)


def test_tilt_is_a_tenth_of_a_degree():
    assert Disturbances().tilt_rad == pytest.approx(math.pi / 1800.0, rel=1e-15)


def test_wave_force_is_the_lift_slope_times_the_waves_angle_of_attack(rig):
    omega = 2.0 * math.pi * 1.0                          # 1 Hz ripples
    k = omega ** 2 / G_M_S2                              # deep water
    orbital_m_s = 0.001 * omega * math.exp(-k * rig["foil_span"] / 2.0)   # 1 mm amplitude, at mid-span
    angle_rad = orbital_m_s / 0.2
    expected = 0.5 * rig["water_density"] * rig["foil_chord"] * rig["foil_span"] * 2.0 * math.pi * angle_rad
    assert Disturbances().wave_force_per_speed2_n_s2_m2 == pytest.approx(expected, rel=1e-12)
    assert 0.01 < angle_rad < 0.03   # a degree or so of angle of attack from 3.4 mm/s of orbital velocity


def test_the_physical_and_the_papers_sizes_are_valid():
    Disturbances().validate()
    Disturbances.paper().validate()
    with pytest.raises(ValueError, match="static friction"):
        dataclasses.replace(Disturbances(), hub_static_n_m=0.5 * Disturbances().hub_coulomb_n_m).validate()


def test_the_papers_sizes_are_the_small_ones_the_ideal_flow_plans_survive():
    paper, physical = Disturbances.paper(), Disturbances()
    assert paper.foil_normal_drag_coefficient == 0.05 and paper.tilt_rad == 0.0002
    # the water and the level are never gentler in the physical sizes than in the paper's
    for name in ("foil_normal_drag_coefficient", "foil_axial_drag_coefficient", "tilt_rad",
                 "wave_force_per_speed2_n_s2_m2", "platform_drag_area_m2"):
        assert getattr(physical, name) >= getattr(paper, name), name
    assert paper != physical and paper == Disturbances.paper()
