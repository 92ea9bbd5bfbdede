"""The towed-foil experiment (swim_model.flow.oscillating_foil): the reduced model against the vortex wake at small
angles of attack, and both against a towing tank.

Tank data (data/anderson1998_oscillating_foil.csv, copied with its source header): Anderson, Streitlien, Barrett &
Triantafyllou, J. Fluid Mech. 360 (1998): NACA 0012, chord 0.10 m, span 0.60 m, pivot at c/3, Re 40 000,
h0/c = 0.75, nominal angle of attack alpha0 = 15 deg, pitch leading heave by 90 deg. The NACA 0012 is modelled by
the Joukowski section of the same chord and 12 % thickness; the water is fresh water at 20 C (998.2 kg/m^3,
1.0e-6 m^2/s), so the towing speed is Re nu / c = 0.4 m/s; the profile drag is the laminar flat plate's friction on
both sides times Hoerner's thickness factor at Re 40 000 (flow.laminar_profile_drag_coefficient: 0.0166), for both
models. No coefficient is fitted to this series.

Section data (data/naca0012_static_polar_low_re.csv, copied with its source header): Sheldahl & Klimas, Sandia
SAND80-2114 (1981), the NACA 0012's static lift and drag at Re 1e4-8e4, 0-25 deg. It checks the laminar profile
drag at zero incidence, the attached flow's normal force below stall and the flat plate's past it.

Both models are held at all 20 points of the tank's file (St 0.09-0.50). Known disagreements, marked xfail (strict,
so a change that removes one is seen): at the lowest Strouhal number (0.09) both models' thrust is about 50 % above
the tank's; at the two highest (0.46, 0.50) the reduced model's thrust is 21 % and 31 % above (the vortex wake's
8 % and 17 %); the wake's efficiency is 0.09-0.16 below the tank's from St = 0.31 on. Where the models' power goes
and what the separation indicators say about the misses: docs/flow_model.md, "The separated regime".

The reduced model with the trailing edge separating (FlowParameters.separation, the onset from the polar
at the tank's Reynolds number, the lags set on this series) is held at the same points: its thrust within 20 % at
all ten, its efficiency within 0.08 at all but St 0.36 (strict xfail). The vortex wake given the same separation
(the reduced model's separation point, Kirchhoff's share of the bound circulation) is held there too: its thrust
within 20 % at all ten; its efficiency stays 0.09-0.16 under the tank's at every point (strict xfails).
"""
import functools
import math
from pathlib import Path

import numpy as np
import pytest

from swim_model import JoukowskiFoil, load_rig
from swim_model.errors import FlowModelError
from swim_model.flow import (
    LAG_STATE_NAMES,
    SEPARATION_LAG_STATE_NAMES,
    CirculatoryFlow,
    FlowParameters,
    laminar_profile_drag_coefficient,
    oscillating_foil,
)
from swim_model.flow_comparison import (
    STATIC_POLAR_NAME,
    polar_separation,
    read_measurements,
    read_static_polar,
    section_normal_force_coefficient,
    static_separation_points,
    steady_normal_force_coefficient,
)
from swim_model.separation import TrailingEdgeSeparation
from swim_model.towed_foil import TowedFoilKinematics, kirchhoff_force

DATA = Path(__file__).parent / "data" / "anderson1998_oscillating_foil.csv"
POLAR = Path(__file__).parent / "data" / STATIC_POLAR_NAME
RHO = 998.2                      # fresh water at 20 C, as rig.yaml
NU = 1.0e-6                      # its kinematic viscosity, m^2/s
CHORD_M, SPAN_M, THICKNESS_RATIO = 0.10, 0.60, 0.12
REYNOLDS = 40_000.0
SPEED_M_S = REYNOLDS * NU / CHORD_M
HEAVE_M = 0.75 * CHORD_M
ALPHA0_RAD = math.radians(15.0)
TANK_FOIL = JoukowskiFoil(CHORD_M, THICKNESS_RATIO * CHORD_M, SPAN_M)
TANK_FLOW = FlowParameters(profile_drag_coefficient=laminar_profile_drag_coefficient(REYNOLDS, THICKNESS_RATIO))


MEASURED = read_measurements(DATA)


def pitch_amplitude(strouhal: float) -> float:
    """The paper's theta0 = atan(pi St) - alpha0."""
    return math.atan(math.pi * strouhal) - ALPHA0_RAD


def heave_frequency(strouhal: float) -> float:
    """The frequency, Hz, of the paper's St = 2 h0 f / U."""
    return strouhal * SPEED_M_S / (2.0 * HEAVE_M)


@functools.lru_cache(maxsize=None)
def tank_run(model: str, strouhal: float, steps_per_cycle: int | None = None,
             flow_parameters: FlowParameters = TANK_FLOW):
    """One run (at oscillating_foil's default steps a cycle unless given); the wake averages one cycle (two give the
    same means to 4 digits at 2.5 times the cost)."""
    frequency = heave_frequency(strouhal)
    return oscillating_foil(TANK_FOIL, speed_m_s=SPEED_M_S, heave_amplitude_m=HEAVE_M,
                            pitch_amplitude_rad=pitch_amplitude(strouhal), frequency_hz=frequency,
                            phase_rad=math.pi / 2, pivot_from_leading_edge_m=CHORD_M / 3, model=model,
                            averaged_cycles=1 if model == "wake" else 2, water_density_kg_m3=RHO,
                            flow_parameters=flow_parameters, steps_per_cycle=steps_per_cycle)


def small_angle_settings(k: float) -> tuple[JoukowskiFoil, dict]:
    """The rig's foil heaving (path angle 8 deg) and pitching 4 deg about c/3 at reduced frequency k, pitch leading
    by 90 deg, at 0.2 m/s: oscillating_foil's foil and keyword arguments but the model and the flow parameters."""
    rig = load_rig()
    foil = JoukowskiFoil(rig.foil_chord_m, rig.foil_max_thickness_m, rig.foil_span_m)
    semichord, speed = 0.5 * rig.foil_chord_m, 0.2
    return foil, dict(speed_m_s=speed, heave_amplitude_m=semichord * math.tan(math.radians(8.0)) / k,
                      pitch_amplitude_rad=math.radians(4.0), frequency_hz=k * speed / semichord / (2.0 * math.pi),
                      phase_rad=math.pi / 2, pivot_from_leading_edge_m=rig.foil_chord_m / 3,
                      water_density_kg_m3=rig.water_density_kg_m3)


@functools.lru_cache(maxsize=None)
def small_angle_run(k: float, model: str, flow_parameters: FlowParameters):
    """One run of the small-angle case (small_angle_settings), shared by the tests that compare it."""
    foil, settings = small_angle_settings(k)
    return oscillating_foil(foil, model=model, flow_parameters=flow_parameters, **settings)


def at_thrust_strouhal(series: str) -> list[tuple[float, float]]:
    """The series at the thrust series' Strouhal numbers (one run for both quantities); the efficiency measured there
    is interpolated between its neighbours, whose Strouhal numbers differ by 0.002-0.005."""
    points = np.array(MEASURED[series])
    return [(st, float(np.interp(st, points[:, 0], points[:, 1]))) for st, _ in MEASURED["thrust_coefficient"]]


# --- definitions -------------------------------------------------------------------------------------------------
def test_tank_data_keeps_its_source_and_covers_the_range():
    header = DATA.read_text().splitlines()[:3]
    assert header[0].startswith("# Anderson, Streitlien, Barrett & Triantafyllou")
    assert "J. Fluid Mech. 360 (1998)" in header[1]
    for series in ("thrust_coefficient", "efficiency"):
        strouhal = [st for st, _ in MEASURED[series]]
        assert min(strouhal) < 0.1 and max(strouhal) > 0.49 and len(strouhal) == 10


@pytest.mark.parametrize("strouhal", [0.1, 0.3, 0.5])
def test_kinematic_definitions_are_the_papers(strouhal):
    """St = 2 h0 f / U; the angle of attack at the pivot at the instant of largest heave velocity (t = 0) is alpha0
    in size (theta0 = atan(pi St) - alpha0), the heave's path angle minus the pitch; the reported peak at the foil
    frame's origin is atan2(-V, U) of eq. 40's velocity there."""
    frequency = heave_frequency(strouhal)
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
    frequency = heave_frequency(0.3)
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
    drag). Measured: thrust +6.9, +9.1, +10.5, +4.3 %; lift +5.2, +5.9, +4.9, +1.5 % at k = 0.5, 1, 2, 4. The peak
    leading-edge suction parameters agree within 15 % too (+3.4, -0.2, -4.6, -14.0 %), and neither flow stalls."""
    inviscid = FlowParameters(profile_drag_coefficient=0.0)
    reduced, wake = (small_angle_run(k, model, inviscid) for model in ("circulatory", "wake"))
    assert reduced.peak_angle_of_attack_rad < math.radians(8.0)
    assert reduced.mean_thrust_n > 0.0
    assert reduced.mean_thrust_n == pytest.approx(wake.mean_thrust_n, rel=0.15)
    assert reduced.lift_amplitude_n == pytest.approx(wake.lift_amplitude_n, rel=0.15)
    assert reduced.peak_leading_edge_suction_parameter == pytest.approx(wake.peak_leading_edge_suction_parameter,
                                                                        rel=0.15)
    assert reduced.min_attached_weight > 0.999 and wake.min_attached_weight == 1.0


# --- against the tank -------------------------------------------------------------------------------------------------
LOW_STROUHAL = "attached-flow models overpredict the thrust at the lowest Strouhal number (module docstring)"
HIGH_STROUHAL = "attached-flow models overpredict the thrust at the highest Strouhal numbers (module docstring)"
WAKE_POWER = "the inviscid vortex wake needs more power than the tank's foil at large amplitude (module docstring)"
REDUCED_THRUST_MISSES = {0.09: LOW_STROUHAL, 0.46: HIGH_STROUHAL, 0.5: HIGH_STROUHAL}
WAKE_THRUST_MISSES = {0.09: LOW_STROUHAL}
WAKE_EFFICIENCY_MISSES = {st: WAKE_POWER for st in (0.31, 0.36, 0.41, 0.46, 0.5)}


def known(points: list[tuple[float, float]], misses: dict[float, str]) -> list:
    """The points as pytest params, those at a known miss's Strouhal number (2 decimals) marked strict xfail."""
    return [pytest.param(st, value, marks=pytest.mark.xfail(strict=True, reason=misses[round(st, 2)]))
            if round(st, 2) in misses else pytest.param(st, value) for st, value in points]


@pytest.mark.parametrize("strouhal, measured", known(MEASURED["thrust_coefficient"], REDUCED_THRUST_MISSES))
def test_reduced_model_thrust_against_the_tank(strouhal, measured):
    """Thrust coefficient within 20 % of the tank's (measured: +54, +10, +7, -2, +0, +6, +4, +13, +21, +31 %)."""
    assert tank_run("circulatory", strouhal).thrust_coefficient == pytest.approx(measured, rel=0.20)


@pytest.mark.parametrize("strouhal, measured", known(MEASURED["efficiency"], {}))
def test_reduced_model_efficiency_against_the_tank(strouhal, measured):
    """Efficiency within 0.08 of the tank's, at the efficiency series' own Strouhal numbers (measured: +0.06 at
    St 0.09, -0.02 to -0.08 from St 0.13 on)."""
    assert tank_run("circulatory", strouhal).efficiency == pytest.approx(measured, abs=0.08)


@pytest.mark.parametrize("strouhal, measured", known(MEASURED["thrust_coefficient"], WAKE_THRUST_MISSES))
def test_wake_thrust_against_the_tank(strouhal, measured):
    """Thrust coefficient within 20 % (measured: +46, +3, +1, -7, -5, +0, -3, +3, +8, +17 %)."""
    assert tank_run("wake", strouhal).thrust_coefficient == pytest.approx(measured, rel=0.20)


@pytest.mark.parametrize("strouhal, measured", known(at_thrust_strouhal("efficiency"), WAKE_EFFICIENCY_MISSES))
def test_wake_efficiency_against_the_tank(strouhal, measured):
    """Efficiency within 0.08 (measured: +0.05, -0.05, -0.04, -0.08, -0.08, then -0.09 to -0.16 from St 0.31)."""
    assert tank_run("wake", strouhal).efficiency == pytest.approx(measured, abs=0.08)


def test_the_wakes_default_time_step_is_converged_at_the_highest_strouhal_number():
    """oscillating_foil's default for the wake (towed_foil.WAKE_MIN_STEPS_PER_CYCLE) against a quarter and half of it
    at St 0.50, where the wake converges slowest: C_T falls with each halving of the step by less each time, and the
    last halving moves it by less than 2.5 % (measured 1.175, 1.138, 1.113 at 200, 400, 800 steps a cycle; 1.095 at
    1600), the efficiency by less than 0.005."""
    strouhal = 0.4955
    default = tank_run("wake", strouhal)
    coarser = [tank_run("wake", strouhal, default.steps_per_cycle // divisor) for divisor in (4, 2)]
    thrust = [run.thrust_coefficient for run in coarser] + [default.thrust_coefficient]
    steps = np.abs(np.diff(thrust))
    assert steps[1] < steps[0]
    assert steps[1] < 0.025 * thrust[-1]
    assert abs(default.efficiency - coarser[1].efficiency) < 0.005


# --- what the misses are ----------------------------------------------------------------------------------------------
def test_the_separation_indicators_single_out_the_misses_only_against_the_free_stream():
    """Where both models miss (St 0.09 and 0.46-0.50) against where they agree (0.22-0.31).

    The leading-edge suction parameter referred to the foil's own speed |u| (the models' criterion) is highest at
    the low end and lowest at the high end, so no critical value separates the high-St misses alone. Referred to the
    towing speed, as Ramesh et al. (JFM 751, 2014) refer theirs to the free stream, it is higher at both ends than
    anywhere between; the quasi-steady incidence at the three-quarter chord rises with St and passes 32 deg only
    at the high end, where the reduced model's stall acts (docs/flow_model.md, "The separated regime")."""
    runs = {round(st, 2): tank_run("circulatory", st) for st, _ in MEASURED["thrust_coefficient"]}
    agree = [runs[st] for st in (0.22, 0.27, 0.31)]
    ends = [runs[0.09], runs[0.46], runs[0.5]]
    own_speed = [r.peak_leading_edge_suction_parameter for r in runs.values()]
    assert runs[0.09].peak_leading_edge_suction_parameter == max(own_speed)
    assert max(runs[st].peak_leading_edge_suction_parameter for st in (0.46, 0.5)) < runs[
        0.13].peak_leading_edge_suction_parameter
    assert min(r.peak_free_stream_suction_parameter for r in ends) > max(
        r.peak_free_stream_suction_parameter for r in agree)
    incidence_deg = [math.degrees(r.peak_three_quarter_chord_incidence_rad) for r in runs.values()]
    assert np.all(np.diff(incidence_deg) > 0.0)
    assert incidence_deg[-3] < 32.0 < incidence_deg[-2]
    assert min(r.min_attached_weight for r in agree) > 0.99 and runs[0.5].min_attached_weight < 0.9
    # the wake's attached flow reads the same
    wake_ends = [tank_run("wake", st) for st in (0.0898, 0.4955)]
    wake_agree = tank_run("wake", 0.2675)
    assert min(r.peak_free_stream_suction_parameter for r in wake_ends) > wake_agree.peak_free_stream_suction_parameter


def test_the_models_power_is_the_heave_drives_and_the_added_mass_puts_in_none():
    """The power split over whole cycles (docs/flow_model.md, "Power").

    The added-mass force's mean power is zero (it is the rate of a periodic kinetic energy) to round-off; the heave
    drive's power -F_Y h' (computed here from the lift and the kinematics) is OscillatingFoilResult.heave_power_w;
    the reduced model's pitch drive puts in at most 3 % of the total at 90 deg, and the vortex wake's, at St 0.46
    and 0.50, 10-12 %: the wake's excess power over the reduced model's there is mostly its pitch moment's."""
    for st in (0.2214, 0.4955):
        frequency = heave_frequency(st)
        kinematics = TowedFoilKinematics(SPEED_M_S, HEAVE_M, pitch_amplitude(st), frequency, math.pi / 2,
                                         TANK_FOIL.leading_edge_x_m - CHORD_M / 3)
        for model in ("circulatory", "wake"):
            run = tank_run(model, st)
            _, heave_rate, _ = kinematics.heave(run.time_s)
            np.testing.assert_allclose(run.heave_power_w, -run.lift_n * heave_rate, rtol=1e-12, atol=1e-15)
            velocity, acceleration = kinematics.velocity(run.time_s), kinematics.acceleration(run.time_s)
            added = kirchhoff_force(TANK_FOIL.added_mass(RHO), velocity, acceleration)
            assert abs(np.mean(np.sum(added * velocity, axis=1))) < 1e-12 * run.mean_power_w
        pitch_share = {model: 1.0 - np.mean(tank_run(model, st).heave_power_w) / tank_run(model, st).mean_power_w
                       for model in ("circulatory", "wake")}
        assert abs(pitch_share["circulatory"]) < 0.03
        if st > 0.45:
            assert 0.09 < pitch_share["wake"] < 0.15
            reduced, wake = tank_run("circulatory", st), tank_run("wake", st)
            pitch_excess = (wake.mean_power_w - np.mean(wake.heave_power_w)) - (
                reduced.mean_power_w - np.mean(reduced.heave_power_w))
            assert pitch_excess > 0.5 * (wake.mean_power_w - reduced.mean_power_w)


def test_the_three_quarter_chord_incidence_of_pure_heave_is_the_path_angle():
    """With no pitch the foil's normal velocity is the heave rate's: the quasi-steady incidence at the three-quarter
    chord peaks at atan(2 pi f h0 / U) = atan(pi St), and the free-stream suction parameter is the foil's own times
    |u| / U, |u| = sqrt(U^2 + h'^2)."""
    strouhal = 0.3
    frequency = heave_frequency(strouhal)
    run = oscillating_foil(TANK_FOIL, speed_m_s=SPEED_M_S, heave_amplitude_m=HEAVE_M, pitch_amplitude_rad=0.0,
                           frequency_hz=frequency, phase_rad=math.pi / 2, pivot_from_leading_edge_m=CHORD_M / 3,
                           cycles=4, averaged_cycles=1, steps_per_cycle=400, flow_parameters=TANK_FLOW)
    # the samples miss the exact peak by at most half a step: cos(pi / 400) in the heave rate
    assert run.peak_three_quarter_chord_incidence_rad == pytest.approx(math.atan(math.pi * strouhal), rel=1e-4)
    _, heave_rate, _ = TowedFoilKinematics(SPEED_M_S, HEAVE_M, 0.0, frequency, math.pi / 2, 0.0).heave(run.time_s)
    free_stream = run.leading_edge_suction_parameter * np.hypot(SPEED_M_S, heave_rate) / SPEED_M_S
    assert run.peak_free_stream_suction_parameter == pytest.approx(np.max(np.abs(free_stream)), rel=1e-12)


# --- the static polar -------------------------------------------------------------------------------------------------
def static_polar() -> dict[float, list[tuple[float, float, float]]]:
    """{Reynolds number: [(alpha_deg, C_L, C_D), ...]} of the NACA 0012's static polar (Sheldahl & Klimas 1981)."""
    return read_static_polar(POLAR)


def test_static_polar_keeps_its_source_and_covers_the_range():
    header = [line for line in POLAR.read_text().splitlines() if line.startswith("#")]
    assert any("Sheldahl and P. C. Klimas" in line for line in header)
    assert any("SAND80-2114 (1981)" in line for line in header)
    polar = static_polar()
    assert sorted(polar) == [1e4, 2e4, 4e4, 8e4]
    for rows in polar.values():
        assert [alpha for alpha, _, _ in rows] == list(range(26))
        assert rows[0][1] == 0.0 and all(drag > 0.0 for _, _, drag in rows)


@pytest.mark.parametrize("reynolds", [1e4, 2e4, 4e4, 8e4])
def test_laminar_profile_drag_is_the_sections_drag_at_zero_incidence(reynolds):
    """laminar_profile_drag_coefficient (Blasius on both sides times Hoerner's thickness factor, no coefficient
    from this file) against the measured C_D at 0 deg: within 12 % (measured: -1, -4, -5, -12 % at Re 1e4-8e4,
    nearest at the rig's Reynolds numbers)."""
    measured = static_polar()[reynolds][0][2]
    assert laminar_profile_drag_coefficient(reynolds, THICKNESS_RATIO) == pytest.approx(measured, rel=0.12)


@pytest.mark.parametrize("reynolds", [4e4, 8e4])
def test_below_stall_the_section_carries_the_attached_flows_normal_force_less_its_boundary_layers_share(reynolds):
    """At 1-5 deg, below the static stall (6-7 deg at these Reynolds numbers), the measured normal force is
    0.85-1.0 of the reduced model's steady one, an attached potential flow's (measured: 0.89-0.94). At Re 1e4-2e4
    it is 0.4-0.9 and falls with incidence: the laminar separation the rig's foil meets (docs/flow_model.md)."""
    model = steady_normal_force_coefficient(tuple(float(a) for a in range(1, 6)))
    for (alpha_deg, lift, drag), attached in zip(static_polar()[reynolds][1:6], model):
        assert 0.85 * attached < section_normal_force_coefficient(alpha_deg, lift, drag) < attached


@pytest.mark.parametrize("reynolds", [1e4, 2e4, 4e4, 8e4])
def test_past_stall_the_section_carries_the_flat_plates_normal_force(reynolds):
    """The separated flow's normal force C_N90 sin(alpha) (FlowParameters.flat_plate_normal_force_coefficient,
    Hoerner's flat plate) against the NACA 0012's measured static normal force C_L cos(alpha) + C_D sin(alpha) at
    20-25 deg, well past its static stall at these Reynolds numbers: within 13 % (measured: 0.94-1.13 of the flat
    plate's at every Reynolds number; below 20 deg the section carries less, 0.4-0.9)."""
    coefficient = FlowParameters().flat_plate_normal_force_coefficient
    for alpha_deg, lift, drag in static_polar()[reynolds]:
        if alpha_deg >= 20.0:
            assert section_normal_force_coefficient(alpha_deg, lift, drag) == pytest.approx(
                coefficient * math.sin(math.radians(alpha_deg)), rel=0.13)


# --- trailing-edge separation (FlowParameters.separation) -------------------------------------------------------------
# Leishman & Beddoes's separation (J. Am. Helicopter Soc. 34, 1989): the static separation point f from the polar
# through Kirchhoff's flow (flow_comparison.static_separation_points, fitted by static_separation_fit), read at the
# effective incidence lagged by T_p, itself lagged by T_f; the normal force and its moment times ((1 + sqrt f)/2)^2,
# the suction times sqrt f. The lags are TrailingEdgeSeparation's defaults (twice the published NACA 0012 values, set
# on this series: docs/flow_model.md, Sec. 6).
#: the separation's efficiency miss on this series: the attached model is already 0.077 under the tank there, and
#: the separation takes 0.006 more
SEPARATED_EFFICIENCY_MISSES = {0.36: "the models' input power is above the tank's at St 0.36 (docs/flow_model.md)"}


def separated(reynolds: float = REYNOLDS, **fields) -> FlowParameters:
    """FlowParameters with the separation of the polar at this Reynolds number (its lags the default ones)."""
    return FlowParameters(separation=polar_separation(static_polar(), reynolds), **fields)


#: the tank's flow with the separation of its polar, at the tank's Reynolds number
TANK_SEPARATED_FLOW = separated(profile_drag_coefficient=TANK_FLOW.profile_drag_coefficient)


def test_the_separation_adds_two_lag_states_and_the_default_has_none():
    flow = CirculatoryFlow(TANK_FOIL, RHO)
    assert not flow.params.separates and flow.lag_state_names == LAG_STATE_NAMES
    with_separation = CirculatoryFlow(TANK_FOIL, RHO, TANK_SEPARATED_FLOW)
    assert with_separation.lag_state_names == LAG_STATE_NAMES + SEPARATION_LAG_STATE_NAMES
    assert with_separation.lag_state_count == 4
    assert TANK_SEPARATED_FLOW.digest() != TANK_FLOW.digest()


@pytest.mark.parametrize("fields, match", [
    (dict(onset_rad=0.0, width_rad=0.01), "onset_rad"), (dict(onset_rad=math.radians(45.0), width_rad=0.01), "onset"),
    (dict(onset_rad=math.nan, width_rad=0.01), "onset"), (dict(onset_rad=0.1, width_rad=0.0), "width_rad"),
    (dict(onset_rad=0.1, width_rad=0.01, point_lag_semichords=-1.0), "point_lag")])
def test_a_separation_outside_its_range_is_refused(fields, match):
    with pytest.raises(FlowModelError, match=match):
        TrailingEdgeSeparation(**fields)


def test_a_separation_that_is_not_one_is_refused():
    with pytest.raises(FlowModelError, match="TrailingEdgeSeparation"):
        FlowParameters(separation=0.1)


@pytest.mark.parametrize("reynolds", [1e4, 2e4, 4e4, 8e4])
def test_the_fitted_onset_is_where_the_polars_separation_point_crosses_one_half(reynolds):
    """The fit's onset lies between the polar's last incidence with f >= 1/2 and its first with f < 1/2 (read off
    the points, no fit), and the logistic follows the points up to 15 deg within 0.12 rms."""
    polar = static_polar()[reynolds]
    points = static_separation_points(polar, steady_normal_force_coefficient(tuple(a for a, _, _ in polar)))
    first_below = next(alpha for alpha, f in points if f < 0.5)
    last_above = max(alpha for alpha, f in points if f >= 0.5 and alpha < first_below)
    separation = polar_separation(static_polar(), reynolds)
    onset, width = separation.onset_rad, separation.width_rad
    assert last_above <= math.degrees(onset) <= first_below
    used = [(math.radians(alpha), f) for alpha, f in points if alpha <= 15.0]
    model = [1.0 / (1.0 + math.exp((math.sin(a) ** 2 - math.sin(onset) ** 2) / (width * math.sin(2 * onset))))
             for a, _ in used]
    assert float(np.sqrt(np.mean([(m - f) ** 2 for m, (_, f) in zip(model, used)]))) < 0.12


@pytest.mark.parametrize("alpha_deg, attached", [(2.0, True), (12.0, False)])
def test_steady_flow_keeps_kirchhoffs_share_of_the_normal_force(alpha_deg, attached):
    """Towed steadily at a fixed incidence with its lag states steady: below the onset (6.3 deg at Re 4e4) the
    force is the attached model's; above it (and below the stall) f is near 0, the normal force a quarter of the
    attached one and the suction gone: ((1 + sqrt f) / 2)^2 and sqrt f, evaluated on the model's own f."""
    params = separated(profile_drag_coefficient=0.0)
    plain = CirculatoryFlow(TANK_FOIL, RHO, FlowParameters(profile_drag_coefficient=0.0))
    flow = CirculatoryFlow(TANK_FOIL, RHO, params)
    velocity = (SPEED_M_S * math.cos(math.radians(alpha_deg)), -SPEED_M_S * math.sin(math.radians(alpha_deg)), 0.0)
    base = plain.evaluate(velocity, plain.steady_lag(velocity))
    terms = flow.evaluate(velocity, flow.steady_lag(velocity))
    assert np.allclose(terms["lag_dot"], 0.0, atol=1e-12)
    point = float(terms["separation_point"])
    kirchhoff = 0.25 * (1.0 + math.sqrt(point)) ** 2
    assert float(base["attached_weight"]) > 0.99            # below the stall: the attached flow's force
    attached_normal = base["f"][1]
    if attached:
        assert point > 0.999
        assert np.allclose(terms["f"], base["f"], rtol=1e-3)
    else:
        assert point < 1e-6
        assert terms["f"][1] == pytest.approx(kirchhoff * attached_normal, rel=0.01)
        assert terms["f"][1] == pytest.approx(0.25 * attached_normal, rel=0.01)
        assert abs(terms["f"][0]) < 1e-3 * abs(base["f"][0])


def test_a_plate_held_at_90_deg_keeps_the_flat_plates_normal_force():
    params = separated(profile_drag_coefficient=0.0)
    plain = CirculatoryFlow(TANK_FOIL, RHO, FlowParameters(profile_drag_coefficient=0.0))
    flow = CirculatoryFlow(TANK_FOIL, RHO, params)
    velocity = (0.0, -SPEED_M_S, 0.0)
    expected = 0.5 * RHO * SPAN_M * CHORD_M * params.flat_plate_normal_force_coefficient * SPEED_M_S ** 2
    for model in (plain, flow):
        force = model.evaluate(velocity, model.steady_lag(velocity))["f"]
        assert force[1] == pytest.approx(expected, rel=1e-3)


@pytest.mark.parametrize("time_scale", [0.5, 2.0])
def test_the_separations_lag_states_are_velocities_so_time_scaling_holds(time_scale):
    """Every force and lag rate is homogeneous of degree 2 in (velocities, lag states), as the Wagner states are
    (P3: flow.py's docstring): scaled by lambda, the force and lag rate scale by lambda^2 (eps to zero)."""
    flow = CirculatoryFlow(TANK_FOIL, RHO, separated(speed_regularization_m_s=1e-9))
    rng = np.random.default_rng(7)
    for _ in range(20):
        velocity = np.array([0.3, -0.1, 2.0]) + rng.normal(0.0, [0.1, 0.2, 3.0])
        lag = np.concatenate([rng.normal(0.0, 0.2, 3), [abs(rng.normal(0.2, 0.1))]])
        base = flow.evaluate(velocity, lag)
        scaled = flow.evaluate(time_scale * velocity, time_scale * lag)
        assert np.allclose(scaled["f"], time_scale ** 2 * base["f"], rtol=1e-9, atol=1e-12)
        assert np.allclose(scaled["lag_dot"], time_scale ** 2 * base["lag_dot"], rtol=1e-9, atol=1e-12)
        assert scaled["separation_point"] == pytest.approx(base["separation_point"], rel=1e-9)


@pytest.mark.parametrize("model", ["circulatory", "wake"])
@pytest.mark.parametrize("k", [0.5, 1.0, 2.0, 4.0])
def test_small_incidence_is_unchanged_below_the_polars_onset(k, model):
    """The small-angle case (small_angle_settings: peak incidence 4-7 deg) with the tank's polar, onset 6.3 deg:
    mean thrust and lift amplitude within 1 % of the attached flow's, in both models (measured: thrust -0.10 to
    -0.05 % reduced, -0.09 to +0.005 % wake; lift -0.08 to -0.06 % and -0.03 to -0.007 %). With the rig's Re 1e4
    polar, onset 3.2 deg, the same motion separates in part (-4.0 to -0.8 %: docs/flow_model.md)."""
    plain = small_angle_run(k, model, FlowParameters(profile_drag_coefficient=0.0))
    run = small_angle_run(k, model, separated(profile_drag_coefficient=0.0))
    assert run.mean_thrust_n == pytest.approx(plain.mean_thrust_n, rel=0.01)
    assert run.lift_amplitude_n == pytest.approx(plain.lift_amplitude_n, rel=0.01)


@pytest.mark.parametrize("strouhal, measured", MEASURED["thrust_coefficient"])
def test_with_the_separation_the_reduced_models_thrust_is_within_20_percent_at_every_point(strouhal, measured):
    """All ten points, St 0.09-0.50, the attached model's three misses (+54 % at St 0.09, +21 and +31 % at St
    0.46-0.50) included: measured +1, -15, -11, -16, -13, -8, -10, -2, +6, +14 %."""
    run = tank_run("circulatory", strouhal, flow_parameters=TANK_SEPARATED_FLOW)
    assert run.thrust_coefficient == pytest.approx(measured, rel=0.20)


@pytest.mark.parametrize("strouhal, measured", known(MEASURED["efficiency"], SEPARATED_EFFICIENCY_MISSES))
def test_with_the_separation_the_reduced_models_efficiency_is_within_0_08(strouhal, measured):
    """At the efficiency series' own Strouhal numbers (measured: -0.002 at St 0.09, -0.036 to -0.064 from St 0.13);
    St 0.36 misses by 0.083 (the attached model: 0.077)."""
    run = tank_run("circulatory", strouhal, flow_parameters=TANK_SEPARATED_FLOW)
    assert run.efficiency == pytest.approx(measured, abs=0.08)


# The wake given the same separation (its separation point the reduced model's, from the same motion): each step's
# vortex holds the bound circulation at Kirchhoff's share of the attached flow's (Wake.step), the suction times sqrt f.
#: the wake's efficiency stays under the tank's at every point with the separation (docs/flow_model.md, Sec. 6: its
#: lift changes only by shedding, and at these frequencies keeps near its attached amplitude)
WAKE_SEPARATED_POWER = "the wake with the separation still needs more power than the tank (module docstring)"


@pytest.mark.parametrize("strouhal, measured", MEASURED["thrust_coefficient"])
def test_with_the_separation_the_wakes_thrust_is_within_20_percent_at_every_point(strouhal, measured):
    """All ten points, the attached wake's miss at St 0.09 (+46 %) included: measured -14, -18, -10, -13, -9, -3,
    -5, +2, +9, +19 %."""
    run = tank_run("wake", strouhal, flow_parameters=TANK_SEPARATED_FLOW)
    assert run.thrust_coefficient == pytest.approx(measured, rel=0.20)


@pytest.mark.parametrize("strouhal, measured", known(at_thrust_strouhal("efficiency"), {
    round(st, 2): WAKE_SEPARATED_POWER for st, _ in MEASURED["thrust_coefficient"]}))
def test_with_the_separation_the_wakes_efficiency_is_within_0_08(strouhal, measured):
    """Measured -0.124, -0.125, -0.086, -0.102, -0.098, -0.103, -0.137, -0.125, -0.152, -0.155 at St 0.09-0.50
    (the attached wake: +0.047 to -0.158)."""
    run = tank_run("wake", strouhal, flow_parameters=TANK_SEPARATED_FLOW)
    assert run.efficiency == pytest.approx(measured, abs=0.08)
