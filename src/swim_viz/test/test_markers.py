"""The planned and travelled paths: where eq. 40's geometry puts the platform and the foil, decimated as said."""
import math

import numpy as np
import pytest

from swim_model import load_rig
from swim_viz.frames import JointPositions
from swim_viz.markers import MAX_PLANNED_POINTS, TravelledPath, planned_paths

RIG = load_rig()


def test_planned_paths_of_a_constrained_plan():
    samples = 5000
    alpha = np.linspace(0.0, 1.0, samples)
    rows = np.column_stack([alpha, 0.3 * np.sin(alpha * 20), 0.2 * np.cos(alpha * 20)])
    lines = {line.namespace: line for line in planned_paths(RIG, ["alpha", "phi", "theta"], rows.ravel(), 0.43)}
    platform = lines["planned_platform"].points_m
    assert len(platform) <= MAX_PLANNED_POINTS
    np.testing.assert_allclose(platform[-1], (0.43 * math.cos(1.0), 0.43 * math.sin(1.0), 0.0), atol=1e-12)
    np.testing.assert_allclose(np.hypot(platform[:, 0], platform[:, 1]), 0.43, atol=1e-12)
    assert len(lines["planned_foil"].points_m) == len(platform)


def test_planned_paths_refuse_rows_that_do_not_fit():
    with pytest.raises(ValueError):
        planned_paths(RIG, ["alpha", "phi", "theta"], np.zeros(7), 0.43)
    with pytest.raises(ValueError):
        planned_paths(RIG, ["alpha", "phi"], np.zeros(8), 0.43)


def test_travelled_path_keeps_points_spacing_apart_and_the_latest_max_points():
    path = TravelledPath(RIG, spacing_m=0.01, max_points=5)
    kept = [path.add(JointPositions(a, 0.43, 0.0, 0.0)) for a in np.arange(0.0, 0.2, 0.001)]
    # the platform moves 0.43 mm per step, the foil (0.36 m out) 0.36 mm: a point every 24 steps of 0.001 rad
    assert kept[0] and sum(kept) == math.ceil(200 / 24)
    platform = path.lines()[0].points_m
    assert len(platform) == 5
    np.testing.assert_allclose(np.hypot(platform[:, 0], platform[:, 1]), 0.43, atol=1e-12)
    path.clear()
    assert all(len(line.points_m) == 0 for line in path.lines())
