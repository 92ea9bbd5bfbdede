"""The vortex wake drawn over the vehicle's path.

Where the foil's shed vortices are, which way they turn and how strong they are, in the tank's plane (a run with
sim_node's flow = wake records them on wake_vortices).

Tank frame throughout: origin on the hub axis, the plane of the rails, x and y in m; circulations counter-clockwise
positive (swim_interfaces/WakeVortices). No ROS: arrays in, a PNG out.
"""
from __future__ import annotations

from pathlib import Path
from typing import Optional

import numpy as np
import numpy.typing as npt

from swim_bringup.figures import pyplot, save_figure

#: the marker area of the strongest vortex, pt^2; the others scale with |circulation| (area, so a vortex of half the
#: strength looks half as big). Chosen to stay readable with a thousand vortices on a 6-inch figure
LARGEST_MARKER_AREA_PT2 = 60.0
#: counter-clockwise (positive) and clockwise (negative) vortices: red and blue, the usual colours of signed vorticity
COUNTER_CLOCKWISE_COLOUR = "tab:red"
CLOCKWISE_COLOUR = "tab:blue"
#: the view around a tank: its radius times this, so the wall and a vortex just inside it stay in the frame
TANK_VIEW_MARGIN = 1.05


def marker_areas_pt2(circulations_m2_s: npt.ArrayLike) -> np.ndarray:
    """Marker area of each vortex, pt^2, shape (k,).

    LARGEST_MARKER_AREA_PT2 |Gamma| / max |Gamma| (zeros when every circulation is zero).
    """
    strength = np.abs(np.asarray(circulations_m2_s, dtype=float))
    largest = strength.max(initial=0.0)
    return np.zeros_like(strength) if largest == 0.0 else LARGEST_MARKER_AREA_PT2 * strength / largest


def marker_colours(circulations_m2_s: npt.ArrayLike) -> list[str]:
    """Colour of each vortex by the sign of its circulation (a zero one counts as counter-clockwise)."""
    return [CLOCKWISE_COLOUR if gamma < 0.0 else COUNTER_CLOCKWISE_COLOUR
            for gamma in np.asarray(circulations_m2_s, dtype=float)]


def _points(name: str, points: npt.ArrayLike) -> np.ndarray:
    array = np.asarray(points, dtype=float)
    if array.ndim != 2 or array.shape[1] != 2 or not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be an (n, 2) array of finite x, y in m, got shape {array.shape}")
    return array


def write_wake_figure(output_path: Path, path_xy_m: npt.ArrayLike, vortices_xy_m: npt.ArrayLike,
                      circulations_m2_s: npt.ArrayLike, reference_xy_m: Optional[npt.ArrayLike] = None,
                      tank_radius_m: Optional[float] = None) -> Path:
    """Draw the wake over the path and save it as a PNG at output_path; returns output_path.

    path_xy_m: (n, 2) the travelled path (the platform's or the foil's), m; vortices_xy_m: (k, 2) the vortices'
    positions and circulations_m2_s: (k,) their circulations, m^2/s, at one instant (the last wake_vortices message
    of a run, say); reference_xy_m: (m, 2) the planned path, dashed; tank_radius_m: the tank's wall, drawn, and
    the view held to the tank (the title counts the vortices outside it: an unbounded wake lets vortex pairs drift
    off).
    ValueError, and nothing written, for arrays of the wrong shape or with non-finite entries.
    """
    path = _points("path_xy_m", path_xy_m)
    vortices = _points("vortices_xy_m", np.reshape(vortices_xy_m, (-1, 2)))
    circulations = np.asarray(circulations_m2_s, dtype=float)
    if circulations.shape != (len(vortices),) or not np.all(np.isfinite(circulations)):
        raise ValueError(f"circulations_m2_s must hold one finite value per vortex ({len(vortices)}), got shape "
                         f"{circulations.shape}")
    reference = None if reference_xy_m is None else _points("reference_xy_m", reference_xy_m)
    figure, axis = pyplot().subplots(figsize=(6, 6))
    if tank_radius_m is not None:
        angle = np.linspace(0.0, 2.0 * np.pi, 361)
        axis.plot(tank_radius_m * np.cos(angle), tank_radius_m * np.sin(angle), color="0.6", linewidth=0.8,
                  label="tank wall")
    if reference is not None:
        axis.plot(reference[:, 0], reference[:, 1], "--", color="0.3", label="desired")
    axis.plot(path[:, 0], path[:, 1], color="k", linewidth=1.0, label="actual")
    colours, areas = marker_colours(circulations), marker_areas_pt2(circulations)
    axis.scatter(vortices[:, 0], vortices[:, 1], s=areas, c=colours, alpha=0.7, linewidths=0)
    for colour, label in ((COUNTER_CLOCKWISE_COLOUR, "vortex, counter-clockwise"),
                          (CLOCKWISE_COLOUR, "vortex, clockwise")):
        axis.scatter([], [], s=0.5 * LARGEST_MARKER_AREA_PT2, c=colour, label=label)   # legend entries only
    largest = np.abs(circulations).max(initial=0.0)
    title = f"vortex wake: {len(vortices)} vortices, area ~ |circulation| (largest {largest:.2g} m^2/s)"
    if tank_radius_m is not None:
        outside = int(np.count_nonzero(np.hypot(vortices[:, 0], vortices[:, 1]) > tank_radius_m))
        title += f"\n{outside} outside the tank, not shown" if outside else ""
        view_m = TANK_VIEW_MARGIN * tank_radius_m
        axis.set_xlim(-view_m, view_m)
        axis.set_ylim(-view_m, view_m)
    axis.set_title(title, fontsize="medium")
    axis.set_aspect("equal")
    axis.set_xlabel("x [m]")
    axis.set_ylabel("y [m]")
    axis.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=3, fontsize="small")
    output_path.parent.mkdir(parents=True, exist_ok=True)
    return save_figure(figure, output_path)
