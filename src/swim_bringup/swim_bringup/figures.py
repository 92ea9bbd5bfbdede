"""The figures of runs and experiments (matplotlib, Agg).

A run's desired and actual motion, a bag's joint motion, the experiments' two-norms over seeds. Each function takes what
the pure layer gives (run_record, analysis, experiments) and writes PNGs; save_figure is the one way a figure is written
(swim-maneuver's and wake_figure's too).
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from swim_bringup.analysis import platform_xy_m
from swim_bringup.experiments import NORMS, change_text
from swim_bringup.reports import ExperimentRow
from swim_bringup.run_record import JointSeries, RecordedBag


def pyplot() -> Any:
    """matplotlib.pyplot on the Agg backend (PNG files, no display)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def save_figure(figure: Any, path: Path) -> Path:
    """Lay the figure out tight, write it as a PNG at path (100 dpi), close it; returns path."""
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    pyplot().close(figure)
    return path


def write_joint_figure(joints: Mapping[str, JointSeries], path: Path) -> Path:
    """Each joint's position against log time, one panel per joint."""
    figure, axes = pyplot().subplots(max(len(joints), 1), 1, sharex=True,
                                     figsize=(8, 1.0 + 1.8 * max(len(joints), 1)), squeeze=False)
    for axis, (name, series) in zip(axes[:, 0], joints.items()):
        axis.plot(series.time_s, series.position)
        axis.set_ylabel(name)
    axes[-1, 0].set_xlabel("log time [s]")
    return save_figure(figure, path)


def write_run_figures(record: RecordedBag, output_dir: Path) -> list[Path]:
    """Write a run's figures into output_dir; their paths.

    Desired vs actual alpha and alphadot (Figs. 19-20 style), heave and pitch, the Cartesian path; with the vortex
    wake recorded, its last vortices over the path (wake.png). The record's run_error if it holds no run, its
    wake_error if the wake could not be read.
    """
    if record.run is None:
        assert record.run_error is not None, "a RecordedBag without run has its run_error"
        raise record.run_error
    run = record.run
    plt = pyplot()
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
    paths.append(save_figure(figure, output_dir / "displacement.png"))
    figure, axes = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
    for axis, column, name in ((axes[0], -2, "phi (heave)"), (axes[1], -1, "theta (pitch)")):
        axis.plot(run.time_s, run.q_reference[:, column], "--", label="desired")
        axis.plot(run.time_s, run.q[:, column], label="actual")
        axis.set_ylabel(f"{name} [rad]")
    axes[0].legend()
    axes[1].set_xlabel("plan time [s]")
    paths.append(save_figure(figure, output_dir / "heave_pitch.png"))
    figure, axis = plt.subplots(figsize=(6, 6))
    for q, style, label in ((run.q_reference, "--", "desired"), (run.q, "-", "actual")):
        xy = platform_xy_m(run, q)
        axis.plot(xy[:, 0], xy[:, 1], style, label=label)
    axis.set_aspect("equal")
    axis.set_xlabel("x [m]")
    axis.set_ylabel("y [m]")
    axis.legend()
    paths.append(save_figure(figure, output_dir / "cartesian_path.png"))
    if record.wake_error is not None:
        raise record.wake_error
    if record.wake is not None:   # a run in the vortex wake (sim_node's flow: wake): its last vortices over the path
        from swim_bringup.wake_figure import write_wake_figure
        from swim_model import load_rig
        wake = record.wake
        paths.append(write_wake_figure(output_dir / "wake.png", platform_xy_m(run, run.q),
                                       np.column_stack([wake.x_m, wake.y_m]), wake.circulations_m2_s,
                                       reference_xy_m=platform_xy_m(run, run.q_reference),
                                       tank_radius_m=0.5 * load_rig().tank_diameter_m))
    return paths


def write_errors_figure(rows: Sequence[ExperimentRow], path: Path) -> Path:
    """Draw the two-norms of every seed with and without sliding mode into path.

    The two-norms of every seed with and without sliding mode: one row of panels per experiment, one column per
    two-norm, each seed's pair joined by a line; the panel's title gives the mean change and its interval.
    """
    figure, axes = pyplot().subplots(max(len(rows), 1), len(NORMS),
                                     figsize=(4.0 * len(NORMS), 1.0 + 2.2 * len(rows)), squeeze=False)
    for axis_row, row in zip(axes, rows):
        for axis, name in zip(axis_row, NORMS):
            pair, seeds = row.per_seed.two_norms[name], row.per_seed.seeds
            for seed, on, off in zip(seeds, pair.sliding_on, pair.sliding_off):
                if on is not None and off is not None:
                    axis.plot([seed, seed], [off, on], color="0.7", linewidth=1)
            for side, marker, label in ((pair.sliding_on, "o", "with sliding"), (pair.sliding_off, "x", "without")):
                present = [(seed, value) for seed, value in zip(seeds, side) if value is not None]
                axis.plot([p[0] for p in present], [p[1] for p in present], marker, label=label)
            change = row.statistics[name].change
            title = f"{row.experiment}\n{name.split('_error')[0]}"
            if change is not None:
                title += f": {change_text(change)}"
            axis.set_title(title, fontsize=8)
            axis.set_xticks(seeds)
            axis.set_ylabel("two-norm [m s^0.5]", fontsize=8)
        axis_row[-1].legend(fontsize=7)
    for axis in axes[-1]:
        axis.set_xlabel("seed")
    return save_figure(figure, path)
