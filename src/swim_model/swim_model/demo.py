"""Model demo: the foil's added mass, then a shape-driven swimming gait, with a plot.

Run as ``ros2 run swim_model swim-model-demo``. Prints the
Joukowski map and the added-mass coefficients of the rig's foil, simulates the constrained and the
free vehicle swimming with a sinusoidal heave/pitch gait (pitch leading heave by 90 deg) from zero
momentum, prints the distance covered, the mean speed and the torques the gait needs against the
motor limits, and saves a figure of the runs.

With ``--flow-comparison`` it draws instead the towed-foil comparison of swim_model.flow_comparison: thrust
coefficient and efficiency against Strouhal number from the reduced flow model, the vortex wake and Anderson et
al.'s tank (flow_comparison.png and .json; about a minute, most of it the wake).
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from swim_model import SinusoidalGait, SwimModelError, VehicleModel, load_rig, simulate_gait
from swim_model.gait import ShapeDrivenRun


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    """The command line of ``swim-model-demo``.

    Parameters
    ----------
    argv : list of str or None
        The arguments (None: sys.argv's).

    Returns
    -------
    argparse.Namespace
        The options.
    """
    parser = argparse.ArgumentParser(prog="swim-model-demo", description=__doc__.splitlines()[0])
    parser.add_argument("--rig", type=Path, default=None, help="rig parameter file (default: the shipped one)")
    parser.add_argument("--output-dir", type=Path, default=Path("runs/model-demo"), help="where the plot goes")
    parser.add_argument("--duration", type=float, default=10.0, help="simulated time, s")
    parser.add_argument("--frequency", type=float, default=1.0, help="gait frequency, Hz")
    parser.add_argument("--heave-amplitude", type=float, default=20.0, help="heave amplitude, deg")
    parser.add_argument("--pitch-amplitude", type=float, default=35.0, help="pitch amplitude, deg")
    parser.add_argument("--pitch-lead", type=float, default=90.0, help="phase of pitch ahead of heave, deg")
    parser.add_argument("--flow-comparison", action="store_true",
                        help="draw the towed-foil comparison of the flow models with the tank data instead")
    parser.add_argument("--measurements", type=Path, default=None,
                        help="tank data CSV for --flow-comparison (default: the tests' copy in the source tree)")
    return parser.parse_args(argv)


def summarize(model: VehicleModel, run: ShapeDrivenRun) -> dict[str, float]:
    """Distance, speed and torque figures of one run.

    Parameters
    ----------
    model : VehicleModel
        The vehicle the run used.
    run : ShapeDrivenRun
        The run.

    Returns
    -------
    dict of str to float
        The figures by name, SI units as their names say.
    """
    alpha = run.q[:, 0]
    radius = run.q[:, 1] if not model.constrained else np.full_like(alpha, model.lane_radius_m)
    duration = run.time_s[-1] - run.time_s[0]
    peak = np.abs(run.tau).max(axis=0)
    limits = model.torque_limits()
    return {
        "displacement_rad": float(alpha[-1] - alpha[0]),
        "arc_length_m": float(np.sum(0.5 * (radius[1:] + radius[:-1]) * np.diff(alpha))),
        "mean_speed_m_s": float(np.sum(0.5 * (radius[1:] + radius[:-1]) * np.diff(alpha)) / duration),
        "final_radius_m": float(radius[-1]),
        "peak_heave_torque_n_m": float(peak[0]),
        "peak_pitch_torque_n_m": float(peak[1]),
        "heave_torque_limit_n_m": float(limits[0]),
        "pitch_torque_limit_n_m": float(limits[1]),
        "within_torque_limits": bool(np.all(peak <= limits)),
    }


def plot(runs: dict[str, tuple[VehicleModel, ShapeDrivenRun]], path: Path) -> None:
    """Draw the runs' paths, speeds and torques.

    Parameters
    ----------
    runs : dict of str to (VehicleModel, ShapeDrivenRun)
        Each run with its model, by label.
    path : pathlib.Path
        The PNG file to write.
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
    for label, (model, run) in runs.items():
        radius = run.q[:, 1] if not model.constrained else np.full(len(run.time_s), model.lane_radius_m)
        axes[0, 0].plot(run.time_s, radius * run.q[:, 0], label=f"{label}: R alpha")
        axes[1, 0].plot(radius * np.cos(run.q[:, 0]), radius * np.sin(run.q[:, 0]), label=label)
        axes[1, 1].plot(run.time_s, run.tau[:, 0], label=f"{label}: heave")
        axes[1, 1].plot(run.time_s, run.tau[:, 1], "--", label=f"{label}: pitch")
    model, run = next(iter(runs.values()))
    axes[0, 1].plot(np.degrees(run.q[:, -2]), np.degrees(run.q[:, -1]))
    axes[0, 0].set(xlabel="time (s)", ylabel="longitudinal displacement (m)", title="Displacement")
    axes[0, 1].set(xlabel="heave phi (deg)", ylabel="pitch theta (deg)", title="Heave-pitch phase portrait")
    axes[1, 0].set(xlabel="x (m)", ylabel="y (m)", title="Path of the platform", aspect="equal")
    axes[1, 1].set(xlabel="time (s)", ylabel="torque (N m)", title="Torques the gait needs")
    for axis in axes.flat:
        axis.grid(True, alpha=0.3)
    for axis in (axes[0, 0], axes[1, 0], axes[1, 1]):
        axis.legend(fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    """Run ``swim-model-demo``: the added mass and a shape-driven gait, or the flow comparison.

    Parameters
    ----------
    argv : list of str, optional
        The arguments (default: sys.argv's).

    Returns
    -------
    int
        The exit status: 0, or 2 for a rig file or gait swim_model refuses.
    """
    args = parse_args(argv)
    if args.flow_comparison:
        from swim_model import flow_comparison
        print("Towed foil (Anderson et al. 1998): reduced flow model and vortex wake ...", flush=True)
        figure = flow_comparison.run(args.output_dir, args.measurements)
        print(f"Wrote {figure} and {figure.with_suffix('.json')}")
        return 0
    try:
        rig = load_rig(args.rig)
        gait = SinusoidalGait(heave_amplitude_rad=math.radians(args.heave_amplitude),
                              pitch_amplitude_rad=math.radians(args.pitch_amplitude),
                              frequency_hz=args.frequency, pitch_lead_rad=math.radians(args.pitch_lead))
        constrained = VehicleModel(rig, constrained=True)
    except SwimModelError as err:
        print(f"swim-model-demo: {err}", file=sys.stderr)
        return 2
    foil = constrained.foil
    per_span = foil.added_mass_per_span(rig.water_density_kg_m3)
    whole = constrained.added_mass
    print(f"Joukowski foil: chord {foil.chord_m} m, thickness {foil.thickness_m} m, span {foil.span_m} m")
    print(f"  map (eq. 1): a = {foil.map.a_m:.6f} m, zeta_c = {foil.map.zeta_c_m:.6f} m, r_c = {foil.map.r_c_m:.6f} m")
    print(f"  reference point: map origin, {foil.leading_edge_x_m * 1000:.2f} mm behind the leading edge;"
          " x toward the leading edge")
    print(f"Added mass (rho = {rig.water_density_kg_m3} kg/m^3)      per metre of span    whole span")
    for name, unit in (("m11", "kg"), ("m22", "kg"), ("m26", "kg m"), ("m66", "kg m^2")):
        print(f"  {name} ({unit:7s})                     {getattr(per_span, name):14.6e}  {getattr(whole, name):12.6e}")
    runs = {}
    summaries = {}
    for label, model in (("constrained", constrained), ("free", VehicleModel(rig, constrained=False))):
        print(f"Simulating the {label} vehicle for {args.duration:g} s ...", flush=True)
        run = simulate_gait(model, gait, args.duration)
        runs[label] = (model, run)
        summaries[label] = summarize(model, run)
    print(f"\nGait: heave {args.heave_amplitude:g} deg, pitch {args.pitch_amplitude:g} deg, "
          f"{args.frequency:g} Hz, pitch leads heave by {args.pitch_lead:g} deg")
    print(f"{'vehicle':12s} {'advance (m)':>12s} {'speed (m/s)':>12s} {'final R (m)':>12s} "
          f"{'heave tau (N m)':>16s} {'pitch tau (N m)':>16s}")
    for label, s in summaries.items():
        print(f"{label:12s} {s['arc_length_m']:12.4f} {s['mean_speed_m_s']:12.4f} {s['final_radius_m']:12.4f} "
              f"{s['peak_heave_torque_n_m']:8.3f} / {s['heave_torque_limit_n_m']:.3f} "
              f"{s['peak_pitch_torque_n_m']:8.3f} / {s['pitch_torque_limit_n_m']:.3f}")
    args.output_dir.mkdir(parents=True, exist_ok=True)
    figure = args.output_dir / "gait.png"
    plot(runs, figure)
    (args.output_dir / "summary.json").write_text(json.dumps(
        {"added_mass_whole_span": whole.__dict__, "added_mass_per_span": per_span.__dict__, "runs": summaries},
        indent=2))
    print(f"\nWrote {figure} and {args.output_dir / 'summary.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
