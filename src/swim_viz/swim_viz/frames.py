"""The rig's frames (paper Fig. 33, the geometry of eq. 40): their tree, and their poses from the joint positions.

Frames, z up, every motion in the plane z = 0 of eq. 40, angles counter-clockwise about z:

- ``tank``: fixed, origin on the hub axis.
- ``hub_arm``: the rails, turned by alpha about the hub axis; x along the rails (e_r of kinematics.py).
- ``platform``: on the rails at R along hub_arm's x; origin at the platform's centre of mass.
- ``heave_link``: origin on the heave axis P, Ld (heave_pivot_inset) inward of the platform's origin, turned by
  phi from the platform; the link lies along its +y, so at phi = 0 it points the way alpha increases
  (dir(alpha + phi) of kinematics.py).
- ``pitch_axis``: origin on the pitch axis E at the link's end (Lh along heave_link's y), at the angle
  alpha + theta in the tank: theta - phi from the heave link, because the floating pulley sets theta relative
  to the platform, not to the link; its +y along the chord toward the leading edge.
- ``foil``: origin at the foil's reference point F (the Joukowski map origin), Lf along the chord from E;
  x along the chord toward the leading edge, y normal to it: the frame of eq. 40's U, V, Omega and of
  swim_model.joukowski.

So the foil frame sits at F = (R - Ld) e_r(alpha) + Lh dir(alpha + phi) + Lf dir(alpha + theta), turned by
alpha + theta + pi/2: swim_model.kinematics.foil_reference_point. One joint per frame below; the URDF
(swim_viz.urdf) and the transforms (rig_state_publisher) both come from rig_joints.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Sequence

import numpy as np
import numpy.typing as npt

from swim_model.rig import RigParameters

TANK_FRAME = "tank"
FOIL_FRAME = "foil"
#: the joint_states names of the rig's coordinates (the free vehicle's; the constrained one has no R)
JOINT_NAMES = ("alpha", "R", "phi", "theta")
FIXED, CONTINUOUS, PRISMATIC = "fixed", "continuous", "prismatic"   # URDF joint types: rotation about z, slide on x

FloatArray = npt.NDArray[np.float64]


@dataclasses.dataclass(frozen=True)
class JointPositions:
    """The rig's coordinates q = (alpha, R, phi, theta): rad, m, rad, rad.

    Each is a float, or all are arrays of samples of one shape.
    """

    alpha_rad: float | FloatArray
    radius_m: float | FloatArray
    phi_rad: float | FloatArray
    theta_rad: float | FloatArray


@dataclasses.dataclass(frozen=True)
class RigJoint:
    """One joint of the frame tree.

    The child's pose in the parent is the origin (translation, then yaw about z), then the joint's motion
    (CONTINUOUS: a rotation by its value about z; PRISMATIC: a slide by its value along x).
    """

    name: str
    parent: str
    child: str
    kind: str
    origin_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    origin_yaw_rad: float = 0.0


@dataclasses.dataclass(frozen=True)
class FrameTransform:
    """The pose of child in parent: translation (m) and a rotation by yaw_rad about z."""

    parent: str
    child: str
    translation_m: tuple[float, float, float]
    yaw_rad: float

    def quaternion_xyzw(self) -> tuple[float, float, float, float]:
        """The rotation as a unit quaternion (x, y, z, w)."""
        return (0.0, 0.0, math.sin(0.5 * self.yaw_rad), math.cos(0.5 * self.yaw_rad))


def rig_joints(rig: RigParameters) -> tuple[RigJoint, ...]:
    """The joints from the tank to the foil, parent before child (module docstring)."""
    return (
        RigJoint("hub", TANK_FRAME, "hub_arm", CONTINUOUS),
        RigJoint("rail", "hub_arm", "platform", PRISMATIC),
        RigJoint("heave", "platform", "heave_link", CONTINUOUS, (-rig.heave_pivot_inset_m, 0.0, 0.0)),
        RigJoint("pitch", "heave_link", "pitch_axis", CONTINUOUS, (0.0, rig.heave_link_length_m, 0.0)),
        RigJoint("foil_mount", "pitch_axis", FOIL_FRAME, FIXED, (0.0, rig.pitch_axis_to_foil_reference_m, 0.0),
                 0.5 * math.pi),
    )


def joint_values(q: JointPositions) -> dict[str, float | FloatArray]:
    """The value of each moving joint of rig_joints for the coordinates q: the pitch joint turns by theta - phi."""
    return {"hub": q.alpha_rad, "rail": q.radius_m, "heave": q.phi_rad, "pitch": q.theta_rad - q.phi_rad}


def _joint_motion(joint: RigJoint, value: float | FloatArray) -> tuple[float | FloatArray, float | FloatArray,
                                                                       float | FloatArray]:
    """(x m, y m, yaw rad) of joint.child in joint.parent at the joint value (a float or an array of them)."""
    x: float | FloatArray = joint.origin_m[0]
    y: float | FloatArray = joint.origin_m[1]
    if joint.kind == PRISMATIC:   # a slide along the child's x, which the origin's yaw turned
        x = x + math.cos(joint.origin_yaw_rad) * value
        y = y + math.sin(joint.origin_yaw_rad) * value
    return x, y, joint.origin_yaw_rad + (value if joint.kind == CONTINUOUS else 0.0)


def joint_transform(joint: RigJoint, value: float) -> FrameTransform:
    """The pose of joint.child in joint.parent at the joint value (rad or m; ignored for a fixed joint)."""
    x, y, yaw = _joint_motion(joint, value)
    return FrameTransform(joint.parent, joint.child, (float(x), float(y), joint.origin_m[2]), float(yaw))


def moving_transforms(rig: RigParameters, q: JointPositions) -> list[FrameTransform]:
    """The transforms of the moving joints (what /tf carries) at the coordinates q (floats)."""
    values = joint_values(q)
    return [joint_transform(joint, float(values[joint.name])) for joint in rig_joints(rig) if joint.kind != FIXED]


def fixed_transforms(rig: RigParameters) -> list[FrameTransform]:
    """The transforms of the fixed joints (what /tf_static carries)."""
    return [joint_transform(joint, 0.0) for joint in rig_joints(rig) if joint.kind == FIXED]


def planar_poses(rig: RigParameters, q: JointPositions) -> dict[str, tuple[FloatArray, FloatArray, FloatArray]]:
    """Every frame's pose in the tank, (x m, y m, yaw rad), each of q's shape.

    The joints are composed from the tank out (every origin of rig_joints is in the plane z = 0).
    """
    values = joint_values(q)
    shape = np.shape(q.alpha_rad)
    poses = {TANK_FRAME: (np.zeros(shape), np.zeros(shape), np.zeros(shape))}
    for joint in rig_joints(rig):
        x_parent, y_parent, yaw_parent = poses[joint.parent]
        x, y, yaw = _joint_motion(joint, np.asarray(values.get(joint.name, 0.0), dtype=float))
        cos_parent, sin_parent = np.cos(yaw_parent), np.sin(yaw_parent)
        poses[joint.child] = (x_parent + cos_parent * x - sin_parent * y,
                              y_parent + sin_parent * x + cos_parent * y, yaw_parent + yaw)
    return poses


def positions_from_names(names: Sequence[str], values: npt.ArrayLike, lane_radius_m: float) -> JointPositions:
    """JointPositions from coordinates named by JOINT_NAMES (any order).

    Without R, the rails are locked at lane_radius_m, m. values: one entry per name, or an (N, len(names)) array
    of N samples. Raises ValueError for unknown, repeated or missing names, a count that does not match, or a
    non-finite value.
    """
    names = list(names)
    required = [name for name in JOINT_NAMES if name != "R" or "R" in names]
    if sorted(names) != sorted(required):
        raise ValueError(f"joint names {names}: expected {list(JOINT_NAMES)} or {[n for n in JOINT_NAMES if n != 'R']}"
                         " (any order)")
    array = np.asarray(values, dtype=float)
    if array.shape[-1:] != (len(names),):
        raise ValueError(f"{array.shape[-1] if array.ndim else 0} values for the {len(names)} joints {names}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"non-finite joint position in {array.tolist() if array.ndim == 1 else 'the samples'}")
    columns = {name: array[..., i] for i, name in enumerate(names)}
    radius = columns["R"] if "R" in columns else np.full(array.shape[:-1], float(lane_radius_m))
    if array.ndim == 1:
        return JointPositions(float(columns["alpha"]), float(radius), float(columns["phi"]), float(columns["theta"]))
    return JointPositions(columns["alpha"], radius, columns["phi"], columns["theta"])
