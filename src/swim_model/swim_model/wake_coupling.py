"""The free-vortex wake as a generalized force on a simulated vehicle, and the separation drag it lacks.

swim_model.wake's vortical force, and the flat-plate separation drag the wake lacks. No ROS.

The plant's equations of motion already hold the added-mass force through Mm = M + Q2' M_A Q2; ``Wake.step``
returns only the vortical force ``F_v = -dI_v/dt``, so adding it counts nothing twice:

    Mm qddot + Cm qdot = B tau + (disturbances) + Q_wake,     Q_wake = Q2(q)' (fx, fy, M_z).

The wake is stepped once per control period and its force held over the next (docs/wake_study.md, Sec. 2,
"Timing"), clipped to force_limit_n and moment_limit_n_m ("Limits"). The frames, the separation drag and the
flows a simulated vehicle swims in (swim_model.flow's ``FLOWS``): docs/wake_study.md, Sec. 2.1. No random
numbers: a run with the wake repeats bit for bit.
"""
from __future__ import annotations

import dataclasses
import math
from typing import cast

import casadi as ca
import numpy as np
import numpy.typing as npt

from swim_model import codegen
from swim_model.errors import StateError
from swim_model.vehicle import VehicleModel
from swim_model.wake import Wake, WakeParameters

Array = npt.NDArray[np.float64]


# The clip limits. The plans move the foil at up to 0.6 m/s (trailing edge, constrained maneuver); the largest
# circulatory force of thin-aerofoil theory, 2 pi (1/2 rho U^2 c s) (lift slope 2 pi, sin(angle of attack) = 1),
# is then 20 N with the rig's foil, acting within half a chord of F (0.6 N m). Twice that is taken as no longer a
# force of the flow but a point vortex inside the model's singular neighbourhood of the surface.
FORCE_LIMIT_N = 40.0         # assumed, see above
MOMENT_LIMIT_N_M = 1.2       # assumed: FORCE_LIMIT_N times half the 6 cm chord
# Kelvin's total circulation in the statistics, measured each period: the contour rule converges as 2^-samples,
# so 64 points reach round-off at a quarter of the default's cost (the default 256 cost more than the wake's step)
KELVIN_SAMPLES = 64
#: the compiled function of the foil's pose and Q2, and its library's name (codegen adds the source's hash)
FOIL_KINEMATICS_NAME = "wake_foil_kinematics"


@dataclasses.dataclass(frozen=True)
class WakeCouplingParameters:
    """The wake's numerical parameters and the clip limits.

    Attributes
    ----------
    wake : WakeParameters
        The wake's numerical parameters (its density is replaced by the rig's).
    force_limit_n : float
        Largest magnitude of the held force (fx, fy), N.
    moment_limit_n_m : float
        Largest magnitude of the held moment, N m.

    Raises
    ------
    StateError
        For a limit that is not positive and finite.
    """

    wake: WakeParameters = WakeParameters()
    force_limit_n: float = FORCE_LIMIT_N
    moment_limit_n_m: float = MOMENT_LIMIT_N_M

    def __post_init__(self) -> None:
        """Check that both clip limits are positive and finite."""
        for name in ("force_limit_n", "moment_limit_n_m"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise StateError(f"WakeCouplingParameters.{name} must be positive and finite, got {value!r}")


@dataclasses.dataclass(frozen=True)
class WakeStatistics:
    """The wake after a period, for analysis (published by sim_node on ``wake_statistics``).

    Attributes
    ----------
    time_s : float
        The wake's time, s.
    vortex_count : int
        Free vortices.
    shed_circulation_m2_s : float
        Sum of the free vortices' circulations, m^2/s.
    total_circulation_m2_s : float
        Kelvin's total circulation measured from the velocity field, m^2/s.
    foil_force : tuple of 3 floats
        (fx N, fy N, M_z N m), the force held over the period (after the clip), foil axes at F.
    thrust_n : float
        Its tank-frame component along the foil's direction of travel about the hub, N.
    generalized_force : tuple of float
        Q2' foil_force, per coordinate of q (N m, or N on R).
    clipped_count, merged_count, reflected_count : int
        Periods clipped, vortex pairs merged, vortices reflected out of the foil.
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


@dataclasses.dataclass(frozen=True)
class WakeVortices:
    """The free vortices after a period (published by sim_node on ``wake_vortices``).

    Attributes
    ----------
    time_s : float
        The wake's time, s, as ``WakeStatistics.time_s``.
    positions_m : (N,) ndarray of complex
        x + iy in the tank frame, m, oldest first.
    circulations_m2_s : (N,) ndarray
        Circulations, counter-clockwise positive, m^2/s.
    trailing_edge_m : complex
        The trailing edge x + iy in the tank frame, m.
    """

    time_s: float
    positions_m: npt.NDArray[np.complex128]
    circulations_m2_s: Array
    trailing_edge_m: complex


class WakeCoupling:
    """The wake behind the vehicle's foil, stepped once per control period; returns the held generalized force.

    Parameters
    ----------
    model : VehicleModel
        The vehicle (its foil, rig density and kinematics).
    params : WakeCouplingParameters, optional
        The wake's parameters and the clip limits.
    """

    def __init__(self, model: VehicleModel, params: WakeCouplingParameters = WakeCouplingParameters()) -> None:
        self.model, self.params = model, params
        self._wake_params = dataclasses.replace(params.wake, rho_kg_m3=model.rig.water_density_kg_m3)
        # the foil's pose and Q2 in one call of compiled C (codegen.native: ~1 us where CasADi's Python call costs
        # ~45 us a function), once per period
        q = model.symbolic.q
        kinematics = ca.Function(FOIL_KINEMATICS_NAME, [q], [model.foil_pose_function()(q),
                                                              ca.densify(model.symbolic.functions["foil_velocity_map"](q))])
        self._kinematics = codegen.native([kinematics], tag=FOIL_KINEMATICS_NAME)[FOIL_KINEMATICS_NAME]
        self.reset()

    def reset(self) -> None:
        """A fresh wake: no vortices, counters at zero (the fluid at rest)."""
        self.wake = Wake(self.model.foil, self._wake_params)
        self.clipped_count = 0
        self.foil_force = np.zeros(3)
        self.generalized_force = np.zeros(self.model.nq)
        self._pose_now = (0.0, 0.0, 0.0)

    def foil_pose(self, q: Array) -> tuple[float, float, float]:
        """The foil frame's pose in the tank frame (the wake's pose).

        Parameters
        ----------
        q : (nq,) ndarray
            Configuration, rad and m.

        Returns
        -------
        tuple of 3 floats
            (x m, y m, chord angle rad).
        """
        return self._foil_kinematics(q)[0]

    def _foil_kinematics(self, q: Array) -> tuple[tuple[float, float, float], Array]:
        """(the foil's pose as foil_pose gives it, Q2(q) 3 x nq as VehicleModel.foil_velocity_map gives it)."""
        self._kinematics.inputs[0][:] = np.asarray(q, dtype=float).reshape(-1)
        self._kinematics()
        x_m, y_m, angle_rad = (float(value) for value in self._kinematics.outputs[0])
        q2: Array = self._kinematics.outputs[1].reshape((3, self.model.nq), order="F").copy()
        return (x_m, y_m, angle_rad), q2

    def step(self, q: Array, qdot: Array, period_s: float) -> Array:
        """Step the wake to the state at the start of a period; return the generalized force to hold over it.

        Q = Q2(q)' clip(fx, fy, M_z): the vortical force of the period that just ended (docs/wake_study.md, Sec. 2,
        "Timing").

        Parameters
        ----------
        q, qdot : (nq,) ndarray
            The state at the start of the period: configuration, rad and m, and velocity, rad/s and m/s.
        period_s : float
            The period just ended, s.

        Returns
        -------
        (nq,) ndarray
            Q, N m and N by coordinate.

        Raises
        ------
        StateError
            For a wake force that is not finite.
        """
        pose, q2 = self._foil_kinematics(q)
        velocity = q2 @ np.asarray(qdot, dtype=float)
        force = self.wake.step(period_s, pose, (velocity[0], velocity[1], velocity[2]))
        self.foil_force = self._clipped(np.array([force.fx_n, force.fy_n, force.moment_n_m]))
        self.generalized_force = q2.T @ self.foil_force   # virtual work: Q . qdot = foil_force . (U, V, Omega)
        self._pose_now = pose
        return self.generalized_force

    def to_generalized(self, q: Array, foil_force: Array) -> Array:
        """Q = Q2(q)' (fx, fy, M_z): a force in foil axes at F and a moment about F as a generalized force.

        Parameters
        ----------
        q : (nq,) ndarray
            Configuration, rad and m.
        foil_force : (3,) ndarray
            (fx N, fy N, M_z N m).

        Returns
        -------
        (nq,) ndarray
            Q, N m and N by coordinate.
        """
        generalized: Array = self._foil_kinematics(q)[1].T @ np.asarray(foil_force, dtype=float)
        return generalized

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
        """The held force's tank-frame component along the foil's direction of travel about the hub.

        e_t = z x F/|F|, the direction in which the foil moves when the whole vehicle turns about the hub (what propels
        it along alpha: Q_alpha = |F| thrust_n + M_z).

        Returns
        -------
        float
            N; 0 with the foil on the hub axis.
        """
        x, y, angle = self._pose_now
        radius = math.hypot(x, y)
        if radius == 0.0:
            return 0.0
        tank = complex(self.foil_force[0], self.foil_force[1]) * complex(math.cos(angle), math.sin(angle))
        return (x * tank.imag - y * tank.real) / radius

    def vortices(self) -> WakeVortices:
        """The free vortices now, tank frame, and the trailing edge they are shed from.

        Returns
        -------
        WakeVortices
            Copies of the positions and circulations.
        """
        wake = self.wake
        x, y, angle = self._pose_now
        edge = complex(x, y) + complex(math.cos(angle), math.sin(angle)) * wake.plane.z_te
        return WakeVortices(time_s=wake.time_s, positions_m=wake.positions_m.copy(),
                            circulations_m2_s=wake.circulations_m2_s.copy(), trailing_edge_m=edge)

    def statistics(self) -> WakeStatistics:
        """The wake's statistics now (Kelvin's total circulation measured from the velocity field).

        Returns
        -------
        WakeStatistics
            The statistics.
        """
        wake = self.wake
        return WakeStatistics(
            time_s=wake.time_s, vortex_count=wake.vortex_count(), shed_circulation_m2_s=wake.shed_circulation(),
            total_circulation_m2_s=wake.total_circulation(KELVIN_SAMPLES),
            foil_force=cast(tuple[float, float, float], tuple(float(f) for f in self.foil_force)),
            thrust_n=self.thrust_n(),
            generalized_force=tuple(float(f) for f in self.generalized_force),
            clipped_count=self.clipped_count, merged_count=wake.merged_count, reflected_count=wake.reflected_count)


def separation_drag(foil_velocity: ca.SX, factors: ca.SX) -> ca.SX:
    """The foil's quadratic drag in foil axes at F: (-k_U |U| U, -k_V |V| V, 0).

    Parameters
    ----------
    foil_velocity : (3,) casadi.SX
        (U m/s, V m/s, Omega rad/s) = Q2 qdot.
    factors : (2,) casadi.SX
        (k_U, k_V) = 1/2 rho Cd A on the chordwise and normal velocities, kg/m.

    Returns
    -------
    (3,) casadi.SX
        (fx N, fy N, M_z N m).
    """
    u, v = foil_velocity[0], foil_velocity[1]
    return ca.vertcat(-factors[0] * ca.fabs(u) * u, -factors[1] * ca.fabs(v) * v, 0)
