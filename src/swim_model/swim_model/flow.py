"""A reduced-order circulatory flow model of the foil: lift with Wagner's lag, leading-edge suction with a cap,
profile drag and a smooth transition to the flat plate's normal force past stall.

What it adds to the ideal model. The ideal (paper's) model applies the added-mass force of Kirchhoff's equations
(eq. 46, ``hydrodynamics.py``): the non-circulatory part. This module is the rest, the force the vortex wake would
add (``wake.py``: ``F_v = -dI_v/dt``), written as a generalized force ``Q2(q)' f`` with ``f = (fx, fy, mz)`` in foil
axes at the foil frame's origin F (the Joukowski map origin, the added mass's reference point) for the whole span.
Nothing is counted twice: the added mass stays in ``Mm``; ``f`` holds no term in the accelerations.

Notation: foil velocity ``(U, V, Omega)`` of F in foil axes (eq. 40; x along the chord toward the leading edge,
y normal to it), ``|u| = sqrt(U^2 + V^2)``, semichord ``b = c/2``, span ``s``; the map of ``joukowski.py``:
``z = zeta + zeta_c + a^2/(zeta + zeta_c)`` on the circle of radius ``r = a + zeta_c``.

1. Normal velocity at the three-quarter chord (thin-aerofoil theory; Theodorsen, NACA Report 496, 1935):
   ``Q = -(V + Omega x_34)``, ``x_34 = x_LE - 3c/4``. For the symmetric Joukowski section this point is exact, not
   an approximation: the Kutta condition on the circle plane (``vortex_force.py``) gives the circulation of a
   translating and turning foil as ``Gamma = -4 pi r (V + Omega (A/r^2 + B/a^2)/2)``, and ``(A/r^2 + B/a^2)/2``
   equals ``x_LE - 3c/4`` for every thickness (tested to 1e-12).
2. Wagner's lag as R. T. Jones's two-state approximation (NACA Report 681, 1940; Bisplinghoff, Ashley & Halfman,
   Aeroelasticity, 1955, Sec. 5-6): ``phi(s) = 1 - A1 e^{-b1 s} - A2 e^{-b2 s}``, A1 = 0.165, b1 = 0.0455,
   A2 = 0.335, b2 = 0.3, s the distance travelled in semichords. As states, two first-order lags of Q in velocity
   units (m/s), travelling at the foil's speed::

       dz_i/dt = (|u| / b) b_i (Q - z_i),       Q_eff = (1 - A1 - A2) Q + A1 z1 + A2 z2,

   whose step response is ``phi`` and whose frequency response is ``C(k) = 1 - sum_i A_i i k / (i k + b_i)``,
   Theodorsen's function within 2.1 % in modulus and 1.3 degrees in phase for k = 0.05-5 (tested).
3. Attached flow: circulation ``Gamma = 4 pi r Q_eff`` (the Joukowski section's Kutta circulation; ``r = c/4`` for
   the flat plate gives ``2 pi b``); circulatory normal force ``N = rho s Gamma U`` (Theodorsen's ``2 pi rho U b C Q``).
   Its moment about F: ``N zeta_c + 4 pi rho s a^2 U (Q_eff - Q)``. In steady flow the first term alone remains, the
   vortical lift acting at ``x = zeta_c`` as in the wake (``vortex_force.py``); with the Munk moment of the added
   mass it puts the lift at the aerodynamic centre ``zeta_c + a^2/r``. For the flat plate the second term is
   ``pi rho b^2 U (C - 1) Q``: exactly what Theodorsen's moment adds to Kirchhoff's (derivation in
   docs/flow_model.md), so total force and moment are Theodorsen's.
4. Leading-edge suction (Garrick, NACA Report 567, 1936): ``S = 4 pi rho s r Q_s^2`` along +x, with
   ``Q_s = Q_eff - Omega c/4`` the leading-edge singularity of unsteady thin-aerofoil theory (the mean normal
   velocity over the chord, wake included: A0 U; Ramesh et al., J. Fluid Mech. 751, 2014). Steady, ``N`` and ``S``
   together are the Kutta-Joukowski force ``rho Gamma |u|`` normal to the motion. Capped by a critical
   leading-edge-suction parameter (Ramesh et al. 2014): ``Q_s`` is limited to ``LESP_crit |u|`` by the smooth
   saturation ``Q_s / (1 + (Q_s / (LESP_crit |u|))^8)^(1/8)`` (the suction a rounded leading edge sustains before
   the flow separates there).
5. Separated flow: the flat plate's normal force ``N_sep = 1/2 rho s c C_N90 |u_34| Q`` with
   ``|u_34| = sqrt(U^2 + Q^2)`` (``C_N = C_N90 sin alpha``), acting at ``x_mid + (c/4) cos alpha`` (from the quarter
   chord at small angles to mid-chord broadside), and cancelling the ideal model's Munk moment
   ``(m11 - m22) U V`` (a steady potential-flow moment that separated flow does not have).
6. Transition: attached weight ``w = (1 + tanh((cos alpha_e - cos alpha_stall) / (sin alpha_stall dalpha))) / 2``
   on the lagged effective angle ``cos alpha_e = U / sqrt(U^2 + Q_eff^2)``; ``f = w f_attached + (1 - w) f_sep``.
   A foil moving trailing edge first (U < 0) counts as separated.
7. Profile drag ``1/2 rho s c C_D0 |u| (U, V)`` against the motion of F in attached flow; separated, only its
   chordwise part (skin friction) is added, the flat plate's normal force being its whole pressure drag.

Smoothness and time scaling: every speed is ``sqrt(... + eps^2)`` with ``eps`` = 1e-7 m/s, so the model is
infinitely differentiable everywhere (also from rest). Away from rest, every force is homogeneous of degree 2 in
(velocities, lag states) and every lag rate of degree 2, so property P3 (time scaling) holds to ``(eps/|u|)^2``
(1e-12 at 0.1 m/s): with ``z -> lambda z`` the scaled trajectory is the original one at lambda times the speed.
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
from swim_model.leading_edge import (CRITICAL_LEADING_EDGE_SUCTION, SPEED_REGULARIZATION_M_S, SUCTION_CAP_EXPONENT,
                                     is_cap_exponent, smooth_cap)

Array = npt.NDArray[np.float64]

LAG_STATE_NAMES = ("wagner_lag_slow", "wagner_lag_fast")
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

    ``C_D0 = 2 (1.328 / sqrt(Re)) (1 + 2 t/c + 60 (t/c)^4)``: Blasius's laminar skin friction on both sides
    (Schlichting, Boundary-Layer Theory, Ch. 7) times Hoerner's form factor for aerofoil sections (Hoerner,
    Fluid-Dynamic Drag, 1965, Ch. 6, eq. 6.23). Chord Reynolds numbers of 1e4-1e5 (the rig, Anderson et al.'s tank)
    are below transition.
    """
    if not (reynolds_number > 0.0 and 0.0 <= thickness_ratio < 0.5):
        raise FlowModelError(f"laminar_profile_drag_coefficient: needs Re > 0 and 0 <= t/c < 0.5, got "
                             f"{reynolds_number!r}, {thickness_ratio!r}")
    return 2.0 * 1.328 / math.sqrt(reynolds_number) * (1.0 + 2.0 * thickness_ratio + 60.0 * thickness_ratio ** 4)


@dataclasses.dataclass(frozen=True)
class FlowParameters:
    """Coefficients of the circulatory flow model, each with its source or the reason it was assumed."""

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

    def __post_init__(self) -> None:
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
        if not is_cap_exponent(self.suction_cap_exponent):
            raise FlowModelError("FlowParameters.suction_cap_exponent must be an even integer >= 2")

    def digest(self) -> str:
        """SHA-256 of the values (compiled models are cached under it)."""
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
    """atan2(-V, U), rad: the angle between the chord and the foil frame's motion (eq. 40's U, V in foil axes).

    Positive when the foil moves toward -y while moving forward (the flow meets it from below): the sign of the
    lift. Works on numbers, numpy arrays and CasADi expressions.
    """
    if isinstance(u_m_s, (ca.SX, ca.MX, ca.DM)) or isinstance(v_m_s, (ca.SX, ca.MX, ca.DM)):
        return ca.atan2(-v_m_s, u_m_s)
    return np.arctan2(-np.asarray(v_m_s, dtype=float), np.asarray(u_m_s, dtype=float))


@dataclasses.dataclass(frozen=True)
class FlowTerms:
    """The model's intermediate quantities as CasADi expressions (``CirculatoryFlow.terms``)."""

    force: ca.SX                # (fx, fy, mz): N, N, N m; foil axes at F, whole span
    lag_rate: ca.SX             # dz/dt, m/s^2
    normal_velocity: ca.SX      # Q at the three-quarter chord, m/s
    effective_normal_velocity: ca.SX  # Q_eff (lagged), m/s
    suction_parameter: ca.SX    # Q_s / |u| (the leading-edge suction parameter before the cap)
    attached_weight: ca.SX      # w in [0, 1]
    circulation: ca.SX          # Gamma, m^2/s


class CirculatoryFlow:
    """The circulatory flow model of one foil (module docstring), as CasADi expressions and functions.

    Args:
        foil: the Joukowski foil (chord, thickness, span).
        rho_kg_m3: water density.
        params: coefficients (default: FlowParameters()).
    """

    lag_state_count = 2

    def __init__(self, foil: JoukowskiFoil, rho_kg_m3: float, params: FlowParameters | None = None) -> None:
        if not (math.isfinite(rho_kg_m3) and rho_kg_m3 > 0.0):
            raise FlowModelError(f"CirculatoryFlow: rho_kg_m3 must be positive, got {rho_kg_m3!r}")
        self.foil = foil
        self.rho_kg_m3 = float(rho_kg_m3)
        self.params = params if params is not None else FlowParameters()
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
        """The model's expressions for foil velocity (U, V, Omega) (3-vector, m/s, m/s, rad/s) and lag states
        (2-vector, m/s)."""
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
        lag_rate = ca.vertcat(*[speed / self.semichord_m * rates[i] * (normal - lag[i]) for i in range(2)])

        # attached flow
        circulation = 4.0 * math.pi * r * effective
        normal_attached = rho_s * circulation * u
        moment_attached = (self.vortical_lift_x_m * normal_attached
                           + 4.0 * math.pi * rho_s * a2 * u * (effective - normal))
        suction_velocity = effective - omega * (self.mid_chord_x_m - self.three_quarter_chord_x_m)
        capped = smooth_cap(suction_velocity, p.critical_leading_edge_suction * speed, p.suction_cap_exponent)
        suction = 4.0 * math.pi * rho_s * r * capped * capped

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
                         suction_parameter=suction_velocity / speed, attached_weight=weight, circulation=circulation)

    def profile_drag(self, velocity: ca.SX) -> ca.SX:
        """The attached flow's profile drag alone, (fx, fy, mz) = -1/2 rho s c C_D0 |u| (U, V, 0) (for the vortex
        wake, whose flow is always attached)."""
        u, v = velocity[0], velocity[1]
        speed = ca.sqrt(u * u + v * v + self.params.speed_regularization_m_s ** 2)
        drag = 0.5 * self.rho_kg_m3 * self.span_m * self.chord_m * self.params.profile_drag_coefficient * speed
        return ca.vertcat(-drag * u, -drag * v, 0.0 * u)

    @cached_property
    def functions(self) -> dict[str, ca.Function]:
        """CasADi functions: ``flow_force(nu, lag) -> f``, ``flow_lag_rate(nu, lag) -> lag_dot``,
        ``flow_terms(nu, lag) -> (f, lag_dot, Q, Q_eff, lesp, w, Gamma)``, ``profile_drag(nu) -> f``, and
        ``flow_lag_step(lag, nu0, nu_half, nu1, h) -> lag_next`` (one RK4 step with the velocity prescribed)."""
        nu, lag = ca.SX.sym("nu", 3), ca.SX.sym("lag", 2)
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
                 t.attached_weight, t.circulation],
                ["nu", "lag"], ["f", "lag_dot", "Q", "Q_eff", "lesp", "attached_weight", "circulation"]),
            "profile_drag": ca.Function("profile_drag", [nu], [self.profile_drag(nu)], ["nu"], ["f"]),
            "flow_lag_step": ca.Function("flow_lag_step", [lag, nu0, nu_half, nu1, h], [step],
                                         ["lag", "nu0", "nu_half", "nu1", "h"], ["lag_next"]),
        }

    # ----- numeric conveniences (CasADi's virtual machine, vectorized over samples) -------------------------------
    def evaluate(self, velocity: npt.ArrayLike, lag: npt.ArrayLike) -> dict[str, Array]:
        """The model's terms at n samples: velocity (n, 3) as (U, V, Omega), lag (n, 2), m/s.

        Returns arrays keyed as ``flow_terms``'s outputs: ``f`` (n, 3), ``lag_dot`` (n, 2), ``Q``, ``Q_eff``, ``lesp``,
        ``attached_weight``, ``circulation`` (n,); for one sample given as vectors (3,) and (2,), without the n axis.
        """
        single = np.ndim(velocity) == 1
        nu = np.atleast_2d(np.asarray(velocity, dtype=float))
        z = np.atleast_2d(np.asarray(lag, dtype=float))
        if nu.shape[1] != 3 or z.shape != (nu.shape[0], 2):
            raise FlowModelError(f"CirculatoryFlow.evaluate: velocity must be (n, 3) and lag (n, 2), got "
                                 f"{nu.shape} and {z.shape}")
        function = self.functions["flow_terms"]
        outputs = function.map(nu.shape[0])(nu.T, z.T)
        result = {}
        for i, value in enumerate(outputs):
            array = np.asarray(value, dtype=float).T          # (n, size)
            array = array[:, 0] if array.shape[1] == 1 else array
            result[function.name_out(i)] = array[0] if single else array
        return result

    def steady_lag(self, velocity: Iterable[float]) -> Array:
        """The lag states of steady motion at this velocity (z_i = Q), m/s."""
        u, v, omega = (float(x) for x in velocity)
        normal = -(v + omega * self.three_quarter_chord_x_m)
        return np.array([normal, normal])

    def integrate_lag(self, velocities: npt.ArrayLike, step_s: float, lag0: npt.ArrayLike) -> Array:
        """Lag states under a prescribed motion, RK4 in one call.

        Args:
            velocities: (2n + 1, 3) foil velocities (U, V, Omega) at t0, t0 + h/2, t0 + h, ..., t0 + n h.
            step_s: h, s.
            lag0: lag states at t0, m/s.
        Returns:
            (n + 1, 2) lag states at t0, t0 + h, ..., t0 + n h.
        """
        nu = np.asarray(velocities, dtype=float)
        if nu.ndim != 2 or nu.shape[1] != 3 or nu.shape[0] % 2 != 1 or nu.shape[0] < 3:
            raise FlowModelError(f"integrate_lag: velocities must be (2n + 1, 3), got {nu.shape}")
        steps = (nu.shape[0] - 1) // 2
        accumulate = self.functions["flow_lag_step"].mapaccum(steps)
        z0 = np.asarray(lag0, dtype=float).reshape(2)
        states = np.asarray(accumulate(z0, nu[0:-1:2].T, nu[1::2].T, nu[2::2].T, float(step_s)), dtype=float)
        return np.column_stack([z0, states]).T


# the towed-foil experiment lives in its own module and imports CirculatoryFlow from here
from swim_model.towed_foil import OscillatingFoilResult, oscillating_foil  # noqa: E402

__all__ = ["CirculatoryFlow", "FLOWS", "FLOW_MODELS", "FlowParameters", "FlowTerms", "LAG_STATE_NAMES",
           "OscillatingFoilResult", "angle_of_attack", "laminar_profile_drag_coefficient", "oscillating_foil"]
