"""The free-vortex wake (swim_model.wake) as a generalized force on the simulated vehicle. No ROS.

What it adds. The plant's equations of motion already hold the ideal-flow (added-mass, Kirchhoff) force of the
foil through Mm = M + Q2' M_A Q2. ``Wake.step`` returns only what that leaves out, the vortical force
``F_v = -dI_v/dt`` of the shed vortices (swim_model.vortex_force), so adding it counts nothing twice:

    Mm qddot + Cm qdot = B tau + (disturbances) + Q_wake,     Q_wake = Q2(q)' (fx, fy, M_z).

Frames (checked by the tests against rigid-body statics). ``kinematics.py``'s foil frame and the wake's foil
axes are the same frame: origin at the Joukowski map origin F (the added mass's reference point, Lf from the
pitch axis), x along the chord toward the leading edge, y the chord rotated by +90 deg. The chord of
kinematics.py points along ``dir(alpha + theta) = (-sin, cos)(alpha + theta)``, so the chord angle the wake
takes in the tank frame is ``alpha + theta + pi/2``; its position is F(q) in the tank frame (origin on the hub
axis); its velocity ``(U, V, Omega) = Q2(q) qdot`` (eq. 40) at F along the same axes; the wake's moment is
about F, which is the point Q2's first two rows are taken at. By virtual work the generalized force is then
``Q2' (fx, fy, M_z)`` and its power ``Q_wake . qdot`` equals ``(fx, fy, M_z) . (U, V, Omega)``.

Timing (zero-order hold, once per control period). At the start of period k (time t_k, state q_k, qdot_k)
the wake is stepped from t_{k-1} to t_k with the foil's pose and velocity at t_k; the force it returns belongs
to the middle of [t_{k-1}, t_k] and is held over [t_k, t_{k+1}], like the torque: a lag of one period (8 ms,
2 to 4 degrees of phase at the paper's 0.7-1.2 Hz gaits). Why not once per RK4 substep: the wake is validated
(Wagner, Garrick: swim_model/test/test_wake.py) at steps of about a period; eight times as many steps would shed
eight times as many vortices (the merging bound reached in 0.3 s instead of 2.4 s) and cost eight times as
much, well under real time; and a force that changes inside the period would break the plant's one compiled
call per period. Shedding one vortex per period is the discretization the wake's validation used.

Force spikes. A vortex passing close to the foil, or one the step carried into the foil and the wake reflected
out, changes the vortical impulse fast. Vortex-vortex velocities are desingularized (Krasny blob,
``WakeParameters.core_radius_m``); what is left is clipped: the force vector's magnitude to ``force_limit_n`` and
the moment to ``moment_limit_n_m`` (both assumed, sized to the largest circulatory force the foil could carry,
see below), and each clipped period counted (``clipped_count``).

No random numbers: a run with the wake repeats bit for bit.
"""
from __future__ import annotations

import dataclasses
import math
from typing import cast

import casadi as ca
import numpy as np
import numpy.typing as npt

from swim_model import StateError, VehicleModel
from swim_model.kinematics import foil_reference_point
from swim_model.wake import Wake, WakeParameters

Array = npt.NDArray[np.float64]

CHORD_ANGLE_OFFSET_RAD = 0.5 * math.pi   # kinematics.py's chord dir(a) = (-sin a, cos a) is at angle a + pi/2

# The clip limits. The plans move the foil at up to 0.6 m/s (trailing edge, constrained maneuver); the largest
# circulatory force of thin-aerofoil theory, 2 pi (1/2 rho U^2 c s) (lift slope 2 pi, sin(angle of attack) = 1),
# is then 20 N with the rig's foil, acting within half a chord of F (0.6 N m). Twice that is taken as no longer a
# force of the flow but a point vortex inside the model's singular neighbourhood of the surface.
FORCE_LIMIT_N = 40.0         # assumed, see above
MOMENT_LIMIT_N_M = 1.2       # assumed: FORCE_LIMIT_N times half the 6 cm chord
# Kelvin's total circulation in the statistics, measured each period: the contour rule converges as 2^-samples,
# so 64 points reach round-off at a quarter of the default's cost (the default 256 cost more than the wake's step)
KELVIN_SAMPLES = 64


@dataclasses.dataclass(frozen=True)
class WakeCouplingParameters:
    """The wake's numerical parameters (swim_model.wake.WakeParameters) and the clip limits."""

    wake: WakeParameters = WakeParameters()
    force_limit_n: float = FORCE_LIMIT_N
    moment_limit_n_m: float = MOMENT_LIMIT_N_M

    def __post_init__(self) -> None:
        for name in ("force_limit_n", "moment_limit_n_m"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise StateError(f"WakeCouplingParameters.{name} must be positive and finite, got {value!r}")


@dataclasses.dataclass(frozen=True)
class WakeStatistics:
    """The wake after a period, for analysis (published by sim_node on ``wake_statistics``).

    ``foil_force`` (fx N, fy N, M_z N m) is the force held over the period (after the clip), foil axes at F;
    ``thrust_n`` its tank-frame component along the foil's direction of travel about the hub (``thrust_n``);
    ``generalized_force`` = Q2' foil_force, per coordinate of q (N m, or N on R).
    """

    time_s: float
    vortex_count: int
    shed_circulation_m2_s: float
    total_circulation_m2_s: float
    foil_force: tuple[float, float, float]
    thrust_n: float
    generalized_force: tuple[float, ...]
    clipped_count: int
    merged_count: int
    reflected_count: int


def _pose_function(model: VehicleModel) -> ca.Function:
    """q -> (x_F, y_F, chord angle alpha + theta + pi/2): the foil frame in the tank frame."""
    q = model.symbolic.q
    coords = model.coordinates(q)
    point = foil_reference_point(coords, model.rig)
    pose = ca.vertcat(point, coords.alpha + coords.theta + CHORD_ANGLE_OFFSET_RAD)
    return ca.Function("foil_pose", [q], [pose], ["q"], ["pose"])


class WakeCoupling:
    """The wake behind the vehicle's foil, stepped once per control period; returns the held generalized force."""

    def __init__(self, model: VehicleModel, params: WakeCouplingParameters = WakeCouplingParameters()) -> None:
        self.model, self.params = model, params
        self._wake_params = dataclasses.replace(params.wake, rho_kg_m3=model.rig.water_density_kg_m3)
        self._pose = _pose_function(model)
        self.reset()

    def reset(self) -> None:
        """A fresh wake: no vortices, counters at zero (the fluid at rest)."""
        self.wake = Wake(self.model.foil, self._wake_params)
        self.clipped_count = 0
        self.foil_force = np.zeros(3)
        self.generalized_force = np.zeros(self.model.nq)
        self._pose_now = (0.0, 0.0, 0.0)

    def foil_pose(self, q: Array) -> tuple[float, float, float]:
        """(x_m, y_m, chord angle rad) of the foil frame in the tank frame (the wake's pose)."""
        pose = np.asarray(self._pose(q), dtype=float).reshape(-1)
        return float(pose[0]), float(pose[1]), float(pose[2])

    def step(self, q: Array, qdot: Array, period_s: float) -> Array:
        """Step the wake to the state (q, qdot) at the start of a period; the generalized force to hold over it.

        Q = Q2(q)' clip(fx, fy, M_z): the vortical force of the period that just ended (module docstring: timing).
        """
        pose = np.asarray(self._pose(q), dtype=float).reshape(-1)
        q2 = self.model.foil_velocity_map(q)
        velocity = q2 @ np.asarray(qdot, dtype=float)
        force = self.wake.step(period_s, (pose[0], pose[1], pose[2]), (velocity[0], velocity[1], velocity[2]))
        self.foil_force = self._clipped(np.array([force.fx_n, force.fy_n, force.moment_n_m]))
        self.generalized_force = q2.T @ self.foil_force   # virtual work: Q . qdot = foil_force . (U, V, Omega)
        self._pose_now = (float(pose[0]), float(pose[1]), float(pose[2]))
        return self.generalized_force

    def to_generalized(self, q: Array, foil_force: Array) -> Array:
        """Q = Q2(q)' (fx, fy, M_z): a force in foil axes at F and a moment about F as a generalized force."""
        return self.model.foil_velocity_map(q).T @ np.asarray(foil_force, dtype=float)

    def _clipped(self, force: Array) -> Array:
        """The force's magnitude to force_limit_n (direction kept) and the moment to moment_limit_n_m; counted."""
        if not np.all(np.isfinite(force)):
            raise StateError(f"the wake's force is not finite: {force}")
        clipped = force.copy()
        magnitude = math.hypot(force[0], force[1])
        if magnitude > self.params.force_limit_n:
            clipped[:2] *= self.params.force_limit_n / magnitude
        clipped[2] = min(max(force[2], -self.params.moment_limit_n_m), self.params.moment_limit_n_m)
        if not np.array_equal(clipped, force):
            self.clipped_count += 1
        return clipped

    def thrust_n(self) -> float:
        """The held force's tank-frame component along e_t = z x F/|F|, the direction in which the foil moves when
        the whole vehicle turns about the hub (what propels it along alpha: Q_alpha = |F| thrust_n + M_z), N."""
        x, y, angle = self._pose_now
        radius = math.hypot(x, y)
        if radius == 0.0:
            return 0.0
        tank = complex(self.foil_force[0], self.foil_force[1]) * complex(math.cos(angle), math.sin(angle))
        return (x * tank.imag - y * tank.real) / radius

    def statistics(self) -> WakeStatistics:
        """The wake's statistics now (Kelvin's total circulation measured from the velocity field)."""
        wake = self.wake
        return WakeStatistics(
            time_s=wake.time_s, vortex_count=wake.vortex_count(), shed_circulation_m2_s=wake.shed_circulation(),
            total_circulation_m2_s=wake.total_circulation(KELVIN_SAMPLES),
            foil_force=cast(tuple[float, float, float], tuple(float(f) for f in self.foil_force)),
            thrust_n=self.thrust_n(),
            generalized_force=tuple(float(f) for f in self.generalized_force),
            clipped_count=self.clipped_count, merged_count=wake.merged_count, reflected_count=wake.reflected_count)


def parameter_defaults() -> dict[str, bool | int | float]:
    """sim_node's ``wake.*`` parameters and their defaults (``enabled`` off: the ideal-flow model alone).

    ``max_vortex_count`` 0 means never merge; the water density is the rig's.
    """
    wake = WakeParameters()
    return {"enabled": False, "core_radius_m": wake.core_radius_m,
            "shed_distance_fraction": wake.shed_distance_fraction, "min_shed_distance_m": wake.min_shed_distance_m,
            "max_vortex_count": wake.max_vortex_count or 0, "protected_vortex_count": wake.protected_vortex_count,
            "opposite_sign_merge_penalty": wake.opposite_sign_merge_penalty,
            "force_limit_n": FORCE_LIMIT_N, "moment_limit_n_m": MOMENT_LIMIT_N_M}


def parameters_from_values(values: dict[str, bool | int | float]) -> WakeCouplingParameters:
    """WakeCouplingParameters from sim_node's ``wake.*`` values (keys of parameter_defaults; StateError if bad)."""
    wake = WakeParameters(core_radius_m=float(values["core_radius_m"]),
                          shed_distance_fraction=float(values["shed_distance_fraction"]),
                          min_shed_distance_m=float(values["min_shed_distance_m"]),
                          max_vortex_count=int(values["max_vortex_count"]) or None,
                          protected_vortex_count=int(values["protected_vortex_count"]),
                          opposite_sign_merge_penalty=float(values["opposite_sign_merge_penalty"]))
    return WakeCouplingParameters(wake=wake, force_limit_n=float(values["force_limit_n"]),
                                  moment_limit_n_m=float(values["moment_limit_n_m"]))
