"""Thrust coefficient and efficiency against Strouhal number: the reduced flow model, the vortex wake and the tank.

The towed-foil experiment of Anderson, Streitlien, Barrett & Triantafyllou (J. Fluid Mech. 360, 1998): NACA 0012
(here the Joukowski section of the same chord and 12 % thickness), chord 0.10 m, span 0.60 m, pivot at c/3,
Re 40 000 in fresh water (0.4 m/s), h0/c = 0.75, nominal angle of attack 15 deg, pitch leading heave by 90 deg;
the same laminar profile drag for both models (flow.laminar_profile_drag_coefficient). The measurements are read
from the CSV that the tests use (src/swim_model/test/data/ in the source tree; ``--measurements`` for another).
Beside them, the NACA 0012's static polar (Sheldahl & Klimas 1981, the CSV beside the tank's) against the reduced
model's steady normal force and the flat plate's (docs/flow_model.md, "The separated regime").
"""
from __future__ import annotations

import csv
import dataclasses
import json
import math
from pathlib import Path

import numpy as np

from swim_model.flow import (
    KINEMATIC_VISCOSITY_WATER_M2_S,
    CirculatoryFlow,
    FlowParameters,
    laminar_profile_drag_coefficient,
    oscillating_foil,
)
from swim_model.joukowski import JoukowskiFoil
from swim_model.separation import TrailingEdgeSeparation, logistic_separation_point

CHORD_M, SPAN_M, THICKNESS_RATIO = 0.10, 0.60, 0.12
REYNOLDS = 40_000.0
WATER_DENSITY_KG_M3 = 998.2
HEAVE_OVER_CHORD = 0.75
ALPHA0_DEG = 15.0
DEFAULT_MEASUREMENTS = Path(__file__).resolve().parents[1] / "test" / "data" / "anderson1998_oscillating_foil.csv"
TOWING_SPEED_M_S = REYNOLDS * KINEMATIC_VISCOSITY_WATER_M2_S / CHORD_M   # Re nu / c: 0.4 m/s
STATIC_POLAR_NAME = "naca0012_static_polar_low_re.csv"   # beside the tank's measurements
#: compute's key for the reduced model with the trailing edge separating as the polar at the tank's Reynolds number
SEPARATED = "circulatory_separated"
POLAR_REYNOLDS = (1.0e4, 4.0e4)    # the rig's order (its foil at 0.17 m/s) and the tank's
STEADY_ANGLES_DEG = tuple(float(a) for a in range(0, 41))   # the steady normal force's incidences, deg


def _csv_rows(path: Path) -> "csv.DictReader[str]":
    """The rows of a CSV file whose comment lines start with #, as dicts by the header's names."""
    return csv.DictReader(line for line in path.read_text().splitlines() if not line.startswith("#"))


def section_normal_force_coefficient(alpha_deg: float, lift_coefficient: float, drag_coefficient: float) -> float:
    """A section's normal force coefficient from its lift and drag at an incidence: C_L cos a + C_D sin a.

    Parameters
    ----------
    alpha_deg : float
        Incidence, deg.
    lift_coefficient, drag_coefficient : float
        C_L and C_D there.

    Returns
    -------
    float
        C_N.
    """
    alpha = math.radians(alpha_deg)
    return lift_coefficient * math.cos(alpha) + drag_coefficient * math.sin(alpha)


def read_measurements(path: Path) -> dict[str, list[tuple[float, float]]]:
    """The tank's measurements from the CSV (comment lines start with #).

    Parameters
    ----------
    path : pathlib.Path
        The CSV file.

    Returns
    -------
    dict of str to list of (float, float)
        {quantity: [(St, value), ...]}.
    """
    series: dict[str, list[tuple[float, float]]] = {}
    for row in _csv_rows(path):
        series.setdefault(row["quantity"], []).append((float(row["strouhal"]), float(row["value"])))
    return series


def read_static_polar(path: Path) -> dict[float, list[tuple[float, float, float]]]:
    """The static polar from its CSV (comment lines start with #).

    Parameters
    ----------
    path : pathlib.Path
        The CSV file, columns reynolds_number, alpha_deg, lift_coefficient, drag_coefficient.

    Returns
    -------
    dict of float to list of (float, float, float)
        {Reynolds number: [(alpha deg, C_L, C_D), ...]} in the file's order.
    """
    polar: dict[float, list[tuple[float, float, float]]] = {}
    for row in _csv_rows(path):
        polar.setdefault(float(row["reynolds_number"]), []).append(
            (float(row["alpha_deg"]), float(row["lift_coefficient"]), float(row["drag_coefficient"])))
    return polar


def steady_normal_force_coefficient(angles_deg: tuple[float, ...] = STEADY_ANGLES_DEG,
                                    params: FlowParameters | None = None) -> list[float]:
    """The reduced model's normal force coefficient of the tank's foil towed at fixed incidences.

    Its lag states at their steady values (``CirculatoryFlow.steady_lag``), no profile drag: N / (1/2 rho U^2 c s)
    with N the force along the foil's normal (in steady motion the added mass adds none).

    Parameters
    ----------
    angles_deg : tuple of float, optional
        Incidences, deg, each in [0, 90).
    params : FlowParameters, optional
        The model's coefficients (default: FlowParameters() without profile drag).

    Returns
    -------
    list of float
        C_N at each incidence.
    """
    speed = TOWING_SPEED_M_S
    foil = JoukowskiFoil(CHORD_M, THICKNESS_RATIO * CHORD_M, SPAN_M)
    flow = CirculatoryFlow(foil, WATER_DENSITY_KG_M3, params or FlowParameters(profile_drag_coefficient=0.0))
    reference = 0.5 * WATER_DENSITY_KG_M3 * speed ** 2 * CHORD_M * SPAN_M
    coefficients = []
    for angle in angles_deg:
        velocity = (speed * math.cos(math.radians(angle)), -speed * math.sin(math.radians(angle)), 0.0)
        force = flow.evaluate(velocity, flow.steady_lag(velocity))["f"]
        coefficients.append(float(force[1]) / reference)
    return coefficients


#: the polar's separation point is read as 1 up to this incidence: below it the section carries 6-11 % less
#: normal force than the attached flow at Re 4e4-8e4, the boundary layer's share, not separation (docs/flow_model.md,
#: "The static polar")
ATTACHED_UP_TO_DEG = 4.0
#: the incidences the fit weighs: the polar's onset and its drop; above 15 deg the transcription's post-stall ramp
SEPARATION_FIT_UP_TO_DEG = 15.0


def static_separation_points(section: list[tuple[float, float, float]],
                             attached_normal: list[float]) -> list[tuple[float, float]]:
    """A static polar's trailing-edge separation point f at each incidence, through Kirchhoff's flow.

    ``C_N = C_N,attached ((1 + sqrt f) / 2)^2`` (Leishman & Beddoes, J. Am. Helicopter Soc. 34, 1989) solved for f,
    with C_N the section's (``section_normal_force_coefficient``) and C_N,attached the reduced model's steady one at
    the same incidence; then divided by its largest value up to ``ATTACHED_UP_TO_DEG``, and capped at 1.

    Parameters
    ----------
    section : list of (float, float, float)
        ``read_static_polar``'s rows at one Reynolds number: (alpha deg, C_L, C_D).
    attached_normal : list of float
        The attached C_N at the same incidences (``steady_normal_force_coefficient``).

    Returns
    -------
    list of (float, float)
        (alpha deg, f) for every incidence above 0.
    """
    raw = []
    for (alpha, lift, drag), attached in zip(section, attached_normal):
        if alpha <= 0.0:
            continue
        ratio = max(section_normal_force_coefficient(alpha, lift, drag), 0.0) / attached
        raw.append((alpha, max(2.0 * math.sqrt(ratio) - 1.0, 0.0) ** 2))
    plateau = max(f for alpha, f in raw if alpha <= ATTACHED_UP_TO_DEG)
    return [(alpha, min(f / plateau, 1.0)) for alpha, f in raw]


def static_separation_fit(points: list[tuple[float, float]]) -> tuple[float, float]:
    """The separation's logistic (``separation.logistic_separation_point``), fitted to a polar's points.

    Least squares over the points up to ``SEPARATION_FIT_UP_TO_DEG``, on a grid of 0.05 deg in the onset a_f and
    0.05 deg in the width w (0.05-3 deg).

    Parameters
    ----------
    points : list of (float, float)
        (alpha deg, f), ``static_separation_points``'s output.

    Returns
    -------
    (float, float)
        ``TrailingEdgeSeparation``'s ``onset_rad`` and ``width_rad``.
    """
    used = [(math.radians(alpha), f) for alpha, f in points if alpha <= SEPARATION_FIT_UP_TO_DEG]
    alpha = np.array([a for a, _ in used])
    measured = np.array([f for _, f in used])
    onsets = np.radians(np.arange(0.5, SEPARATION_FIT_UP_TO_DEG, 0.05))[:, None, None]
    widths = np.radians(np.arange(0.05, 3.0001, 0.05))[None, :, None]
    model = logistic_separation_point(np.sin(alpha) ** 2, onsets, widths)
    error = np.sum((model - measured) ** 2, axis=-1)
    i, j = np.unravel_index(int(np.argmin(error)), error.shape)
    return float(onsets[i, 0, 0]), float(widths[0, j, 0])


def polar_separation(polar: dict[float, list[tuple[float, float, float]]],
                     reynolds: float = REYNOLDS) -> TrailingEdgeSeparation:
    """The section's trailing-edge separation at one of the polar's Reynolds numbers, its lags the default ones.

    Parameters
    ----------
    polar : dict
        ``read_static_polar``'s output.
    reynolds : float, optional
        One of its Reynolds numbers (default: the tank's).

    Returns
    -------
    TrailingEdgeSeparation
        Onset and width from ``static_separation_fit`` of ``static_separation_points`` against the reduced model's
        steady normal force at the polar's incidences.
    """
    section = polar[reynolds]
    attached = steady_normal_force_coefficient(tuple(alpha for alpha, _, _ in section))
    onset, width = static_separation_fit(static_separation_points(section, attached))
    return TrailingEdgeSeparation(onset, width)


def compute(strouhal: list[float], models: tuple[str, ...] = ("circulatory", "wake"),
            separation: TrailingEdgeSeparation | None = None) -> dict[str, dict[str, list[float]]]:
    """The towed-foil figures of Anderson's case for each flow model.

    Parameters
    ----------
    strouhal : list of float
        Strouhal numbers 2 h0 f / U to run.
    models : tuple of str, optional
        ``oscillating_foil``'s models.
    separation : TrailingEdgeSeparation, optional
        With it, the reduced model with the trailing edge separating too, as ``SEPARATED``.

    Returns
    -------
    dict of str to dict of str to list of float
        {model (or SEPARATED): {"strouhal", "thrust_coefficient", "efficiency", "power_coefficient",
        "heave_power_coefficient", "peak_angle_of_attack_deg", "peak_three_quarter_chord_incidence_deg",
        "peak_leading_edge_suction_parameter", "peak_free_stream_suction_parameter", "min_attached_weight"}}
        (OscillatingFoilResult's figures; the heave drive's power over 1/2 rho U^3 c s).
    """
    speed = TOWING_SPEED_M_S
    heave = HEAVE_OVER_CHORD * CHORD_M
    power_reference_w = 0.5 * WATER_DENSITY_KG_M3 * speed ** 3 * CHORD_M * SPAN_M   # C_P's 1/2 rho U^3 c s
    foil = JoukowskiFoil(CHORD_M, THICKNESS_RATIO * CHORD_M, SPAN_M)
    params = FlowParameters(profile_drag_coefficient=laminar_profile_drag_coefficient(REYNOLDS, THICKNESS_RATIO))
    runs = [(model, model, params) for model in models]
    if separation is not None:
        runs.append((SEPARATED, "circulatory", dataclasses.replace(params, separation=separation)))
    results: dict[str, dict[str, list[float]]] = {}
    for key, model, flow_parameters in runs:
        rows: dict[str, list[float]] = {name: [] for name in (
            "strouhal", "thrust_coefficient", "efficiency", "power_coefficient", "heave_power_coefficient",
            "peak_angle_of_attack_deg", "peak_three_quarter_chord_incidence_deg",
            "peak_leading_edge_suction_parameter", "peak_free_stream_suction_parameter", "min_attached_weight")}
        for st in strouhal:
            run = oscillating_foil(foil, speed_m_s=speed, heave_amplitude_m=heave,
                                   pitch_amplitude_rad=math.atan(math.pi * st) - math.radians(ALPHA0_DEG),
                                   frequency_hz=st * speed / (2.0 * heave), phase_rad=math.pi / 2,
                                   pivot_from_leading_edge_m=CHORD_M / 3, model=model,
                                   averaged_cycles=1 if model == "wake" else 2,
                                   water_density_kg_m3=WATER_DENSITY_KG_M3, flow_parameters=flow_parameters)
            for name, value in (
                    ("strouhal", st), ("thrust_coefficient", run.thrust_coefficient), ("efficiency", run.efficiency),
                    ("power_coefficient", run.power_coefficient),
                    ("heave_power_coefficient", float(np.mean(run.heave_power_w)) / power_reference_w),
                    ("peak_angle_of_attack_deg", math.degrees(run.peak_angle_of_attack_rad)),
                    ("peak_three_quarter_chord_incidence_deg",
                     math.degrees(run.peak_three_quarter_chord_incidence_rad)),
                    ("peak_leading_edge_suction_parameter", run.peak_leading_edge_suction_parameter),
                    ("peak_free_stream_suction_parameter", run.peak_free_stream_suction_parameter),
                    ("min_attached_weight", run.min_attached_weight)):
                rows[name].append(value)
        results[key] = rows
    return results


def plot(results: dict[str, dict[str, list[float]]], measured: dict[str, list[tuple[float, float]]] | None,
         path: Path, polar: dict[float, list[tuple[float, float, float]]] | None = None,
         separation: TrailingEdgeSeparation | None = None) -> None:
    """Draw thrust coefficient and efficiency against Strouhal number, models and tank, and the steady normal force.

    Parameters
    ----------
    results : dict
        ``compute``'s output.
    measured : dict or None
        ``read_measurements``'s output, or None without tank data.
    path : pathlib.Path
        The PNG file to write.
    polar : dict or None, optional
        ``read_static_polar``'s output, drawn beside the reduced model's and the flat plate's steady normal force.
    separation : TrailingEdgeSeparation, optional
        The separation of ``SEPARATED``, whose steady normal force is drawn too.
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(16, 4.5))
    styles = {"circulatory": ("tab:blue", "o-", "reduced model (swim_model.flow)"),
              "wake": ("tab:orange", "s--", "vortex wake (swim_model.wake) + profile drag"),
              SEPARATED: ("tab:green", "d-.", f"reduced model, trailing edge separating (Re {REYNOLDS:.0f} polar)")}
    for model, rows in results.items():
        colour, style, label = styles[model]
        axes[0].plot(rows["strouhal"], rows["thrust_coefficient"], style, color=colour, label=label)
        axes[1].plot(rows["strouhal"], rows["efficiency"], style, color=colour, label=label)
    if measured:
        for axis, quantity in zip(axes, ("thrust_coefficient", "efficiency")):
            points = np.array(measured.get(quantity, []))
            if points.size:
                axis.plot(points[:, 0], points[:, 1], "k^", label="Anderson et al. 1998 (tank)")
    axes[0].set(xlabel="Strouhal number 2 h0 f / U", ylabel="thrust coefficient T / (1/2 rho U^2 c s)",
                title="Thrust")
    axes[1].set(xlabel="Strouhal number 2 h0 f / U", ylabel="efficiency T U / P", title="Efficiency",
                ylim=(0.0, 1.0))
    angles = np.array(STEADY_ANGLES_DEG)
    axes[2].plot(angles, steady_normal_force_coefficient(), "-", color="tab:blue", label="reduced model, steady")
    if separation is not None:
        axes[2].plot(angles, steady_normal_force_coefficient(params=FlowParameters(profile_drag_coefficient=0.0,
                                                                                   separation=separation)),
                     "-.", color="tab:green", label="reduced model, steady, trailing edge separating")
    axes[2].plot(angles, FlowParameters().flat_plate_normal_force_coefficient * np.sin(np.radians(angles)), ":",
                 color="grey", label="flat plate, C_N90 sin(alpha)")
    for reynolds, marker in zip(POLAR_REYNOLDS, ("kv", "k^")):
        section = (polar or {}).get(reynolds, [])
        if section:
            axes[2].plot([row[0] for row in section], [section_normal_force_coefficient(*row) for row in section],
                         marker, markersize=4,
                         label=f"NACA 0012 static, Re {reynolds:.0f} (Sheldahl & Klimas 1981)")
    axes[2].set(xlabel="incidence, deg", ylabel="normal force coefficient N / (1/2 rho U^2 c s)",
                title="Steady normal force")
    for axis in axes:
        axis.grid(True, alpha=0.3)
        axis.legend(fontsize=8)
    fig.suptitle(f"Towed foil: h0/c = {HEAVE_OVER_CHORD}, alpha0 = {ALPHA0_DEG:g} deg, pitch leading heave by 90 deg, "
                 f"Re = {REYNOLDS:.0f}", fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def run(output_dir: Path, measurements: Path | None = None) -> Path:
    """Compute, write flow_comparison.png and flow_comparison.json into output_dir.

    Parameters
    ----------
    output_dir : pathlib.Path
        Where the files go.
    measurements : pathlib.Path, optional
        The tank data CSV (default: the tests' copy in the source tree).

    Returns
    -------
    pathlib.Path
        The figure's path.
    """
    source = measurements if measurements is not None else DEFAULT_MEASUREMENTS
    measured = read_measurements(source) if source.exists() else None
    if measured is None:
        print(f"swim-model-demo: no tank data at {source}: drawing the models only (--measurements CSV)")
        strouhal = list(np.round(np.linspace(0.1, 0.5, 9), 3))
    else:
        strouhal = [st for st, _ in measured["thrust_coefficient"]]
    polar_path = source.parent / STATIC_POLAR_NAME
    polar = read_static_polar(polar_path) if polar_path.exists() else None
    separation = polar_separation(polar) if polar is not None and REYNOLDS in polar else None
    results = compute(strouhal, separation=separation)
    output_dir.mkdir(parents=True, exist_ok=True)
    figure = output_dir / "flow_comparison.png"
    plot(results, measured, figure, polar, separation)
    (output_dir / "flow_comparison.json").write_text(json.dumps({"models": results, "measured": measured}, indent=2))
    return figure
