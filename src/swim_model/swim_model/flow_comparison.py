"""Thrust coefficient and efficiency against Strouhal number: the reduced flow model, the vortex wake and the tank.

The towed-foil experiment of Anderson, Streitlien, Barrett & Triantafyllou (J. Fluid Mech. 360, 1998): NACA 0012
(here the Joukowski section of the same chord and 12 % thickness), chord 0.10 m, span 0.60 m, pivot at c/3,
Re 40 000 in fresh water (0.4 m/s), h0/c = 0.75, nominal angle of attack 15 deg, pitch leading heave by 90 deg;
the same laminar profile drag for both models (flow.laminar_profile_drag_coefficient). The measurements are read
from the CSV that the tests use (src/swim_model/test/data/ in the source tree; ``--measurements`` for another).
"""
from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np

from swim_model.flow import (
    KINEMATIC_VISCOSITY_WATER_M2_S,
    FlowParameters,
    laminar_profile_drag_coefficient,
    oscillating_foil,
)
from swim_model.joukowski import JoukowskiFoil

CHORD_M, SPAN_M, THICKNESS_RATIO = 0.10, 0.60, 0.12
REYNOLDS = 40_000.0
WATER_DENSITY_KG_M3 = 998.2
HEAVE_OVER_CHORD = 0.75
ALPHA0_DEG = 15.0
DEFAULT_MEASUREMENTS = Path(__file__).resolve().parents[1] / "test" / "data" / "anderson1998_oscillating_foil.csv"


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
    rows = csv.DictReader(line for line in path.read_text().splitlines() if not line.startswith("#"))
    series: dict[str, list[tuple[float, float]]] = {}
    for row in rows:
        series.setdefault(row["quantity"], []).append((float(row["strouhal"]), float(row["value"])))
    return series


def compute(strouhal: list[float],
            models: tuple[str, ...] = ("circulatory", "wake")) -> dict[str, dict[str, list[float]]]:
    """The towed-foil figures of Anderson's case for each flow model.

    Parameters
    ----------
    strouhal : list of float
        Strouhal numbers 2 h0 f / U to run.
    models : tuple of str, optional
        ``oscillating_foil``'s models.

    Returns
    -------
    dict of str to dict of str to list of float
        {model: {"strouhal", "thrust_coefficient", "efficiency", "peak_angle_of_attack_deg",
        "peak_leading_edge_suction_parameter", "min_attached_weight"}} (OscillatingFoilResult's figures).
    """
    speed = REYNOLDS * KINEMATIC_VISCOSITY_WATER_M2_S / CHORD_M
    heave = HEAVE_OVER_CHORD * CHORD_M
    foil = JoukowskiFoil(CHORD_M, THICKNESS_RATIO * CHORD_M, SPAN_M)
    params = FlowParameters(profile_drag_coefficient=laminar_profile_drag_coefficient(REYNOLDS, THICKNESS_RATIO))
    results: dict[str, dict[str, list[float]]] = {}
    for model in models:
        rows: dict[str, list[float]] = {"strouhal": [], "thrust_coefficient": [], "efficiency": [],
                                 "peak_angle_of_attack_deg": [], "peak_leading_edge_suction_parameter": [],
                                 "min_attached_weight": []}
        for st in strouhal:
            run = oscillating_foil(foil, speed_m_s=speed, heave_amplitude_m=heave,
                                   pitch_amplitude_rad=math.atan(math.pi * st) - math.radians(ALPHA0_DEG),
                                   frequency_hz=st * speed / (2.0 * heave), phase_rad=math.pi / 2,
                                   pivot_from_leading_edge_m=CHORD_M / 3, model=model,
                                   averaged_cycles=1 if model == "wake" else 2,
                                   water_density_kg_m3=WATER_DENSITY_KG_M3, flow_parameters=params)
            rows["strouhal"].append(st)
            rows["thrust_coefficient"].append(run.thrust_coefficient)
            rows["efficiency"].append(run.efficiency)
            rows["peak_angle_of_attack_deg"].append(math.degrees(run.peak_angle_of_attack_rad))
            rows["peak_leading_edge_suction_parameter"].append(run.peak_leading_edge_suction_parameter)
            rows["min_attached_weight"].append(run.min_attached_weight)
        results[model] = rows
    return results


def plot(results: dict[str, dict[str, list[float]]], measured: dict[str, list[tuple[float, float]]] | None,
         path: Path) -> None:
    """Draw thrust coefficient and efficiency against Strouhal number, models and tank.

    Parameters
    ----------
    results : dict
        ``compute``'s output.
    measured : dict or None
        ``read_measurements``'s output, or None without tank data.
    path : pathlib.Path
        The PNG file to write.
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    styles = {"circulatory": ("tab:blue", "o-", "reduced model (swim_model.flow)"),
              "wake": ("tab:orange", "s--", "vortex wake (swim_model.wake) + profile drag")}
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
    results = compute(strouhal)
    output_dir.mkdir(parents=True, exist_ok=True)
    figure = output_dir / "flow_comparison.png"
    plot(results, measured, figure)
    (output_dir / "flow_comparison.json").write_text(json.dumps({"models": results, "measured": measured}, indent=2))
    return figure
