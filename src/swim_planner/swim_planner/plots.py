"""Figures of a primitive like the paper's Figs. 3-8 and 13-16."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from swim_planner.primitives import Primitive


def plot_primitive(primitive: Primitive, path: Path) -> None:
    """Displacement and velocity, heave and pitch, their phase portrait, and the torques."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    spec = primitive.spec
    t = primitive.time_s
    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
    axes[0, 0].plot(t, primitive.q[:, 0], label="alpha (rad)")
    axes[0, 0].plot(t, primitive.qdot[:, 0], label="alphadot (rad/s)")
    if not spec.constrained:
        axes[0, 0].plot(t, primitive.q[:, 1] - spec.lane_radius_m, label="R - R_lane (m)")
    axes[0, 1].plot(t, np.degrees(primitive.q[:, -2]), label="heave phi")
    axes[0, 1].plot(t, np.degrees(primitive.q[:, -1]), label="pitch theta")
    axes[1, 0].plot(np.degrees(primitive.q[:, -2]), np.degrees(primitive.q[:, -1]))
    axes[1, 0].plot(np.degrees(primitive.q[0, -2]), np.degrees(primitive.q[0, -1]), "o", label="start")
    axes[1, 1].plot(t, primitive.torque[:, 0], label="heave")
    axes[1, 1].plot(t, primitive.torque[:, 1], label="pitch")
    axes[0, 0].set(xlabel="time (s)", title="Displacement and velocity")
    axes[0, 1].set(xlabel="time (s)", ylabel="deg", title="Heave and pitch")
    axes[1, 0].set(xlabel="heave phi (deg)", ylabel="pitch theta (deg)", title="Heave-pitch phase portrait")
    axes[1, 1].set(xlabel="time (s)", ylabel="N m", title="Torques")
    for axis in axes.flat:
        axis.grid(True, alpha=0.3)
        axis.legend(fontsize=8)
    fig.suptitle(f"{spec.primitive_id}  (J = {primitive.index_j:.4f})")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
