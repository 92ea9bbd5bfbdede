"""The rig's frames against eq. 40's geometry written out here, and the joint_states parsing."""
import math

import numpy as np
import pytest

from swim_model import load_rig
from swim_viz.frames import (
    FOIL_FRAME,
    TANK_FRAME,
    JointPositions,
    fixed_transforms,
    moving_transforms,
    planar_poses,
    positions_from_names,
    rig_joints,
)

RIG = load_rig()


def foil_point_eq40(alpha, radius, phi, theta):
    """F = (R - Ld) e_r(alpha) + Lh dir(alpha + phi) + Lf dir(alpha + theta), dir(b) = (-sin b, cos b)."""
    ld, lh, lf = RIG.heave_pivot_inset_m, RIG.heave_link_length_m, RIG.pitch_axis_to_foil_reference_m
    return ((radius - ld) * math.cos(alpha) - lh * math.sin(alpha + phi) - lf * math.sin(alpha + theta),
            (radius - ld) * math.sin(alpha) + lh * math.cos(alpha + phi) + lf * math.cos(alpha + theta))


def compose(transforms):
    """Each child's 4x4 pose in the tank, from the transforms' quaternions and translations (parents first)."""
    poses = {TANK_FRAME: np.eye(4)}
    for t in transforms:
        x, y, z, w = t.quaternion_xyzw()
        rotation = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                             [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                             [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
        local = np.eye(4)
        local[:3, :3], local[:3, 3] = rotation, t.translation_m
        poses[t.child] = poses[t.parent] @ local
    return poses


@pytest.mark.parametrize("q", [(0.0, 0.43, 0.0, 0.0), (0.3, 0.43, 0.2, -0.4), (-2.5, 0.6, -0.7, 1.1)])
def test_composed_transforms_put_the_foil_where_eq40_does(q):
    transforms = moving_transforms(RIG, JointPositions(*q)) + fixed_transforms(RIG)
    foil = compose(transforms)[FOIL_FRAME]
    np.testing.assert_allclose(foil[:3, 3], (*foil_point_eq40(*q), 0.0), atol=1e-12)
    # x along the chord toward the leading edge: dir(alpha + theta)
    chord = (-math.sin(q[0] + q[3]), math.cos(q[0] + q[3]), 0.0)
    np.testing.assert_allclose(foil[:3, 0], chord, atol=1e-12)
    poses = planar_poses(RIG, JointPositions(*q))
    np.testing.assert_allclose(poses[FOIL_FRAME][:2], foil_point_eq40(*q), atol=1e-12)
    np.testing.assert_allclose(poses["platform"][:2], (q[1] * math.cos(q[0]), q[1] * math.sin(q[0])), atol=1e-12)


def test_planar_poses_take_arrays_of_samples():
    alpha, phi, theta = np.linspace(0, 1, 5), np.linspace(-0.5, 0.5, 5), np.linspace(0.2, -0.2, 5)
    x, y, yaw = planar_poses(RIG, JointPositions(alpha, np.full(5, 0.43), phi, theta))[FOIL_FRAME]
    expected = np.array([foil_point_eq40(a, 0.43, p, t) for a, p, t in zip(alpha, phi, theta)])
    np.testing.assert_allclose(np.column_stack([x, y]), expected, atol=1e-12)
    np.testing.assert_allclose(yaw, alpha + theta + 0.5 * math.pi, atol=1e-12)


def test_every_frame_has_one_parent_and_the_tree_is_rooted_in_the_tank():
    joints = rig_joints(RIG)
    children = [j.child for j in joints]
    assert len(set(children)) == len(children) and TANK_FRAME not in children
    known = {TANK_FRAME}
    for joint in joints:
        assert joint.parent in known
        known.add(joint.child)


def test_positions_from_names_any_order_and_the_constrained_lane():
    q = positions_from_names(["theta", "phi", "alpha"], [0.3, 0.2, 0.1], 0.43)
    assert (q.alpha_rad, q.radius_m, q.phi_rad, q.theta_rad) == (0.1, 0.43, 0.2, 0.3)
    q = positions_from_names(["alpha", "R", "phi", "theta"], [[0.1, 0.5, 0.2, 0.3], [0.2, 0.6, 0.3, 0.4]], 0.43)
    np.testing.assert_array_equal(q.radius_m, [0.5, 0.6])


@pytest.mark.parametrize("names, values", [(["alpha", "phi"], [0.0, 0.0]), (["alpha", "phi", "phi"], [0, 0, 0]),
                                           (["alpha", "phi", "theta"], [0.0, 0.0]),
                                           (["alpha", "phi", "theta"], [0.0, math.nan, 0.0])])
def test_positions_from_names_refuses_what_does_not_fit(names, values):
    with pytest.raises(ValueError):
        positions_from_names(names, values, 0.43)
