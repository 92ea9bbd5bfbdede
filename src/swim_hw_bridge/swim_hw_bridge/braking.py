"""The deceleration each motor can surely give its link, from the rig's model: what the braking bound of the
safety layer (safety.py, rule 6) counts on.

For a joint j driven by torque tau, the link's acceleration from tau alone is tau (M^-1)_jj, and for a symmetric
positive definite M, (M^-1)_jj >= 1 / M_jj. So the largest diagonal entry of the free vehicle's joint-space
inertia over the joint's range (both joints' ranges and both lanes gridded) gives a deceleration the motor can
always produce: a = BRAKING_TORQUE_FRACTION tau_max / max M_jj. The most it can accelerate the link is the
largest tau_max (M^-1)_jj over the same grid.
"""
from __future__ import annotations

import itertools

import numpy as np
from swim_model import RigParameters, VehicleModel

from swim_hw_bridge.safety import BRAKING_TORQUE_FRACTION

#: grid points per joint range when searching the largest inertia (M varies smoothly with the joint angles)
GRID_POINTS = 13


def joint_accelerations(rig: RigParameters, hard_limits_rad: tuple[tuple[float, float], tuple[float, float]],
                        torque_limits_n_m: tuple[float, float], fraction: float = BRAKING_TORQUE_FRACTION
                        ) -> tuple[tuple[float, float], tuple[float, float]]:
    """((heave, pitch) decelerations the motors surely give, (heave, pitch) accelerations they give at most), in
    rad/s^2, over the hard limits' ranges."""
    model = VehicleModel(rig, constrained=False)
    heave = np.linspace(*hard_limits_rad[0], GRID_POINTS)
    pitch = np.linspace(*hard_limits_rad[1], GRID_POINTS)
    largest_inertia, largest_mobility = np.zeros(2), np.zeros(2)
    for radius, phi, theta in itertools.product((rig.lane_1_radius_m, rig.lane_2_radius_m), heave, pitch):
        mass = model.mass_matrix([0.0, radius, phi, theta])
        largest_inertia = np.maximum(largest_inertia, np.diag(mass)[2:4])
        largest_mobility = np.maximum(largest_mobility, np.diag(np.linalg.inv(mass))[2:4])
    torque = np.asarray(torque_limits_n_m, dtype=float)
    decelerations = fraction * torque / largest_inertia
    accelerations = torque * largest_mobility
    return (float(decelerations[0]), float(decelerations[1])), (float(accelerations[0]), float(accelerations[1]))
