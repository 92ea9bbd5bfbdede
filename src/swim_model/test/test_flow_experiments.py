"""The towed-foil experiment (swim_model.flow.oscillating_foil): the reduced model against the vortex wake at small
angles of attack, and both against a towing tank.

Tank data (data/anderson1998_oscillating_foil.csv, copied with its source header): Anderson, Streitlien, Barrett &
Triantafyllou, J. Fluid Mech. 360 (1998): NACA 0012, chord 0.10 m, span 0.60 m, pivot at c/3, Re 40 000,
h0/c = 0.75, nominal angle of attack alpha0 = 15 deg, pitch leading heave by 90 deg. The NACA 0012 is modelled by
the Joukowski section of the same chord and 12 % thickness; the water is fresh water at 20 C (998.2 kg/m^3,
1.0e-6 m^2/s), so the towing speed is Re nu / c = 0.4 m/s; the profile drag is the laminar flat plate's friction on
both sides times Hoerner's thickness factor at Re 40 000 (flow.laminar_profile_drag_coefficient: 0.0166), for both
models. No coefficient is fitted to this series.

Known disagreements, marked xfail (strict, so a change that removes one is seen): at the two highest Strouhal
numbers (0.46, 0.50) the reduced model's thrust is 21 % and 31 % above the tank's; the vortex wake's thrust is
26 % above at 0.50, and its efficiency is 0.09-0.15 below the tank's from St = 0.31 on (it needs 10-25 % more power
than the reduced model there: an inviscid wake that separates only at the trailing edge).
"""
import csv
import functools
import math
from pathlib import Path

import numpy as np
import pytest

from swim_model import JoukowskiFoil, load_rig
from swim_model.flow import FlowParameters, laminar_profile_drag_coefficient, oscillating_foil
from swim_model.towed_foil import TowedFoilKinematics

DATA = Path(__file__).parent / "data" / "anderson1998_oscillating_foil.csv"
RHO = 998.2                      # fresh water at 20 C, as rig.yaml
NU = 1.0e-6                      # its kinematic viscosity, m^2/s
CHORD_M, SPAN_M, THICKNESS_RATIO = 0.10, 0.60, 0.12
REYNOLDS = 40_000.0
SPEED_M_S = REYNOLDS * NU / CHORD_M
HEAVE_M = 0.75 * CHORD_M
ALPHA0_RAD = math.radians(15.0)
TANK_FOIL = JoukowskiFoil(CHORD_M, THICKNESS_RATIO * CHORD_M, SPAN_M)
TANK_FLOW = FlowParameters(profile_drag_coefficient=laminar_profile_drag_coefficient(REYNOLDS, THICKNESS_RATIO))


def measurements() -> dict[str, list[tuple[float, float]]]:
    rows = csv.DictReader(line for line in DATA.read_text().splitlines() if not line.startswith("#"))
    series: dict[str, list[tuple[float, float]]] = {}
    for row in rows:
        series.setdefault(row["quantity"], []).append((float(row["strouhal"]), float(row["value"])))
    return series


MEASURED = measurements()


def pitch_amplitude(strouhal: float) -> float:
    """The paper's theta0 = atan(pi St) - alpha0."""
    return math.atan(math.pi * strouhal) - ALPHA0_RAD


@functools.lru_cache(maxsize=None)
def tank_run(model: str, strouhal: float):
    """One run; the wake averages one cycle (two give the same means to 4 digits at 2.5 times the cost)."""
    frequency = strouhal * SPEED_M_S / (2.0 * HEAVE_M)
    return oscillating_foil(TANK_FOIL, speed_m_s=SPEED_M_S, heave_amplitude_m=HEAVE_M,
                            pitch_amplitude_rad=pitch_amplitude(strouhal), frequency_hz=frequency,
                            phase_rad=math.pi / 2, pivot_from_leading_edge_m=CHORD_M / 3, model=model,
                            averaged_cycles=1 if model == "wake" else 2, water_density_kg_m3=RHO,
                            flow_parameters=TANK_FLOW)


def in_range(series: str) -> list[tuple[float, float]]:
    return [(st, value) for st, value in MEASURED[series] if 0.13 <= st <= 0.5]


def known(points: list[tuple[float, float]], failing: set[float], reason: str) -> list:
    return [pytest.param(st, value, marks=pytest.mark.xfail(strict=True, reason=reason)) if round(st, 2) in failing
            else pytest.param(st, value) for st, value in points]


# --- definitions -------------------------------------------------------------------------------------------------
def test_tank_data_keeps_its_source_and_covers_the_range():
    header = DATA.read_text().splitlines()[:3]
    assert header[0].startswith("# Anderson, Streitlien, Barrett & Triantafyllou")
    assert "J. Fluid Mech. 360 (1998)" in header[1]
    for series in ("thrust_coefficient", "efficiency"):
        strouhal = [st for st, _ in MEASURED[series]]
        assert min(strouhal) < 0.13 and max(strouhal) > 0.49 and len(in_range(series)) == 9


@pytest.mark.parametrize("strouhal", [0.1, 0.3, 0.5])
def test_kinematic_definitions_are_the_papers(strouhal):
    """St = 2 h0 f / U; the angle of attack at the pivot at the instant of largest heave velocity (t = 0) is alpha0
    in size (theta0 = atan(pi St) - alpha0), the heave's path angle minus the pitch; the reported peak at the foil
    frame's origin is atan2(-V, U) of eq. 40's velocity there."""
    frequency = strouhal * SPEED_M_S / (2.0 * HEAVE_M)
    theta0 = pitch_amplitude(strouhal)
    kinematics = TowedFoilKinematics(SPEED_M_S, HEAVE_M, theta0, frequency, math.pi / 2,
                                     TANK_FOIL.leading_edge_x_m - CHORD_M / 3)
    u_p, v_p = kinematics.pivot_velocity(np.array([0.0]))[0]
    assert abs(math.atan2(-v_p, u_p)) == pytest.approx(ALPHA0_RAD, abs=1e-12)
    t = np.linspace(0.0, 1.0 / frequency, 97)
    _, heave_rate, _ = kinematics.heave(t)
    theta, _, _ = kinematics.pitch(t)
    pivot = kinematics.pivot_velocity(t)
    np.testing.assert_allclose(np.arctan2(-pivot[:, 1], pivot[:, 0]), theta - np.arctan(heave_rate / SPEED_M_S),
                               atol=1e-12)
    # the pivot's velocity is the towing speed plus the heave rate, whatever the pitch
    np.testing.assert_allclose(np.hypot(pivot[:, 0], pivot[:, 1]), np.hypot(SPEED_M_S, heave_rate), rtol=1e-12)
    result = oscillating_foil(TANK_FOIL, speed_m_s=SPEED_M_S, heave_amplitude_m=HEAVE_M, pitch_amplitude_rad=theta0,
                              frequency_hz=frequency, phase_rad=math.pi / 2, pivot_from_leading_edge_m=CHORD_M / 3,
                              cycles=4, averaged_cycles=1, flow_parameters=TANK_FLOW)
    assert result.strouhal == pytest.approx(2.0 * HEAVE_M * frequency / SPEED_M_S, rel=1e-12)
    assert result.peak_angle_of_attack_at_pivot_rad >= ALPHA0_RAD - 1e-3
    velocity = kinematics.velocity(result.time_s)
    assert result.peak_angle_of_attack_rad == pytest.approx(
        np.max(np.abs(np.arctan2(-velocity[:, 1], velocity[:, 0]))), rel=1e-12)


def test_thrust_and_power_definitions():
    """Mean thrust is the mean force along the towing direction; the input power is that of the heave force and
    the pitch moment about the pivot (computed here from the tank-frame force, moment and the pivot's motion)."""
    result = tank_run("circulatory", 0.3)
    frequency = 0.3 * SPEED_M_S / (2.0 * HEAVE_M)
    kinematics = TowedFoilKinematics(SPEED_M_S, HEAVE_M, pitch_amplitude(0.3), frequency, math.pi / 2,
                                     TANK_FOIL.leading_edge_x_m - CHORD_M / 3)
    assert result.mean_thrust_n == pytest.approx(np.mean(result.thrust_n), rel=1e-12)
    reference = 0.5 * RHO * SPEED_M_S ** 2 * CHORD_M * SPAN_M
    assert result.thrust_coefficient == pytest.approx(result.mean_thrust_n / reference, rel=1e-12)
    assert result.efficiency == pytest.approx(result.mean_thrust_n * SPEED_M_S / result.mean_power_w, rel=1e-12)
    # heave power: the force along +Y times the pivot's heave rate; pitch power: the rest of the foil's power
    _, heave_rate, _ = kinematics.heave(result.time_s)
    heave_power = -result.lift_n * heave_rate
    assert np.mean(heave_power) > 0.0 and np.mean(result.power_w - heave_power) != 0.0
    assert result.mean_power_w > 0.0 and result.thrust_coefficient > 0.0


# --- against the vortex wake at small angles of attack --------------------------------------------------------------
@pytest.mark.parametrize("k", [0.5, 1.0, 2.0, 4.0])
def test_reduced_model_agrees_with_the_wake_at_small_angles(k):
    """The rig's foil heaving (path angle 8 deg) and pitching 4 deg about c/3, pitch leading by 90 deg: peak angle
    of attack 4-7 deg. Mean thrust and lift amplitude within 15 % of the vortex wake's (both inviscid: no profile
    drag). Measured: thrust +3.1, +2.7, +8.3, +7.5 %; lift +1.7, -2.1, -1.5, -2.0 % at k = 0.5, 1, 2, 4. The peak
    leading-edge suction parameters agree within 15 % too (+2.2, -1.0, -4.1, -13.2 %), and neither flow stalls."""
    rig = load_rig()
    foil = JoukowskiFoil(rig.foil_chord_m, rig.foil_max_thickness_m, rig.foil_span_m)
    semichord, speed = 0.5 * rig.foil_chord_m, 0.2
    settings = dict(speed_m_s=speed, heave_amplitude_m=semichord * math.tan(math.radians(8.0)) / k,
                    pitch_amplitude_rad=math.radians(4.0), frequency_hz=k * speed / semichord / (2.0 * math.pi),
                    phase_rad=math.pi / 2, pivot_from_leading_edge_m=rig.foil_chord_m / 3,
                    water_density_kg_m3=rig.water_density_kg_m3,
                    flow_parameters=FlowParameters(profile_drag_coefficient=0.0))
    runs = {model: oscillating_foil(foil, model=model, **settings) for model in ("circulatory", "wake")}
    reduced, wake = runs["circulatory"], runs["wake"]
    assert reduced.peak_angle_of_attack_rad < math.radians(8.0)
    assert reduced.mean_thrust_n > 0.0
    assert reduced.mean_thrust_n == pytest.approx(wake.mean_thrust_n, rel=0.15)
    assert reduced.lift_amplitude_n == pytest.approx(wake.lift_amplitude_n, rel=0.15)
    assert reduced.peak_leading_edge_suction_parameter == pytest.approx(wake.peak_leading_edge_suction_parameter,
                                                                        rel=0.15)
    assert reduced.min_attached_weight > 0.999 and wake.min_attached_weight == 1.0


# --- against the tank -------------------------------------------------------------------------------------------------
HIGH_STROUHAL = "attached-flow models overpredict the thrust at the highest Strouhal numbers (module docstring)"
WAKE_POWER = "the inviscid vortex wake needs more power than the tank's foil at large amplitude (module docstring)"
WAKE_STROUHAL = [0.18, 0.27, 0.36, 0.46, 0.5]  # a subset: the wake costs seconds a run


@pytest.mark.parametrize("strouhal, measured", known(in_range("thrust_coefficient"), {0.46, 0.5}, HIGH_STROUHAL))
def test_reduced_model_thrust_against_the_tank(strouhal, measured):
    """Thrust coefficient within 20 % of the tank's (measured: +10, +7, -2, +0, +6, +4, +13 % for St 0.13-0.41)."""
    assert tank_run("circulatory", strouhal).thrust_coefficient == pytest.approx(measured, rel=0.20)


def test_leading_edge_separation_does_not_single_out_the_highest_strouhal_numbers():
    """Why the high-St misses are not the leading edge's: the peak leading-edge suction parameter, which sets where
    a rounded edge separates whatever the motion (Ramesh et al., JFM 751, 2014), is no higher at St 0.46 and 0.50,
    where both models overpredict the thrust, than at St 0.13-0.18, where they agree with the tank; the reduced
    model's stall does act there (docs/flow_model.md, "What the misses are not")."""
    low = [tank_run("circulatory", st) for st, _ in in_range("thrust_coefficient") if st < 0.2]
    high = [tank_run("circulatory", st) for st, _ in in_range("thrust_coefficient") if st > 0.45]
    assert len(low) == 2 and len(high) == 2
    assert max(r.peak_leading_edge_suction_parameter for r in high) < min(
        r.peak_leading_edge_suction_parameter for r in low)
    assert min(r.min_attached_weight for r in low) > 0.999 and max(r.min_attached_weight for r in high) < 0.9


@pytest.mark.parametrize("strouhal, measured", known(in_range("efficiency"), set(), ""))
def test_reduced_model_efficiency_against_the_tank(strouhal, measured):
    """Efficiency within 0.08 of the tank's (measured: -0.04 to -0.08, St 0.13-0.5)."""
    assert tank_run("circulatory", strouhal).efficiency == pytest.approx(measured, abs=0.08)


def wake_points(series: str) -> list[tuple[float, float]]:
    """At the thrust series' Strouhal numbers (one wake run for both quantities); the efficiency measured there is
    interpolated between its neighbours, whose Strouhal numbers differ by 0.002-0.005."""
    strouhal = [st for st, _ in in_range("thrust_coefficient") if round(st, 2) in WAKE_STROUHAL]
    points = np.array(MEASURED[series])
    return [(st, float(np.interp(st, points[:, 0], points[:, 1]))) for st in strouhal]


@pytest.mark.parametrize("strouhal, measured", known(wake_points("thrust_coefficient"), {0.5}, HIGH_STROUHAL))
def test_wake_thrust_against_the_tank(strouhal, measured):
    """Thrust coefficient within 20 % (measured: +6, -0, +2, +16 % at St 0.18, 0.27, 0.36, 0.46)."""
    assert tank_run("wake", strouhal).thrust_coefficient == pytest.approx(measured, rel=0.20)


@pytest.mark.parametrize("strouhal, measured", known(wake_points("efficiency"), {0.36, 0.46, 0.5}, WAKE_POWER))
def test_wake_efficiency_against_the_tank(strouhal, measured):
    """Efficiency within 0.08 (measured: -0.03, -0.07 at St 0.18, 0.27)."""
    assert tank_run("wake", strouhal).efficiency == pytest.approx(measured, abs=0.08)
