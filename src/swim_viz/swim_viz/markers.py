"""What marker_node draws, without ROS: the planned and the travelled paths, as polylines in the tank frame.

The paths are those of the platform's centre and of the foil's reference point (tank frame: swim_viz.frames).

A path is the platform's origin R e_r(alpha) and the foil frame's origin F (eq. 40's geometry) over the samples of a
plan (swim_interfaces/PlannedTrajectory) or over the joint_states received.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Sequence

import numpy as np
import numpy.typing as npt

from swim_model.rig import RigParameters
from swim_viz.frames import FOIL_FRAME, TANK_FRAME, JointPositions, planar_poses, positions_from_names

#: the bodies whose paths are drawn: frame -> the marker's namespace suffix
TRACED_FRAMES = {"platform": "platform", FOIL_FRAME: "foil"}
#: a drawn plan keeps at most this many points per path (a 30 s plan at 8 ms has 3750): a line of a few thousand
#: points draws at once in RViz and Foxglove
MAX_PLANNED_POINTS = 2000
PLANNED_RGBA = (0.2, 0.6, 1.0, 1.0)
TRAVELLED_RGBA = (1.0, 0.5, 0.0, 1.0)
PATH_WIDTH_M = 0.004


@dataclasses.dataclass(frozen=True)
class PathLine:
    """One polyline to draw: its namespace, frame, points (N, 3) in m, colour (r, g, b, a in [0, 1]), width in m."""

    namespace: str
    frame_id: str
    points_m: npt.NDArray[np.float64]
    rgba: tuple[float, float, float, float]
    width_m: float = PATH_WIDTH_M


def traced_points(rig: RigParameters, q: JointPositions) -> dict[str, npt.NDArray[np.float64]]:
    """Namespace suffix -> the traced frames' origins in the tank, (N, 3) for N samples of q (z = 0)."""
    poses = planar_poses(rig, q)
    return {suffix: np.column_stack([np.atleast_1d(poses[frame][0]), np.atleast_1d(poses[frame][1]),
                                     np.zeros(np.size(poses[frame][0]))])
            for frame, suffix in TRACED_FRAMES.items()}


def planned_paths(rig: RigParameters, joint_names: Sequence[str], flat_positions: npt.ArrayLike,
                  lane_radius_m: float) -> list[PathLine]:
    """The paths of a plan, from its positions and joint names.

    The positions are N x nq, row-major, as PlannedTrajectory stores them; lane_radius_m serves a constrained plan
    (no R). At most MAX_PLANNED_POINTS points each, the last sample always kept. Raises ValueError for names or
    sizes that do not fit.
    """
    names = list(joint_names)
    flat = np.asarray(flat_positions, dtype=float)
    if not names or flat.size % len(names) or flat.size == 0:
        raise ValueError(f"{flat.size} positions do not make rows of the {len(names)} joints {names}")
    rows = flat.reshape(-1, len(names))
    stride = max(1, math.ceil(len(rows) / MAX_PLANNED_POINTS))
    kept = np.unique(np.append(np.arange(0, len(rows), stride), len(rows) - 1))
    points = traced_points(rig, positions_from_names(names, rows[kept], lane_radius_m))
    return [PathLine(f"planned_{suffix}", TANK_FRAME, xyz, PLANNED_RGBA) for suffix, xyz in points.items()]


class TravelledPath:
    """The paths travelled, from joint positions as they come.

    A point is kept when a traced frame has moved spacing_m from the last kept point, and the most recent
    max_points are kept.
    """

    def __init__(self, rig: RigParameters, spacing_m: float, max_points: int) -> None:
        if not (spacing_m >= 0.0 and max_points >= 2):
            raise ValueError(f"spacing_m must be >= 0 and max_points >= 2, got {spacing_m!r} and {max_points!r}")
        self.rig, self.spacing_m, self.max_points = rig, float(spacing_m), int(max_points)
        self._points: dict[str, list[tuple[float, float, float]]] = {suffix: [] for suffix in TRACED_FRAMES.values()}

    def clear(self) -> None:
        """Forget every kept point."""
        for points in self._points.values():
            points.clear()

    def add(self, q: JointPositions) -> bool:
        """Add the traced frames' origins at q (floats); whether a point was kept."""
        new = {suffix: (float(xyz[0, 0]), float(xyz[0, 1]), float(xyz[0, 2]))
               for suffix, xyz in traced_points(self.rig, q).items()}
        moved = any(not points or math.dist(points[-1], new[suffix]) >= self.spacing_m
                    for suffix, points in self._points.items())
        if not moved:
            return False
        for suffix, points in self._points.items():
            points.append(new[suffix])
            if len(points) > self.max_points:
                del points[: len(points) - self.max_points]
        return True

    def lines(self) -> list[PathLine]:
        """The travelled paths as polylines in the tank frame, one per traced frame."""
        return [PathLine(f"travelled_{suffix}", TANK_FRAME, np.array(points, dtype=float).reshape(-1, 3),
                         TRAVELLED_RGBA) for suffix, points in self._points.items()]
