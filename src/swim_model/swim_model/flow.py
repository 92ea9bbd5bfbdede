"""A reduced-order circulatory flow model of the foil.

Lift with Wagner's lag, leading-edge suction with a cap, profile drag and a smooth transition to the flat plate's
normal force past stall; with ``FlowParameters.separation``, the trailing edge's separation from a static polar
(swim_model.separation) too.
The ideal (paper's) model applies the added-mass force of Kirchhoff's equations (eq. 46, ``hydrodynamics.py``).
This module is the rest, the force the vortex wake would add (``wake.py``: ``F_v = -dI_v/dt``), as a generalized
force ``Q2(q)' f`` with ``f = (fx, fy, mz)`` in foil axes at the foil frame's origin F for the whole span; the
added mass stays in ``Mm`` and ``f`` holds no term in the accelerations (docs/flow_model.md, Sec. 1).

The terms, each with its source (Theodorsen's three-quarter chord, R. T. Jones's two-state Wagner lag, Garrick's
suction capped at Ramesh et al.'s critical LESP, the flat plate past stall, laminar profile drag), and why each is
what it is: docs/flow_model.md, Sec. 2; the coefficients: Sec. 3 (``FlowParameters``). Every speed is
``sqrt(... + eps^2)``, so the model is smooth everywhere, and every force and lag rate is homogeneous of degree 2
in (velocities, lag states), so time scaling (P3) holds to ``(eps/|u|)^2``.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from functools import cached_property
from typing import Any, Iterable, Union, overload

import casadi as ca
import numpy as np
import numpy.typing as npt

from swim_model.errors import FlowModelError
from swim_model.joukowski import AddedMass, JoukowskiFoil
from swim_model.leading_edge import (
    CRITICAL_LEADING_EDGE_SUCTION,
    SPEED_REGULARIZATION_M_S,
    SUCTION_CAP_EXPONENT,
    is_cap_exponent,
    smooth_cap,
)
from swim_model.separation import TrailingEdgeSeparation, kirchhoff_share, static_separation_point

Array = npt.NDArray[np.float64]

#: the Wagner lag states, m/s: every circulatory model has them
LAG_STATE_NAMES = ("wagner_lag_slow", "wagner_lag_fast")
#: the trailing-edge separation's lag states, m/s, after the Wagner ones when FlowParameters.separation is set:
#: the effective normal velocity lagged by the pressure lag, and the speed times the lagged separation point
SEPARATION_LAG_STATE_NAMES = ("separation_lag_normal_velocity", "separation_lag_point_speed")
#: the water a simulated vehicle swims in (swim_model.plant: the simulator's and the emulated rig's), each with the
#: VehicleModel flow model it integrates: "ideal" (the paper's added mass only), "circulatory" (this module's
#: force and lag states) and "wake" (the ideal model plus swim_model.wake_coupling's wake force and separation drag)
FLOWS = {"ideal": "ideal", "circulatory": "circulatory", "wake": "ideal"}
#: the flow models a VehicleModel (and a plan made with it) has: FLOWS' models
FLOW_MODELS = tuple(dict.fromkeys(FLOWS.values()))

KINEMATIC_VISCOSITY_WATER_M2_S = 1.0e-6
# fresh water at 20 C (1.00e-6 m^2/s; ITTC fresh water tables), the rig's water as rig.yaml's density


def laminar_profile_drag_coefficient(reynolds_number: float, thickness_ratio: float) -> float:
    """Zero-lift profile drag coefficient of a smooth section with a laminar boundary layer (per chord).

    ``C_D0 = 2 (1.328 / sqrt(Re)) (1 + 2 t/c + 60 (t/c)^4)``: Blasius's laminar skin friction on both sides times
    Hoerner's form factor for aerofoil sections. Chord Reynolds numbers of 1e4-1e5 (the rig, Anderson et al.'s tank)
    are below transition.

    Parameters
    ----------
    reynolds_number : float
        Chord Reynolds number U c / nu, > 0.
    thickness_ratio : float
        t/c, in [0, 0.5).

    Returns
    -------
    float
        C_D0, dimensionless (per chord and span).

    Raises
    ------
    FlowModelError
        For Re <= 0 or t/c outside [0, 0.5).

    References
    ----------
    Schlichting, Boundary-Layer Theory, Ch. 7; Hoerner, Fluid-Dynamic Drag (1965), Ch. 6, eq. 6.23.
    """
    if not (reynolds_number > 0.0 and 0.0 <= thickness_ratio < 0.5):
        raise FlowModelError(f"laminar_profile_drag_coefficient: needs Re > 0 and 0 <= t/c < 0.5, got "
                             f"{reynolds_number!r}, {thickness_ratio!r}")
    return 2.0 * 1.328 / math.sqrt(reynolds_number) * (1.0 + 2.0 * thickness_ratio + 60.0 * thickness_ratio ** 4)


@dataclasses.dataclass(frozen=True)
class FlowParameters:
    """Coefficients of the circulatory flow model, each with its source or the reason it was assumed.

    Sources and reasons beside each field and in docs/flow_model.md, Sec. 3.

    Attributes
    ----------
    wagner_slow_gain, wagner_slow_rate : float
        A1 and b1 of Jones's Wagner function (b1 per semichord travelled), dimensionless.
    wagner_fast_gain, wagner_fast_rate : float
        A2 and b2 of Jones's Wagner function, dimensionless.
    critical_leading_edge_suction : float
        LESP_crit, the leading-edge suction parameter where the suction saturates, dimensionless.
    suction_cap_exponent : int
        Order of the smooth saturation, an even integer >= 2.
    stall_angle_rad : float
        Lagged effective incidence where attached and separated flow weigh equally, rad.
    stall_width_rad : float
        Half-width of the attached-to-separated transition, rad.
    flat_plate_normal_force_coefficient : float
        C_N90 of the flat plate broadside past stall, dimensionless.
    profile_drag_coefficient : float
        C_D0 of the attached flow (``laminar_profile_drag_coefficient``), dimensionless.
    speed_regularization_m_s : float
        eps in sqrt(speed^2 + eps^2), m/s.
    separation : TrailingEdgeSeparation or None
        The trailing edge's separation from a static polar (swim_model.separation), with its two lag states; None:
        attached flow up to the stall.

    Raises
    ------
    FlowModelError
        For a rate, cap or width that is not positive, a negative gain or drag, gains summing to 1 or more, a stall
        range reaching 90 deg, or a cap exponent that is not an even integer >= 2.
    """

    wagner_slow_gain: float = 0.165
    wagner_slow_rate: float = 0.0455
    wagner_fast_gain: float = 0.335
    wagner_fast_rate: float = 0.3
    # R. T. Jones, NACA Report 681 (1940): phi(s) = 1 - 0.165 e^{-0.0455 s} - 0.335 e^{-0.3 s}, s in semichords
    critical_leading_edge_suction: float = CRITICAL_LEADING_EDGE_SUCTION
    # the edge's critical leading-edge suction parameter (swim_model.leading_edge: Ramesh et al., JFM 751, 2014)
    suction_cap_exponent: int = SUCTION_CAP_EXPONENT
    # assumed: the order of the smooth saturation (swim_model.leading_edge)
    stall_angle_rad: float = math.radians(25.0)
    # assumed: angle of the lagged effective incidence where attached and separated flow weigh equally; of the order
    # of the dynamic-stall lift peak of oscillating NACA 0012 sections (McCroskey, AGARD-CP-227, 1981: 20-25 deg
    # at reduced frequencies 0.05-0.15), above the 10-14 deg static stall
    stall_width_rad: float = math.radians(2.5)
    # assumed: half-width of the transition; the attached weight is 0.997 at 20 deg and 0.003 at 30 deg
    flat_plate_normal_force_coefficient: float = 1.98
    # Hoerner, Fluid-Dynamic Drag (1965), Ch. 3: two-dimensional flat plate normal to the flow, C_D = 1.98
    # (White, Fluid Mechanics, Table 7.2: 2.0); C_N = C_N90 sin(alpha) past stall (Fage & Johansen, Proc. R. Soc.
    # A 116, 1927)
    profile_drag_coefficient: float = 0.031
    # laminar_profile_drag_coefficient at the rig's chord Reynolds number 1.2e4 (0.2 m/s, 6 cm, 1.0e-6 m^2/s)
    # and thickness ratio 0.133: 0.0312
    speed_regularization_m_s: float = SPEED_REGULARIZATION_M_S
    # assumed: eps in sqrt(speed^2 + eps^2), smooth at rest (swim_model.leading_edge)
    separation: TrailingEdgeSeparation | None = None
    # None: the attached flow up to the stall; a section's separation (swim_model.separation, its onset from a static
    # polar: flow_comparison.static_separation_fit) adds it and its two lag states (docs/flow_model.md, Sec. 6)

    @property
    def separates(self) -> bool:
        """Whether the trailing edge separates (``separation`` set)."""
        return self.separation is not None

    def __post_init__(self) -> None:
        """Check every coefficient's range (the class's Raises)."""
        positive = ("wagner_slow_rate", "wagner_fast_rate", "critical_leading_edge_suction", "stall_angle_rad",
                    "stall_width_rad", "flat_plate_normal_force_coefficient", "speed_regularization_m_s")
        for name in positive:
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise FlowModelError(f"FlowParameters.{name} must be positive and finite, got {value!r}")
        for name in ("wagner_slow_gain", "wagner_fast_gain", "profile_drag_coefficient"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise FlowModelError(f"FlowParameters.{name} must be non-negative and finite, got {value!r}")
        if self.wagner_slow_gain + self.wagner_fast_gain >= 1.0:
            raise FlowModelError("FlowParameters: the Wagner gains must sum to less than 1 (phi(0) > 0)")
        if not self.stall_angle_rad + 2.0 * self.stall_width_rad < math.pi / 2:
            raise FlowModelError("FlowParameters: stall_angle_rad + 2 stall_width_rad must stay below 90 deg")
        if self.separation is not None and not isinstance(self.separation, TrailingEdgeSeparation):
            raise FlowModelError(f"FlowParameters.separation must be a TrailingEdgeSeparation or None, got "
                                 f"{self.separation!r}")
        if not is_cap_exponent(self.suction_cap_exponent):
            raise FlowModelError("FlowParameters.suction_cap_exponent must be an even integer >= 2")

    def digest(self) -> str:
        """SHA-256 of the values (compiled models are cached under it).

        Returns
        -------
        str
            Hex digest.
        """
        return hashlib.sha256(json.dumps({k: repr(v) for k, v in dataclasses.asdict(self).items()},
                                         sort_keys=True).encode()).hexdigest()


Symbolic = Union[ca.SX, ca.MX, ca.DM]


@overload
def angle_of_attack(u_m_s: float, v_m_s: float) -> float: ...
@overload
def angle_of_attack(u_m_s: Array, v_m_s: Array) -> Array: ...
@overload
def angle_of_attack(u_m_s: Symbolic, v_m_s: Symbolic | float) -> Symbolic: ...
@overload
def angle_of_attack(u_m_s: float, v_m_s: Symbolic) -> Symbolic: ...


def angle_of_attack(u_m_s: Any, v_m_s: Any) -> Any:
    """atan2(-V, U): the angle between the chord and the foil frame's motion (eq. 40's U, V in foil axes).

    Positive when the foil moves toward -y while moving forward (the flow meets it from below): the sign of the
    lift. Works on numbers, numpy arrays and CasADi expressions.

    Parameters
    ----------
    u_m_s : float, ndarray or casadi expression
        U, the velocity along the chord toward the leading edge, m/s.
    v_m_s : float, ndarray or casadi expression
        V, the velocity normal to the chord, m/s (same shape as ``u_m_s``).

    Returns
    -------
    float, ndarray or casadi expression
        The angle of attack, rad, of the inputs' kind and shape.
    """
    if isinstance(u_m_s, (ca.SX, ca.MX, ca.DM)) or isinstance(v_m_s, (ca.SX, ca.MX, ca.DM)):
        return ca.atan2(-v_m_s, u_m_s)
    return np.arctan2(-np.asarray(v_m_s, dtype=float), np.asarray(u_m_s, dtype=float))


@dataclasses.dataclass(frozen=True)
class FlowTerms:
    """The model's intermediate quantities as CasADi expressions (``CirculatoryFlow.terms``).

    Attributes
    ----------
    force : (3,) casadi.SX
        (fx N, fy N, mz N m) in foil axes at F, whole span.
    lag_rate : (n_lag,) casadi.SX
        dz/dt, m/s^2 (``CirculatoryFlow.lag_state_names``).
    normal_velocity : casadi.SX
        Q at the three-quarter chord, m/s.
    effective_normal_velocity : casadi.SX
        Q_eff (lagged), m/s.
    suction_parameter : casadi.SX
        Q_s / |u|, the leading-edge suction parameter before the cap, dimensionless.
    attached_weight : casadi.SX
        w in [0, 1]: 1 attached, 0 separated.
    circulation : casadi.SX
        Gamma, m^2/s.
    separation_point : casadi.SX
        f in [0, 1], the lagged trailing-edge separation point: 1 attached, 0 separated from the trailing edge to
        the leading edge (1 without separation).
    """

    force: ca.SX                # (fx, fy, mz): N, N, N m; foil axes at F, whole span
    lag_rate: ca.SX             # dz/dt, m/s^2
    normal_velocity: ca.SX      # Q at the three-quarter chord, m/s
    effective_normal_velocity: ca.SX  # Q_eff (lagged), m/s
    suction_parameter: ca.SX    # Q_s / |u| (the leading-edge suction parameter before the cap)
    attached_weight: ca.SX      # w in [0, 1]
    circulation: ca.SX          # Gamma, m^2/s
    separation_point: ca.SX     # f in [0, 1]


class CirculatoryFlow:
    """The circulatory flow model of one foil, as CasADi expressions and functions.

    Parameters
    ----------
    foil : JoukowskiFoil
        The foil (chord, thickness, span).
    rho_kg_m3 : float
        Water density, kg/m^3, > 0.
    params : FlowParameters, optional
        Coefficients (default: FlowParameters()).

    Raises
    ------
    FlowModelError
        For a density that is not positive and finite.

    References
    ----------
    docs/flow_model.md, Sec. 2.
    """

    def __init__(self, foil: JoukowskiFoil, rho_kg_m3: float, params: FlowParameters | None = None) -> None:
        if not (math.isfinite(rho_kg_m3) and rho_kg_m3 > 0.0):
            raise FlowModelError(f"CirculatoryFlow: rho_kg_m3 must be positive, got {rho_kg_m3!r}")
        self.foil = foil
        self.rho_kg_m3 = float(rho_kg_m3)
        self.params = params if params is not None else FlowParameters()
        self.lag_state_names: tuple[str, ...] = LAG_STATE_NAMES + (
            SEPARATION_LAG_STATE_NAMES if self.params.separates else ())
        self.lag_state_count = len(self.lag_state_names)
        m = foil.map
        self.chord_m = foil.leading_edge_x_m - foil.trailing_edge_x_m
        self.semichord_m = 0.5 * self.chord_m
        self.span_m = foil.span_m
        self.circle_radius_m = m.r_c_m
        self.leading_edge_x_m = foil.leading_edge_x_m
        self.mid_chord_x_m = 0.5 * (foil.leading_edge_x_m + foil.trailing_edge_x_m)
        self.three_quarter_chord_x_m = foil.leading_edge_x_m - 0.75 * self.chord_m
        self.vortical_lift_x_m = m.zeta_c_m                           # steady vortical lift acts here (wake.py)
        self.aerodynamic_centre_x_m = m.zeta_c_m + m.a_m ** 2 / m.r_c_m  # with the Munk moment
        self.added_mass: AddedMass = foil.added_mass(self.rho_kg_m3)

    # ----- the model ------------------------------------------------------------------------------------------
    def terms(self, velocity: ca.SX, lag: ca.SX) -> FlowTerms:
        """The model's expressions at one foil velocity and lag state.

        Parameters
        ----------
        velocity : (3,) casadi.SX
            Foil velocity (U m/s, V m/s, Omega rad/s) in foil axes.
        lag : (n_lag,) casadi.SX
            Lag states (``lag_state_names``), m/s.

        Returns
        -------
        FlowTerms
            Force, lag rate and the intermediate quantities.
        """
        p = self.params
        u, v, omega = velocity[0], velocity[1], velocity[2]
        eps2 = p.speed_regularization_m_s ** 2
        rho_s = self.rho_kg_m3 * self.span_m
        chord, r = self.chord_m, self.circle_radius_m
        a2 = self.foil.map.a_m ** 2
        speed = ca.sqrt(u * u + v * v + eps2)
        normal = -(v + omega * self.three_quarter_chord_x_m)
        gains = (p.wagner_slow_gain, p.wagner_fast_gain)
        rates = (p.wagner_slow_rate, p.wagner_fast_rate)
        effective = (1.0 - gains[0] - gains[1]) * normal + gains[0] * lag[0] + gains[1] * lag[1]
        lag_rates = [speed / self.semichord_m * rates[i] * (normal - lag[i]) for i in range(2)]

        # attached flow
        circulation = 4.0 * math.pi * r * effective
        normal_attached = rho_s * circulation * u
        moment_attached = (self.vortical_lift_x_m * normal_attached
                           + 4.0 * math.pi * rho_s * a2 * u * (effective - normal))
        suction_velocity = effective - omega * (self.mid_chord_x_m - self.three_quarter_chord_x_m)
        capped = smooth_cap(suction_velocity, p.critical_leading_edge_suction * speed, p.suction_cap_exponent)
        suction = 4.0 * math.pi * rho_s * r * capped * capped

        # trailing-edge separation (Leishman & Beddoes 1989): the static separation point f at the effective
        # incidence lagged by T_p, lagged by T_f; Kirchhoff's flow keeps ((1 + sqrt f) / 2)^2 of the normal force and
        # its moment and sqrt f of the suction. Both lags are velocities (P3): the lagged normal velocity, and the
        # speed times the lagged f
        if p.separation is not None:
            lagged_normal, point_speed = lag[2], lag[3]
            static_point = static_separation_point(u, lagged_normal, p.separation, p.speed_regularization_m_s)
            lag_rates.append(speed / (self.semichord_m * p.separation.pressure_lag_semichords)
                             * (effective - lagged_normal))
            lag_rates.append(speed / (self.semichord_m * p.separation.point_lag_semichords)
                             * (speed * static_point - point_speed))
            separation_point = ca.fmax(point_speed, 0.0) / speed
            kirchhoff = kirchhoff_share(separation_point)
            normal_attached = kirchhoff * normal_attached
            moment_attached = kirchhoff * moment_attached
            suction = ca.sqrt(separation_point) * suction
        else:
            separation_point = 1.0 + 0.0 * u
        lag_rate = ca.vertcat(*lag_rates)

        # separated flow: the flat plate
        speed_34 = ca.sqrt(u * u + normal * normal + eps2)
        normal_separated = 0.5 * rho_s * chord * p.flat_plate_normal_force_coefficient * speed_34 * normal
        pressure_centre = self.mid_chord_x_m + 0.25 * chord * u / speed_34
        munk = (self.added_mass.m11 - self.added_mass.m22) * u * v
        moment_separated = pressure_centre * normal_separated - munk

        # transition on the lagged effective incidence
        cos_effective = u / ca.sqrt(u * u + effective * effective + eps2)
        width = math.sin(p.stall_angle_rad) * p.stall_width_rad
        weight = 0.5 * (1.0 + ca.tanh((cos_effective - math.cos(p.stall_angle_rad)) / width))

        # on a thin section every chordwise pressure force is leading-edge suction, so the ideal model's
        # velocity-dependent chordwise force (eq. 46: m22 Omega V + m26 Omega^2, the non-circulatory part of the
        # suction) is inside S; subtracting it leaves the total chordwise force S attached and none separated
        kirchhoff_suction = self.added_mass.m22 * omega * v + self.added_mass.m26 * omega * omega
        drag = 0.5 * rho_s * chord * p.profile_drag_coefficient * speed
        force = ca.vertcat(weight * suction - kirchhoff_suction - drag * u,
                           weight * (normal_attached - drag * v) + (1.0 - weight) * normal_separated,
                           weight * moment_attached + (1.0 - weight) * moment_separated)
        return FlowTerms(force=force, lag_rate=lag_rate, normal_velocity=normal, effective_normal_velocity=effective,
                         suction_parameter=suction_velocity / speed, attached_weight=weight, circulation=circulation,
                         separation_point=separation_point)

    def profile_drag(self, velocity: ca.SX) -> ca.SX:
        """The attached flow's profile drag alone, for the vortex wake (whose flow is always attached).

        Parameters
        ----------
        velocity : (3,) casadi.SX
            Foil velocity (U m/s, V m/s, Omega rad/s) in foil axes.

        Returns
        -------
        (3,) casadi.SX
            (fx, fy, mz) = -1/2 rho s c C_D0 |u| (U, V, 0), N, N and N m.
        """
        u, v = velocity[0], velocity[1]
        speed = ca.sqrt(u * u + v * v + self.params.speed_regularization_m_s ** 2)
        drag = 0.5 * self.rho_kg_m3 * self.span_m * self.chord_m * self.params.profile_drag_coefficient * speed
        return ca.vertcat(-drag * u, -drag * v, 0.0 * u)

    @cached_property
    def functions(self) -> dict[str, ca.Function]:
        """The model's CasADi functions.

        ``flow_force(nu, lag) -> f``, ``flow_lag_rate(nu, lag) -> lag_dot``,
        ``flow_terms(nu, lag) -> (f, lag_dot, Q, Q_eff, lesp, w, Gamma, separation_point)``,
        ``profile_drag(nu) -> f``, and
        ``flow_lag_step(lag, nu0, nu_half, nu1, h) -> lag_next`` (one RK4 step with the velocity prescribed).
        """
        nu, lag = ca.SX.sym("nu", 3), ca.SX.sym("lag", self.lag_state_count)
        t = self.terms(nu, lag)
        rate = ca.Function("flow_lag_rate", [nu, lag], [t.lag_rate], ["nu", "lag"], ["lag_dot"])
        nu0, nu_half, nu1, h = ca.SX.sym("nu0", 3), ca.SX.sym("nu_half", 3), ca.SX.sym("nu1", 3), ca.SX.sym("h")
        k1 = rate(nu0, lag)
        k2 = rate(nu_half, lag + 0.5 * h * k1)
        k3 = rate(nu_half, lag + 0.5 * h * k2)
        k4 = rate(nu1, lag + h * k3)
        step = lag + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        return {
            "flow_force": ca.Function("flow_force", [nu, lag], [t.force], ["nu", "lag"], ["f"]),
            "flow_lag_rate": rate,
            "flow_terms": ca.Function(
                "flow_terms", [nu, lag],
                [t.force, t.lag_rate, t.normal_velocity, t.effective_normal_velocity, t.suction_parameter,
                 t.attached_weight, t.circulation, t.separation_point],
                ["nu", "lag"], ["f", "lag_dot", "Q", "Q_eff", "lesp", "attached_weight", "circulation",
                                "separation_point"]),
            "profile_drag": ca.Function("profile_drag", [nu], [self.profile_drag(nu)], ["nu"], ["f"]),
            "flow_lag_step": ca.Function("flow_lag_step", [lag, nu0, nu_half, nu1, h], [step],
                                         ["lag", "nu0", "nu_half", "nu1", "h"], ["lag_next"]),
        }

    # ----- numeric conveniences (CasADi's virtual machine, vectorized over samples) -------------------------------
    def evaluate(self, velocity: npt.ArrayLike, lag: npt.ArrayLike) -> dict[str, Array]:
        """The model's terms at n samples (CasADi's virtual machine, vectorized over samples).

        Parameters
        ----------
        velocity : (n, 3) or (3,) array_like
            Foil velocity (U m/s, V m/s, Omega rad/s) in foil axes.
        lag : (n, n_lag) or (n_lag,) array_like
            Lag states (``lag_state_names``), m/s.

        Returns
        -------
        dict of str to ndarray
            Keyed as ``flow_terms``'s outputs: ``f`` (n, 3), ``lag_dot`` (n, n_lag), ``Q``, ``Q_eff``, ``lesp``,
            ``attached_weight``, ``circulation``, ``separation_point`` (n,); for one sample given as vectors (3,)
            and (n_lag,), without the n axis.

        Raises
        ------
        FlowModelError
            For shapes other than (n, 3) and (n, n_lag).
        """
        single = np.ndim(velocity) == 1
        nu = np.atleast_2d(np.asarray(velocity, dtype=float))
        z = np.atleast_2d(np.asarray(lag, dtype=float))
        if nu.shape[1] != 3 or z.shape != (nu.shape[0], self.lag_state_count):
            raise FlowModelError(f"CirculatoryFlow.evaluate: velocity must be (n, 3) and lag "
                                 f"(n, {self.lag_state_count}), got {nu.shape} and {z.shape}")
        function = self.functions["flow_terms"]
        outputs = function.map(nu.shape[0])(nu.T, z.T)
        result = {}
        for i, value in enumerate(outputs):
            array = np.asarray(value, dtype=float).T          # (n, size)
            array = array[:, 0] if array.shape[1] == 1 else array
            result[function.name_out(i)] = array[0] if single else array
        return result

    def steady_lag(self, velocity: Iterable[float]) -> Array:
        """The lag states of steady motion at this velocity (each lagged normal velocity Q; f static at Q's incidence).

        Parameters
        ----------
        velocity : iterable of 3 floats
            Foil velocity (U m/s, V m/s, Omega rad/s) in foil axes.

        Returns
        -------
        (n_lag,) ndarray
            Lag states (``lag_state_names``), m/s.
        """
        u, v, omega = (float(x) for x in velocity)
        normal = -(v + omega * self.three_quarter_chord_x_m)
        p = self.params
        if p.separation is None:
            return np.array([normal, normal])
        speed = math.sqrt(u * u + v * v + p.speed_regularization_m_s ** 2)
        point = static_separation_point(u, normal, p.separation, p.speed_regularization_m_s)
        return np.array([normal, normal, normal, speed * point])

    def integrate_lag(self, velocities: npt.ArrayLike, step_s: float, lag0: npt.ArrayLike) -> Array:
        """Lag states under a prescribed motion, RK4 in one call.

        Parameters
        ----------
        velocities : (2n + 1, 3) array_like
            Foil velocities (U m/s, V m/s, Omega rad/s) at t0, t0 + h/2, t0 + h, ..., t0 + n h.
        step_s : float
            h, s.
        lag0 : (n_lag,) array_like
            Lag states at t0, m/s.

        Returns
        -------
        (n + 1, n_lag) ndarray
            Lag states at t0, t0 + h, ..., t0 + n h, m/s.

        Raises
        ------
        FlowModelError
            For velocities that are not (2n + 1, 3) with n >= 1.
        """
        nu = np.asarray(velocities, dtype=float)
        if nu.ndim != 2 or nu.shape[1] != 3 or nu.shape[0] % 2 != 1 or nu.shape[0] < 3:
            raise FlowModelError(f"integrate_lag: velocities must be (2n + 1, 3), got {nu.shape}")
        steps = (nu.shape[0] - 1) // 2
        accumulate = self.functions["flow_lag_step"].mapaccum(steps)
        z0 = np.asarray(lag0, dtype=float).reshape(self.lag_state_count)
        states = np.asarray(accumulate(z0, nu[0:-1:2].T, nu[1::2].T, nu[2::2].T, float(step_s)), dtype=float)
        return np.column_stack([z0, states]).T


# the towed-foil experiment lives in its own module and imports CirculatoryFlow from here
from swim_model.towed_foil import OscillatingFoilResult, oscillating_foil  # noqa: E402

__all__ = ["CirculatoryFlow", "FLOWS", "FLOW_MODELS", "FlowParameters", "FlowTerms", "LAG_STATE_NAMES",
           "SEPARATION_LAG_STATE_NAMES",
           "OscillatingFoilResult", "angle_of_attack", "laminar_profile_drag_coefficient", "oscillating_foil"]
