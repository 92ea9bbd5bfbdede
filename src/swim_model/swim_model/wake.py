"""A free-vortex wake behind the Joukowski foil: what the paper's ideal-flow model leaves out.

2-D inviscid flow around the foil of ``joukowski.py`` with point vortices, after Streitlien & Triantafyllou
(AIAA J. 1995) and the discrete-vortex methods of Katz & Plotkin, "Low-Speed Aerodynamics" (2nd ed. 2001),
Ch. 13. The closed forms are ``vortex_force.py``'s; this module holds the wake's state and its time step.

``Wake.step(dt, pose, velocity)`` convects the free vortices (Adams-Bashforth), moves the foil, reflects the
vortices it carried inside and absorbs those at the surface into the bound circulation, sheds one vortex by the
Kutta condition (relaxed to Kirchhoff's share when the trailing edge separates), returns the vortical force and
moment ``F_v = -dI_v/dt`` (the added-mass force stays the ideal model's: nothing is counted twice), with the
leading-edge suction beyond the critical LESP taken off, and amalgamates vortices above ``max_vortex_count``. Each
rule, with its sources, the viscous core growth and the assumptions: docs/wake_study.md, Sec. 1.2; the absorption:
docs/wake_near_surface.md.
"""
from __future__ import annotations

import cmath
import dataclasses
import math

import numpy as np
import numpy.typing as npt

from swim_model.errors import StateError
from swim_model.joukowski import JoukowskiFoil
from swim_model.leading_edge import (
    CRITICAL_LEADING_EDGE_SUCTION,
    SPEED_REGULARIZATION_M_S,
    SUCTION_CAP_EXPONENT,
    is_cap_exponent,
    smooth_cap,
)
from swim_model.separation import kirchhoff_share
from swim_model.vortex_force import CirclePlane, angular_impulse_from_terms, compiled, impulse_from_terms

Pose = tuple[float, float, float]        # x_m, y_m (frame origin in the tank frame), theta_rad (chord angle)
Velocity = tuple[float, float, float]    # U_m_s, V_m_s (origin velocity along the foil axes), Omega_rad_s

#: x = r_max^2 / (4 nu t) at the Lamb-Oseen vortex's largest speed: the root of (1 + 2 x) e^-x = 1
LAMB_OSEEN_PEAK_RADIUS2 = 1.2564312086261696
#: d(delta^2)/d(nu t) of a blob whose largest speed Gamma/(4 pi delta) is the Lamb-Oseen vortex's,
#: Gamma (1 - e^-x) / (2 pi r_max): delta^2 = x nu t / (1 - e^-x)^2 (docs/wake_study.md, Sec. 1.2)
LAMB_OSEEN_CORE_GROWTH = LAMB_OSEEN_PEAK_RADIUS2 / (1.0 - math.exp(-LAMB_OSEEN_PEAK_RADIUS2)) ** 2


def viscous_core_radius(core_radius_m: npt.NDArray[np.float64], kinematic_viscosity_m2_s: float,
                        dt_s: float) -> npt.NDArray[np.float64]:
    """The blob cores after dt_s of viscous diffusion, so that a vortex's largest speed stays a Lamb-Oseen vortex's.

    ``delta^2 + LAMB_OSEEN_CORE_GROWTH nu dt`` (docs/wake_study.md, Sec. 1.2, "Viscous core growth").

    Parameters
    ----------
    core_radius_m : ndarray
        The cores, m (any shape).
    kinematic_viscosity_m2_s : float
        nu, m^2/s.
    dt_s : float
        The diffusion time, s.

    Returns
    -------
    ndarray
        The grown cores, m, of core_radius_m's shape.
    """
    grown: npt.NDArray[np.float64] = np.sqrt(core_radius_m ** 2
                                             + LAMB_OSEEN_CORE_GROWTH * kinematic_viscosity_m2_s * dt_s)
    return grown


@compiled
def _merge_pair(positions_m: npt.NDArray[np.complex128], circulations_m2_s: npt.NDArray[np.float64],
                origin_m: complex, candidates: int, chord_m: float, opposite_sign_penalty: float) -> int:
    """I of the pair (i, i + 1), i + 1 < candidates, of least cost.

    The cost is separation / (distance from the foil frame's origin of the nearer one + chord), times
    opposite_sign_penalty for opposite signs (the first of equal costs).
    """
    best, best_cost = 0, math.inf
    for i in range(candidates - 1):
        separation = abs(positions_m[i + 1] - positions_m[i])
        distance = min(abs(positions_m[i + 1] - origin_m), abs(positions_m[i] - origin_m))
        cost = separation / (distance + chord_m)
        if circulations_m2_s[i + 1] * circulations_m2_s[i] < 0.0:
            cost *= opposite_sign_penalty
        if cost < best_cost:
            best, best_cost = i, cost
    return best


def compile_kernels() -> None:
    """Compile the wake's numba kernels into their on-disk cache, or load them from it.

    Steps a small wake through shedding, merging and the Kelvin statistics, so that a process stepping a wake
    afterwards starts at full speed. Compiling takes seconds (7 to 19 s on this 2-core host, by its load); loading
    the cache well under one. For an install step.
    """
    # any foil, motion and bound do: the kernels are compiled for the argument types only
    foil = JoukowskiFoil(chord_m=0.06, thickness_m=0.008, span_m=0.2)
    wake = Wake(foil, WakeParameters(max_vortex_count=4, protected_vortex_count=2))
    for n in range(1, 8):
        wake.step(0.008, (0.4, 0.001 * n, 1.6), (0.1, 0.01, 0.2))
    wake.total_circulation(8)


@dataclasses.dataclass(frozen=True)
class WakeParameters:
    """Numerical parameters of the wake; all assumed (the paper models no wake), each with its reason beside it.

    Attributes
    ----------
    rho_kg_m3 : float
        Water density, kg/m^3.
    core_radius_m : float
        Krasny blob radius of a new vortex in the physical plane, m.
    shed_distance_fraction : float
        A new vortex's distance behind the cusp as a fraction of the trailing edge's travel in the step.
    min_shed_distance_m : float
        Smallest distance of a new vortex behind the cusp, m.
    max_vortex_count : int or None
        Bound on the vortex count above which vortices are amalgamated; None: never merge.
    protected_vortex_count : int
        The newest vortices, never merged.
    opposite_sign_merge_penalty : float
        Cost factor of merging a pair of opposite signs.
    surface_absorption_gap_m : float
        A vortex closer than this to the circle (``|zeta| - r``, m) is absorbed into the bound circulation; 0: never.
    critical_leading_edge_suction : float or None
        LESP beyond which the leading edge's suction is lost; None: the attached flow's whole suction.
    suction_cap_exponent : int
        Order of the smooth cap, an even integer >= 2.
    speed_regularization_m_s : float
        eps in |u| = sqrt(U^2 + V^2 + eps^2), m/s.
    kinematic_viscosity_m2_s : float
        nu, by which each vortex's core grows with its age, m^2/s; 0: the inviscid wake.

    Raises
    ------
    StateError
        For a value outside its range (each check names the field).
    """

    rho_kg_m3: float = 998.2
    # assumed: fresh water at 20 C, as rig.yaml
    core_radius_m: float = 1.5e-3
    # assumed: Krasny blob radius, 2.5 % of the rig's 6 cm chord: smooths vortex-vortex encounters
    # (roll-up) without changing the far field; image and body terms stay exact
    shed_distance_fraction: float = 0.5
    # assumed: a vortex shed over one step sits at the centroid of the vorticity shed during the step,
    # half the distance the trailing edge moves through the fluid in that step (Katz & Plotkin, Ch. 13, use 0.2-0.3)
    min_shed_distance_m: float = 2.0e-4
    # assumed: keeps the new vortex off the cusp (F' = 0) when the trailing edge is nearly at rest
    max_vortex_count: int | None = 600
    # assumed: bound on the vortex count (cost grows as N^2); None: never merge. 600 (4.8 s of wake at one vortex
    # per 8 ms period) is where the closed loop in the wake stops changing with it: merged down to 300, a foil
    # circling the hub meets old vortices amalgamated into few strong ones, whose passes push the hub with up to
    # 5.6 N m and lose runs that at 600 and 1200 are tracked (docs/wake_study.md, "The vortex count")
    protected_vortex_count: int = 60
    # assumed: the newest vortices (the near wake, about one cycle of the paper's gaits at 8 ms) are never merged
    opposite_sign_merge_penalty: float = 10.0
    # assumed: merging vortices of opposite sign destroys their dipole; such pairs are merged last
    surface_absorption_gap_m: float = 1.5e-3
    # assumed: a vortex within one core radius (core_radius_m) of the circle, |zeta| - r, has its core on the
    # wall: its vorticity is in the boundary layer and it is absorbed into the bound circulation
    # (docs/wake_near_surface.md). Smaller than the gap of a vortex just shed at min_shed_distance_m behind the
    # cusp (1.8 mm on the rig's foil). 0: never absorb
    critical_leading_edge_suction: float | None = CRITICAL_LEADING_EDGE_SUCTION
    # the leading edge holds suction up to this leading-edge suction parameter, beyond it the suction is lost
    # (docs/wake_study.md, Sec. 1.2, "Leading-edge suction"); the reduced model's edge (swim_model.leading_edge).
    # None: the attached flow's whole suction
    suction_cap_exponent: int = SUCTION_CAP_EXPONENT
    # assumed: the order of the smooth cap LESP / (1 + (LESP/LESP_crit)^n)^(1/n) (swim_model.leading_edge)
    speed_regularization_m_s: float = SPEED_REGULARIZATION_M_S
    # assumed: eps in the speed |u| = sqrt(U^2 + V^2 + eps^2) (swim_model.leading_edge)
    kinematic_viscosity_m2_s: float = 0.0
    # the fluid's kinematic viscosity, by which each vortex's core grows with its age (docs/wake_study.md,
    # Sec. 1.2, "Viscous core growth"); water at 20 C: 1.0e-6. Assumed 0 by default: the inviscid wake, every
    # core core_radius_m for as long as the vortex lives, as the wake's checks against theory and the tank were
    # made

    def __post_init__(self) -> None:
        """Check every coefficient's range (the class's Raises)."""
        for name in ("rho_kg_m3", "core_radius_m", "shed_distance_fraction", "min_shed_distance_m"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise StateError(f"WakeParameters.{name} must be positive and finite, got {value!r}")
        if not (math.isfinite(self.kinematic_viscosity_m2_s) and self.kinematic_viscosity_m2_s >= 0.0):
            raise StateError("WakeParameters.kinematic_viscosity_m2_s must be finite and >= 0, "
                             f"got {self.kinematic_viscosity_m2_s!r}")
        if not (math.isfinite(self.surface_absorption_gap_m) and self.surface_absorption_gap_m >= 0.0):
            raise StateError("WakeParameters.surface_absorption_gap_m must be finite and >= 0, "
                             f"got {self.surface_absorption_gap_m!r}")
        critical = self.critical_leading_edge_suction
        if critical is not None and not (math.isfinite(critical) and critical > 0.0):
            raise StateError(f"WakeParameters.critical_leading_edge_suction must be positive or None, got {critical!r}")
        if not is_cap_exponent(self.suction_cap_exponent):
            raise StateError("WakeParameters.suction_cap_exponent must be an even integer >= 2")
        if not (math.isfinite(self.speed_regularization_m_s) and self.speed_regularization_m_s > 0.0):
            raise StateError("WakeParameters.speed_regularization_m_s must be positive and finite")
        if self.max_vortex_count is not None and self.max_vortex_count <= self.protected_vortex_count + 1:
            raise StateError("WakeParameters.max_vortex_count must exceed protected_vortex_count + 1")


@dataclasses.dataclass(frozen=True)
class WakeForce:
    """The vortical force and moment on the foil over one step, foil axes, for the whole span.

    Per metre of span: divide by the foil's span. Valid at the middle of the step.

    Attributes
    ----------
    fx_n : float
        Along the chord toward the leading edge (thrust when the foil swims forward), N.
    fy_n : float
        Normal to the chord, N.
    moment_n_m : float
        About the foil frame's origin (the map origin, the added mass's reference point), counter-clockwise, N m.
    time_s : float
        The middle of the step, s.
    """

    fx_n: float
    fy_n: float
    moment_n_m: float
    time_s: float


class Wake:
    """Point-vortex wake of one foil; call ``step`` once per control period.

    Parameters
    ----------
    foil : JoukowskiFoil
        The foil (a Joukowski section with zeta_c > 0).
    params : WakeParameters, optional
        Numerical parameters (default: WakeParameters()).
    """

    def __init__(self, foil: JoukowskiFoil, params: WakeParameters | None = None) -> None:
        self.foil = foil
        self.params = params or WakeParameters()
        self.plane = CirclePlane(foil.map)
        self.time_s = 0.0
        self.positions_m = np.zeros(0, dtype=complex)          # tank frame, X + iY
        self.circulations_m2_s = np.zeros(0)                   # counter-clockwise positive
        self.core_radii_m = np.zeros(0)                        # each vortex's blob core (viscous_core_radius)
        self._previous_velocities = np.zeros(0, dtype=complex)  # tank frame, at the previous step
        self._has_previous_velocity = np.zeros(0, dtype=bool)
        self._previous_dt_s = 0.0
        self._pose: Pose | None = None
        self._velocity: Velocity = (0.0, 0.0, 0.0)
        self._impulse = 0j          # tank frame, per metre of span
        self._angular_impulse = 0.0  # about the tank origin, per metre of span
        # at the current pose, for the current vortices (None: to be computed): their circle-plane positions and
        # their terms of the impulse sums (CirclePlane.impulse_terms), so that a step maps the vortices once and a
        # merge updates one term
        self._zeta: npt.NDArray[np.complex128] | None = None
        self._impulse_terms = np.zeros(0, dtype=complex)
        self._angular_terms = np.zeros(0)
        self._separation_point = 1.0   # f of the current step (Wake.step)
        self.reflected_count = 0
        self.merged_count = 0
        self.absorbed_count = 0
        self.absorbed_circulation_m2_s = 0.0  # sum of the absorbed vortices' circulations (now the foil's)

    # --- queries ------------------------------------------------------------------------------------------
    def vortex_count(self) -> int:
        """The number of free vortices.

        Returns
        -------
        int
            The count.
        """
        return int(self.circulations_m2_s.size)

    def shed_circulation(self) -> float:
        """Sum of the free vortices' circulations (minus the foil's bound circulation).

        Returns
        -------
        float
            m^2/s.
        """
        return float(np.sum(self.circulations_m2_s))

    def bound_circulation(self) -> float:
        """Circulation around the foil: the total circulation of the flow minus that of the free vortices.

        Returns
        -------
        float
            m^2/s.
        """
        return self.total_circulation() - self.shed_circulation()

    def total_circulation(self, samples: int = 256) -> float:
        """Circulation of the whole flow, measured on a contour enclosing foil and wake (Kelvin: zero).

        The trapezoidal rule on a circle twice the farthest vortex's radius: the error falls as 2^-samples
        (CirclePlane.far_field_circulation), so 64 already reach round-off.

        Parameters
        ----------
        samples : int, optional
            Points of the rule.

        Returns
        -------
        float
            m^2/s.
        """
        zeta = self._current_circle_plane_positions()
        return self.plane.far_field_circulation(zeta, self.circulations_m2_s, self._velocity, samples)

    def vortices_in_foil_frame(self) -> npt.NDArray[np.complex128]:
        """Free-vortex positions in the foil frame (for plots).

        Returns
        -------
        (N,) ndarray of complex
            z = x + iy, m; empty before the first step.
        """
        if self._pose is None:
            return np.zeros(0, dtype=complex)
        x, y, theta = self._pose
        unrotate: complex = np.exp(-1j * theta)
        return (self.positions_m - complex(x, y)) * unrotate

    def add_vortex(self, position_m: complex, circulation_m2_s: float) -> None:
        """Put a free vortex at a tank-frame position.

        An initial condition, not a shedding: the images take ``-circulation_m2_s`` into the bound circulation
        (Kelvin holds), and the impulse the next force is measured from is re-evaluated, so placing it exerts no
        force. Needs the foil's pose (one ``step`` first).

        Parameters
        ----------
        position_m : complex
            x + iy in the tank frame, m.
        circulation_m2_s : float
            Circulation, counter-clockwise, m^2/s.

        Raises
        ------
        StateError
            Before the first step, for a non-finite value, or for a position inside the foil.
        """
        if self._pose is None:
            raise StateError("Wake.add_vortex: step the wake once first, so the foil has a pose")
        position, gamma = complex(position_m), float(circulation_m2_s)
        if not (math.isfinite(position.real) and math.isfinite(position.imag) and math.isfinite(gamma)):
            raise StateError(f"Wake.add_vortex: position and circulation must be finite, got {position_m!r}, "
                             f"{circulation_m2_s!r}")
        x, y, theta = self._pose
        unrotate = complex(math.cos(theta), -math.sin(theta))
        zeta = self.plane.to_circle(np.array([(position - complex(x, y)) * unrotate]))
        if abs(zeta[0]) <= self.plane.r_m:
            raise StateError(f"Wake.add_vortex: {position_m!r} is inside the foil")
        self.positions_m = np.append(self.positions_m, position)
        self.circulations_m2_s = np.append(self.circulations_m2_s, gamma)
        self.core_radii_m = np.append(self.core_radii_m, self.params.core_radius_m)
        self._previous_velocities = np.append(self._previous_velocities, 0j)
        self._has_previous_velocity = np.append(self._has_previous_velocity, False)
        self._map_vortices(self._circle_plane_positions()[0])
        self._impulse, self._angular_impulse = self._impulses()

    # --- the step ----------------------------------------------------------------------------------------------
    def step(self, dt_s: float, pose: Pose, velocity: Velocity, separation_point: float = 1.0) -> WakeForce:
        """Advance by dt_s to the foil's new pose and velocity; return the vortical force over the step.

        The step's rules: docs/wake_study.md, Sec. 1.2. With the trailing edge separated (separation_point f below
        1), the step's vortex holds the bound circulation at Kirchhoff's share ((1 + sqrt f)/2)^2 of the attached
        flow's (``CirclePlane.separated_kutta_strength``), and the edge keeps sqrt f of its suction, as
        swim_model.flow's separation does (docs/flow_model.md, Sec. 6).

        Parameters
        ----------
        dt_s : float
            Step, s (> 0).
        pose : tuple of 3 floats
            (x m, y m, theta rad) of the foil frame in the tank frame at the end of the step.
        velocity : tuple of 3 floats
            (U m/s, V m/s, Omega rad/s) in foil axes at the end of the step.
        separation_point : float, optional
            f >= 0 of the trailing edge's separation at the end of the step (swim_model.separation; 1: attached,
            the Kutta condition; the reduced model's lagged f passes 1 a little where the speed falls).

        Returns
        -------
        WakeForce
            The vortical force and moment, valid at the middle of the step.

        Raises
        ------
        StateError
            For a step that is not positive, a non-finite pose or velocity, or a separation point that is not finite
            and >= 0; the wake is unchanged.
        """
        if not (math.isfinite(dt_s) and dt_s > 0.0):
            raise StateError(f"Wake.step: dt_s must be positive and finite, got {dt_s!r}")
        values = tuple(float(v) for v in (*pose, *velocity))
        if len(values) != 6 or not all(math.isfinite(v) for v in values):
            raise StateError(f"Wake.step: pose and velocity must be 3 finite numbers each, got {pose!r}, {velocity!r}")
        if not (math.isfinite(separation_point) and separation_point >= 0.0):
            raise StateError(f"Wake.step: separation_point must be finite and >= 0, got {separation_point!r}")
        self._separation_point = float(separation_point)
        new_pose: Pose = values[:3]
        new_velocity: Velocity = values[3:]
        old_pose = new_pose if self._pose is None else self._pose

        self._convect(dt_s)
        self._pose, self._velocity = new_pose, new_velocity
        self.time_s += dt_s
        self._shed(dt_s, self._absorb_at_surface(self._reflect_inside_foil()))

        impulse, angular_impulse = self._impulses()
        force_tank = -(impulse - self._impulse) / dt_s
        origin_mid = 0.5 * (complex(old_pose[0], old_pose[1]) + complex(new_pose[0], new_pose[1]))
        moment_origin = -(angular_impulse - self._angular_impulse) / dt_s
        moment = moment_origin - (origin_mid.conjugate() * force_tank).imag
        force_foil = force_tank * cmath.exp(-1j * 0.5 * (old_pose[2] + new_pose[2]))

        force_foil -= self._lost_suction()
        self._merge()
        self._impulse, self._angular_impulse = self._impulses()
        span = self.foil.span_m
        return WakeForce(fx_n=float(force_foil.real) * span, fy_n=float(force_foil.imag) * span,
                         moment_n_m=moment * span, time_s=self.time_s - 0.5 * dt_s)

    # --- internals ---------------------------------------------------------------------------------------------
    def _circle_plane_positions(self) -> tuple[npt.NDArray[np.complex128], complex]:
        """(zeta_k, rotation e^{i theta}) of the free vortices at the current pose, mapped anew."""
        if self._pose is None:
            return np.zeros(0, dtype=complex), 1.0 + 0j
        x, y, theta = self._pose
        rotation = complex(math.cos(theta), math.sin(theta))
        z = (self.positions_m - complex(x, y)) / rotation
        return self.plane.to_circle(z), rotation

    def _current_circle_plane_positions(self) -> npt.NDArray[np.complex128]:
        """zeta_k at the current pose: the step's, or mapped anew when there is none."""
        if self._zeta is None:
            return self._circle_plane_positions()[0]
        return self._zeta

    def _map_vortices(self, zeta: npt.NDArray[np.complex128]) -> None:
        """Keep zeta (the vortices' circle-plane positions at the current pose) and their impulse terms."""
        self._zeta = zeta
        self._impulse_terms, self._angular_terms = self.plane.impulse_terms(zeta, self.circulations_m2_s)

    def _rotation(self) -> complex:
        """e^{i theta} of the current pose."""
        theta = self._pose[2] if self._pose is not None else 0.0
        return complex(math.cos(theta), math.sin(theta))

    def _convect(self, dt_s: float) -> None:
        if self.positions_m.size == 0:
            return
        zeta = self._current_circle_plane_positions()
        velocities = self._rotation() * self.plane.vortex_velocities(zeta, self.circulations_m2_s, self._velocity,
                                                                     self.core_radii_m)
        increment = velocities.copy()
        if self._previous_dt_s > 0.0:
            ratio = dt_s / (2.0 * self._previous_dt_s)
            has = self._has_previous_velocity
            increment[has] += ratio * (velocities[has] - self._previous_velocities[has])
        self.positions_m = self.positions_m + dt_s * increment
        if self.params.kinematic_viscosity_m2_s > 0.0:
            self.core_radii_m = viscous_core_radius(self.core_radii_m, self.params.kinematic_viscosity_m2_s, dt_s)
        self._zeta = None   # the vortices moved
        self._previous_velocities = velocities
        self._has_previous_velocity = np.ones(velocities.size, dtype=bool)
        self._previous_dt_s = dt_s

    def _reflect_inside_foil(self) -> npt.NDArray[np.complex128]:
        """Mirror the vortices inside the circle to their image points; their circle-plane positions after it."""
        zeta, rotation = self._circle_plane_positions()
        inside = np.abs(zeta) < self.plane.r_m
        if not np.any(inside):
            return zeta
        self.reflected_count += int(np.count_nonzero(inside))
        mirrored = self.plane.image(zeta[inside])
        x, y, _ = self._pose  # type: ignore[misc]
        self.positions_m[inside] = complex(x, y) + rotation * self.plane.to_foil(mirrored)
        zeta[inside] = mirrored
        return zeta

    def _absorb_at_surface(self, zeta: npt.NDArray[np.complex128]) -> npt.NDArray[np.complex128]:
        """Remove the vortices over the surface closer to the circle than surface_absorption_gap_m.

        Over the surface: forward of the trailing edge. A vortex aft of it is in the wake, however near the cusp:
        one just shed there sits closer to the circle than the gap when the step is short.
        zeta holds the vortices' circle-plane positions; returns those of the vortices kept.
        """
        gap_m = self.params.surface_absorption_gap_m
        if gap_m == 0.0 or zeta.size == 0:
            return zeta
        absorbed = np.abs(zeta) - self.plane.r_m < gap_m
        if not np.any(absorbed):
            return zeta
        absorbed[absorbed] = self.plane.to_foil(zeta[absorbed]).real > self.plane.z_te.real   # over the surface
        if not np.any(absorbed):
            return zeta
        self.absorbed_count += int(np.count_nonzero(absorbed))
        self.absorbed_circulation_m2_s += float(np.sum(self.circulations_m2_s[absorbed]))
        keep = ~absorbed
        self.positions_m, self.circulations_m2_s = self.positions_m[keep], self.circulations_m2_s[keep]
        self.core_radii_m = self.core_radii_m[keep]
        self._previous_velocities = self._previous_velocities[keep]
        self._has_previous_velocity = self._has_previous_velocity[keep]
        return zeta[keep]

    def _shed(self, dt_s: float, zeta: npt.NDArray[np.complex128]) -> None:
        """Shed the step's vortex.

        Its strength is the Kutta condition's against the vortices at zeta, their circle-plane positions at the
        current pose, relaxed to Kirchhoff's share when the trailing edge separates; keeps the circle-plane
        positions and impulse terms of all (``_map_vortices``).
        """
        u, v, omega = self._velocity
        te_speed = abs(complex(u, v) + 1j * omega * self.plane.z_te)
        distance = max(self.params.shed_distance_fraction * te_speed * dt_s, self.params.min_shed_distance_m)
        zeta_new = complex(self.plane.to_circle(np.array([self.plane.z_te - distance]))[0])
        rotation = self._rotation()
        gamma = self.plane.separated_kutta_strength(zeta_new, zeta, self.circulations_m2_s, self._velocity,
                                                    kirchhoff_share(self._separation_point))
        x, y, _ = self._pose  # type: ignore[misc]
        position = complex(x, y) + rotation * (self.plane.z_te - distance)
        self.positions_m = np.append(self.positions_m, position)
        self.circulations_m2_s = np.append(self.circulations_m2_s, gamma)
        self.core_radii_m = np.append(self.core_radii_m, self.params.core_radius_m)
        self._previous_velocities = np.append(self._previous_velocities, 0j)
        self._has_previous_velocity = np.append(self._has_previous_velocity, False)
        # the new vortex mapped back from its tank-frame position, as every vortex is
        new = self.plane.to_circle((self.positions_m[-1:] - complex(x, y)) / rotation)
        self._map_vortices(np.append(zeta, new))

    def leading_edge_suction_parameter(self) -> float:
        """The flow's leading-edge suction parameter now, before the cap.

        A0 = q_LE / (4 |u|) (``CirclePlane.leading_edge_suction_parameter``; sin(alpha) in the steady Kutta flow),
        signed as the suction velocity of swim_model.flow.

        Returns
        -------
        float
            A0, dimensionless; NaN before the first step.
        """
        if self._pose is None:
            return math.nan
        _, known_le = self.plane.edge_potential_derivatives(self._current_circle_plane_positions(),
                                                            self.circulations_m2_s, self._velocity)
        return float(self.plane.leading_edge_suction_parameter(known_le, self._velocity, self._speed_m_s()))

    def _speed_m_s(self) -> float:
        """The foil's speed |u| = sqrt(U^2 + V^2 + eps^2) now, m/s (eps: speed_regularization_m_s)."""
        u, v, _ = self._velocity
        return math.sqrt(u * u + v * v + self.params.speed_regularization_m_s ** 2)

    def _lost_suction(self) -> float:
        """The leading-edge suction the edge cannot hold, per metre of span along the chord, N/m.

        The attached flow's 4 pi rho r (LESP |u|)^2 less sqrt f times the same with LESP capped at
        critical_leading_edge_suction as swim_model.flow caps it (0 when the parameter is None and f is 1).
        """
        critical = self.params.critical_leading_edge_suction
        kept_share = math.sqrt(self._separation_point)
        if critical is None and kept_share == 1.0:
            return 0.0
        speed = self._speed_m_s()
        lesp = self.leading_edge_suction_parameter()
        capped = lesp if critical is None else smooth_cap(lesp, critical, self.params.suction_cap_exponent)
        lost_squared = lesp * lesp - kept_share * capped * capped
        return float(4.0 * math.pi * self.params.rho_kg_m3 * self.plane.r_m * speed * speed * lost_squared)

    def _impulses(self) -> tuple[complex, float]:
        """(I_v in the tank frame, L_v about the tank origin), per metre of span, from the kept impulse terms."""
        rho = self.params.rho_kg_m3
        impulse = self._rotation() * impulse_from_terms(self._impulse_terms, rho)
        x, y, _ = self._pose  # type: ignore[misc]
        angular = angular_impulse_from_terms(self._angular_terms, rho) + (complex(x, -y) * impulse).imag
        return impulse, angular

    def _merge(self) -> None:
        limit = self.params.max_vortex_count
        if limit is None:
            return
        while self.circulations_m2_s.size > limit:
            self._merge_one_pair()

    def _merge_one_pair(self) -> None:
        z, gamma = self.positions_m, self.circulations_m2_s
        candidates = z.size - self.params.protected_vortex_count  # pairs (i, i+1) with i + 1 < candidates
        x, y, _ = self._pose  # type: ignore[misc]
        i = int(_merge_pair(z, gamma, complex(x, y), candidates, self.foil.chord_m,
                            self.params.opposite_sign_merge_penalty))
        weights = np.abs(gamma[i:i + 2])
        total_weight = float(np.sum(weights))
        share = weights / total_weight if total_weight > 0.0 else np.array([0.5, 0.5])
        z[i] = share[0] * z[i] + share[1] * z[i + 1]
        self._previous_velocities[i] = (share[0] * self._previous_velocities[i]
                                        + share[1] * self._previous_velocities[i + 1])
        self._has_previous_velocity[i] = self._has_previous_velocity[i] and self._has_previous_velocity[i + 1]
        gamma[i] = gamma[i] + gamma[i + 1]
        cores = self.core_radii_m
        if cores[i] != cores[i + 1]:   # the squared cores' mean by the centroid's weights (equal ones kept)
            cores[i] = math.sqrt(share[0] * cores[i] ** 2 + share[1] * cores[i + 1] ** 2)
        keep = np.ones(z.size, dtype=bool)
        keep[i + 1] = False
        self.positions_m, self.circulations_m2_s, self.core_radii_m = z[keep], gamma[keep], cores[keep]
        self._previous_velocities = self._previous_velocities[keep]
        self._has_previous_velocity = self._has_previous_velocity[keep]
        self.merged_count += 1
        # the merged vortex's circle-plane position and impulse terms; the others' are unchanged
        zeta = self._current_circle_plane_positions()[keep]
        merged = self.plane.to_circle((self.positions_m[i:i + 1] - complex(x, y)) / self._rotation())
        zeta[i] = merged[0]
        impulse_terms, angular_terms = self._impulse_terms[keep], self._angular_terms[keep]
        impulse_term, angular_term = self.plane.impulse_terms(merged, self.circulations_m2_s[i:i + 1])
        impulse_terms[i], angular_terms[i] = impulse_term[0], angular_term[0]
        self._zeta, self._impulse_terms, self._angular_terms = zeta, impulse_terms, angular_terms
