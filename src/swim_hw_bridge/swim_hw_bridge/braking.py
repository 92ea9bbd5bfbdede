"""What each motor can do to its link and what the rig's own motion does to it, from the rig's model.

This is what the braking rule of the safety layer (safety.py, rule 6) counts on.

For a joint j driven by torque tau_j, the link's acceleration from tau_j alone is tau_j (M^-1)_jj, and for a
symmetric positive definite M, (M^-1)_jj >= 1 / M_jj. So the largest diagonal entry of the free vehicle's
joint-space inertia over the joints' ranges (both joints' ranges and both lanes gridded) gives a deceleration the
motor can always produce: a = BRAKING_TORQUE_FRACTION tau_max / max M_jj; the most it can accelerate the link is
the largest tau_max (M^-1)_jj over the same grid. The rest of
    qddot = M^-1 (B tau - Cm(q, qdot) qdot)
is the other motor's torque through the off-diagonal inertia (within the quarter of the torque the fraction
leaves) and the velocity terms -(M^-1 Cm qdot)_j, evaluated at each period's state (VelocityTerms).
"""
from __future__ import annotations

import itertools

import numpy as np

from swim_hw_bridge.safety import BRAKING_TORQUE_FRACTION, JointDynamicsBounds
from swim_model import RigParameters, VehicleModel

#: grid points per joint range when searching the largest inertia (M varies smoothly with the joint angles)
GRID_POINTS = 13


class VelocityTerms:
    """The (heave, pitch) accelerations of the velocity terms, -(M^-1 Cm(q, qdot) qdot)_j, rad/s^2.

    They are the free vehicle's forward dynamics at zero torque, through its native entry point (microseconds a
    call, so the I/O loop can ask every period; its buffers are its own: one calling thread).
    """

    def __init__(self, model: VehicleModel) -> None:
        self._forward = model.native_function("forward_dynamics")

    def __call__(self, positions: tuple[float, float, float, float],
                 rates: tuple[float, float, float, float]) -> tuple[float, float]:
        """The (heave, pitch) velocity-term accelerations, rad/s^2, at (q, qdot) of the four coordinates."""
        forward = self._forward
        forward.inputs[0][:], forward.inputs[1][:], forward.inputs[2][:] = positions, rates, 0.0
        forward()
        return float(forward.outputs[0][2]), float(forward.outputs[0][3])


def joint_dynamics_bounds(rig: RigParameters, fraction: float = BRAKING_TORQUE_FRACTION) -> JointDynamicsBounds:
    """What the rig's motors surely give and give at most, and the velocity terms (module docstring).

    The (heave, pitch) decelerations the motors (the rig's torque limits) surely give and the accelerations they
    give at most between the hard stops, rad/s^2.
    """
    model = VehicleModel(rig, constrained=False)
    heave = np.linspace(*rig.hard_limits_rad[0], GRID_POINTS)
    pitch = np.linspace(*rig.hard_limits_rad[1], GRID_POINTS)
    largest_inertia, largest_mobility = np.zeros(2), np.zeros(2)
    for radius, phi, theta in itertools.product((rig.lane_1_radius_m, rig.lane_2_radius_m), heave, pitch):
        mass = model.mass_matrix([0.0, radius, phi, theta])
        largest_inertia = np.maximum(largest_inertia, np.diag(mass)[2:4])
        largest_mobility = np.maximum(largest_mobility, np.diag(np.linalg.inv(mass))[2:4])
    torque = np.asarray(rig.torque_limits_n_m, dtype=float)
    decelerations = fraction * torque / largest_inertia
    accelerations = torque * largest_mobility
    return JointDynamicsBounds(decelerations_rad_s2=(float(decelerations[0]), float(decelerations[1])),
                               drive_accelerations_rad_s2=(float(accelerations[0]), float(accelerations[1])),
                               velocity_terms=VelocityTerms(model))
