"""swim-analyze: the paper's measures of a recorded run (Sec. 7), a JSON report, figures, side-by-side tables.

From the tracking_state topic (reference and measured q each control period) and the plan:
- two-norms of the errors, ||e||_2 = sqrt(int e(t)^2 dt): longitudinal R_d (alpha - alpha_d) in m, lateral
  R - R_d in m, Cartesian |p - p_d| of the platform's position p = R (cos alpha, sin alpha) in m;
- the final lateral offset and final alpha error, the duration, peak |torque| per motor, the fraction of
  periods with a saturated motor, and the energy used, int (|tau_h phidot| + |tau_p thetadot|) dt in J (motors
  do not take energy back, so negative power is counted as spent too).
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path
from typing import Any, Mapping, Optional

import numpy as np

from swim_bringup.bag import read_messages
from swim_bringup.reports import BridgeMeasures, RunAnalysis, RunMeasures
from swim_controller.measures import two_norm


@dataclasses.dataclass
class Run:
    time_s: np.ndarray            # plan time of each tracked period
    q: np.ndarray                 # measured, (n, nq)
    qdot: np.ndarray
    q_reference: np.ndarray
    torque: np.ndarray            # commanded (heave, pitch), (n, 2)
    saturated: np.ndarray         # (n, 2) bool
    joint_names: list[str]
    lane_radius_m: float
    sliding_mode_enabled: bool


def load_run(bag_path: Path) -> Run:
    """The tracked periods of the last plan executed in the bag."""
    rows: list[Any] = []   # the tracking_state messages (the typestore's class)
    lane_radius_m = None
    for topic, _, message in read_messages(bag_path, ("tracking_state", "plan")):
        if topic == "plan":
            lane_radius_m = message.lane_radius_m
            continue
        if rows and message.plan_time_s < rows[-1].plan_time_s:
            rows = []   # a new plan started: keep the last one
        rows.append(message)
    if not rows:
        raise ValueError(f"{bag_path}: no tracking_state messages (was a plan executed while recording?)")
    if lane_radius_m is None and "R" not in rows[0].joint_names:
        raise ValueError(f"{bag_path}: no plan message: the constrained vehicle's lane radius, which turns its "
                         f"alpha errors into metres, is unknown")
    return Run(time_s=np.array([r.plan_time_s for r in rows]),
               q=np.array([r.feedback.positions for r in rows]),
               qdot=np.array([r.feedback.velocities for r in rows]),
               q_reference=np.array([r.reference.positions for r in rows]),
               torque=np.array([r.output_torques for r in rows]),
               saturated=np.array([r.torque_saturated for r in rows], dtype=bool),
               joint_names=list(rows[0].joint_names),
               lane_radius_m=float(lane_radius_m or 0.0),
               sliding_mode_enabled=bool(rows[-1].sliding_mode_enabled))


def _radius(run: Run, q: np.ndarray) -> np.ndarray:
    return q[:, run.joint_names.index("R")] if "R" in run.joint_names else np.full(len(q), run.lane_radius_m)


def measures(run: Run) -> RunMeasures:
    alpha = run.joint_names.index("alpha")
    radius, radius_reference = _radius(run, run.q), _radius(run, run.q_reference)
    alpha_error = run.q[:, alpha] - run.q_reference[:, alpha]
    position = radius[:, None] * np.column_stack([np.cos(run.q[:, alpha]), np.sin(run.q[:, alpha])])
    reference = radius_reference[:, None] * np.column_stack([np.cos(run.q_reference[:, alpha]),
                                                             np.sin(run.q_reference[:, alpha])])
    power = np.abs(run.torque * run.qdot[:, -2:]).sum(axis=1)
    return RunMeasures(
        duration_s=float(run.time_s[-1] - run.time_s[0]),
        longitudinal_error_two_norm_m_s05=two_norm(run.time_s, radius_reference * alpha_error),
        lateral_error_two_norm_m_s05=two_norm(run.time_s, radius - radius_reference),
        cartesian_error_two_norm_m_s05=two_norm(run.time_s, np.linalg.norm(position - reference, axis=1)),
        final_alpha_error_rad=float(alpha_error[-1]),
        final_lateral_offset_m=float(radius[-1] - radius_reference[-1]),
        peak_heave_torque_n_m=float(np.abs(run.torque[:, 0]).max()),
        peak_pitch_torque_n_m=float(np.abs(run.torque[:, 1]).max()),
        saturated_fraction=float(run.saturated.any(axis=1).mean()),
        energy_used_j=float(np.trapezoid(power, run.time_s)),
        sliding_mode_enabled=run.sliding_mode_enabled,
        periods=int(len(run.time_s)),
    )


def bridge_measures(bag_path: Path) -> Optional[BridgeMeasures]:
    """From a bridge_node's /diagnostics in the bag (None without any): the faults it latched during the run (a
    latched fault holds the motors at zero until reset: the vehicle did not swim as commanded from then on) and
    its count of overrun periods."""
    faults: set[str] = set()
    overruns = None
    for _, _, array in read_messages(bag_path, ("/diagnostics",)):
        for status in array.status:
            if status.name.endswith("bridge_node: I/O loop"):
                values = {pair.key: pair.value for pair in status.values}
                faults.update(name for name in values.get("faults", "NONE").split("|") if name != "NONE")
                overruns = int(values.get("overruns", overruns or 0))
    if overruns is None:
        return None
    return BridgeMeasures(bridge_faults="|".join(sorted(faults)) or "NONE", bridge_overruns=overruns)


def analyze(bag_path: Path) -> RunAnalysis:
    """The measures of the last plan tracked in the bag, and the bridge's if a bridge ran."""
    return RunAnalysis(measures(load_run(bag_path)), bridge_measures(bag_path))


def write_figures(bag_path: Path, output_dir: Path) -> list[Path]:
    """Desired vs actual alpha and alphadot (Figs. 19-20 style), heave and pitch, the Cartesian path."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    run = load_run(bag_path)
    output_dir.mkdir(parents=True, exist_ok=True)
    alpha = run.joint_names.index("alpha")
    paths = []
    figure, axes = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
    axes[0].plot(run.time_s, run.q_reference[:, alpha], "--", label="desired")
    axes[0].plot(run.time_s, run.q[:, alpha], label="actual")
    axes[0].set_ylabel("alpha [rad]")
    axes[0].legend()
    axes[1].plot(run.time_s, run.qdot[:, alpha], label="actual")
    axes[1].set_ylabel("alphadot [rad/s]")
    axes[1].set_xlabel("plan time [s]")
    paths.append(_save(figure, output_dir / "displacement.png"))
    figure, axes = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
    for axis, column, name in ((axes[0], -2, "phi (heave)"), (axes[1], -1, "theta (pitch)")):
        axis.plot(run.time_s, run.q_reference[:, column], "--", label="desired")
        axis.plot(run.time_s, run.q[:, column], label="actual")
        axis.set_ylabel(f"{name} [rad]")
    axes[0].legend()
    axes[1].set_xlabel("plan time [s]")
    paths.append(_save(figure, output_dir / "heave_pitch.png"))
    figure, axis = plt.subplots(figsize=(6, 6))
    for q, style, label in ((run.q_reference, "--", "desired"), (run.q, "-", "actual")):
        radius = _radius(run, q)
        axis.plot(radius * np.cos(q[:, alpha]), radius * np.sin(q[:, alpha]), style, label=label)
    axis.set_aspect("equal")
    axis.set_xlabel("x [m]")
    axis.set_ylabel("y [m]")
    axis.legend()
    paths.append(_save(figure, output_dir / "cartesian_path.png"))
    return paths


def _save(figure, path: Path) -> Path:
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    import matplotlib.pyplot as plt
    plt.close(figure)
    return path


def summary_table(reports: Mapping[str, RunAnalysis]) -> str:
    """The measures of several runs (a RunReport is one) side by side, one column per run; a measure that only
    some runs have (the bridge's) is blank for the others."""
    columns = [report.measure_values() for report in reports.values()]
    rows = list(dict.fromkeys(key for values in columns for key in values))
    width = max(len(r) for r in rows)
    lines = [" " * width + "".join(f"  {name[-22:]:>22}" for name in reports)]
    for row in rows:
        cells = "".join(f"  {_format(values.get(row, '')):>22}" for values in columns)
        lines.append(f"{row:<{width}}{cells}")
    return "\n".join(lines)


def _format(value) -> str:
    return f"{value:.4g}" if isinstance(value, float) else str(value)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="swim-analyze", description=__doc__.splitlines()[0])
    parser.add_argument("bags", type=Path, nargs="+", help="rosbag2 folders of runs (several: a side-by-side table)")
    parser.add_argument("--output", type=Path, default=None, help="folder for report.json and figures (one bag)")
    args = parser.parse_args(argv)
    try:
        # a run folder's bag is named for its folder
        reports = {(bag.parent.name if bag.name == "bag" else str(bag)): analyze(bag) for bag in args.bags}
    except (ValueError, OSError) as err:
        print(f"swim-analyze: {err}", file=sys.stderr)
        return 2
    print(summary_table(reports))
    if args.output is not None and len(args.bags) == 1:
        args.output.mkdir(parents=True, exist_ok=True)
        (args.output / "report.json").write_text(json.dumps(next(iter(reports.values())).to_json(), indent=2))
        write_figures(args.bags[0], args.output)
    return 0


if __name__ == "__main__":
    sys.exit(main())
