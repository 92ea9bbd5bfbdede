"""Kinematics of the swimming machine (paper Fig. 33 and eq. 40), symbolic in CasADi.

Inertial frame: origin on the hub axis, angles counter-clockwise. With
``e_r = (cos alpha, sin alpha)`` along the rails and ``dir(beta) = (-sin beta, cos beta)``
(a unit vector perpendicular to the rails for beta = alpha):

- platform centre of mass at ``R e_r``; heave axis P at ``(R - Ld) e_r`` (Ld: heave_pivot_inset);
- heave link (peduncle, length Lh) along ``dir(alpha + phi)``: at phi = 0 it points in the
  direction of increasing alpha; the pitch axis E at its end, ``E = P + Lh dir(alpha + phi)``;
- foil chord (x of the foil frame, toward the leading edge) along ``c = dir(alpha + theta)``,
  the foil normal ``n = c`` rotated by +90 deg; the foil's reference point (the Joukowski map
  origin) at ``F = E + Lf c``.

The foil-frame velocities of F, ``U = c . dF/dt``, ``V = n . dF/dt``, ``Omega = alphadot + thetadot``,
are exactly eq. 40; these sign conventions are the ones that make eq. 40 hold, and the
tests compare against eq. 40 as printed.
"""
from __future__ import annotations

import dataclasses

import casadi as ca

from swim_model.rig import RigParameters

Vec = ca.SX


def unit_along(angle: ca.SX) -> ca.SX:
    """The unit vector at an angle from +x, e_r(angle).

    Parameters
    ----------
    angle : casadi.SX
        Angle from the tank frame's +x, counter-clockwise, rad.

    Returns
    -------
    (2,) casadi.SX
        (cos angle, sin angle).
    """
    return ca.vertcat(ca.cos(angle), ca.sin(angle))


def unit_across(angle: ca.SX) -> ca.SX:
    """dir(angle) = (-sin angle, cos angle): e_r(angle) rotated by +90 deg.

    Parameters
    ----------
    angle : casadi.SX
        The angle of e_r (``unit_along``), rad; the result points a quarter turn counter-clockwise from it.

    Returns
    -------
    (2,) casadi.SX
        The unit vector.
    """
    return ca.vertcat(-ca.sin(angle), ca.cos(angle))


@dataclasses.dataclass(frozen=True)
class Coordinates:
    """The full coordinates (alpha, R, phi, theta) as symbols or expressions of the chosen q.

    Attributes
    ----------
    alpha : casadi.SX
        Hub angle, rad.
    radius : casadi.SX
        R, the platform's distance from the hub axis along the rails, m.
    phi : casadi.SX
        Heave angle of the link relative to the rails' normal, rad.
    theta : casadi.SX
        Pitch angle of the foil, rad.
    """

    alpha: ca.SX
    radius: ca.SX
    phi: ca.SX
    theta: ca.SX


@dataclasses.dataclass(frozen=True)
class RigidBody:
    """One rigid body: centre-of-mass position, absolute angle, mass and central inertia.

    Attributes
    ----------
    name : str
        The body's name (``platform``, ``heave_link``, ...).
    position : (2,) casadi.SX
        Centre of mass in the tank frame, m.
    angle : casadi.SX
        Absolute angle, rad.
    mass_kg : float
        Mass, kg.
    inertia_kg_m2 : float
        Inertia about the centre of mass, kg m^2.
    """

    name: str
    position: ca.SX
    angle: ca.SX
    mass_kg: float
    inertia_kg_m2: float


def foil_reference_point(c: Coordinates, rig: RigParameters) -> ca.SX:
    """F = (R - Ld) e_r + Lh dir(alpha + phi) + Lf dir(alpha + theta), the foil frame's origin (eq. 40).

    Parameters
    ----------
    c : Coordinates
        The coordinates.
    rig : RigParameters
        Ld, Lh and Lf.

    Returns
    -------
    (2,) casadi.SX
        F in the tank frame, m.
    """
    return ((c.radius - rig.heave_pivot_inset_m) * unit_along(c.alpha)
            + rig.heave_link_length_m * unit_across(c.alpha + c.phi)
            + rig.pitch_axis_to_foil_reference_m * unit_across(c.alpha + c.theta))


def foil_velocity_map(c: Coordinates, q: ca.SX, rig: RigParameters) -> ca.SX:
    """Q2(q): (U, V, Omega) = Q2(q) qdot (eq. 40), foil frame at the foil reference point.

    Parameters
    ----------
    c, q : Coordinates and (nq,) casadi.SX
        The coordinates as expressions of the model's configuration symbols q (rad and m), which Q2 is the
        Jacobian by.
    rig : RigParameters
        Ld, Lh and Lf.

    Returns
    -------
    (3, nq) casadi.SX
        Q2: qdot to (U m/s, V m/s, Omega rad/s).
    """
    jacobian_f = ca.jacobian(foil_reference_point(c, rig), q)
    chord = unit_across(c.alpha + c.theta)
    normal = ca.vertcat(-chord[1], chord[0])
    return ca.vertcat(chord.T @ jacobian_f, normal.T @ jacobian_f, ca.jacobian(c.alpha + c.theta, q))


def rigid_bodies(c: Coordinates, rig: RigParameters) -> list[RigidBody]:
    """The mechanism's bodies (the paper's M(q) of eq. 4; all inertias assumed, see rig.yaml).

    Motor rotors turn at alphadot + N phidot and alphadot + N thetadot (gear ratio N), both motors being on the
    platform; their masses are part of the platform's.

    Parameters
    ----------
    c : Coordinates
        The coordinates.
    rig : RigParameters
        Lengths, masses, inertias and gear ratios.

    Returns
    -------
    list of RigidBody
        Hub arm, platform, heave and pitch rotors, heave link, foil assembly.
    """
    origin = ca.SX.zeros(2)
    pivot = (c.radius - rig.heave_pivot_inset_m) * unit_along(c.alpha)
    link = unit_across(c.alpha + c.phi)
    pitch_axis = pivot + rig.heave_link_length_m * link
    chord = unit_across(c.alpha + c.theta)
    return [
        RigidBody("hub_arm", origin, c.alpha, 0.0, rig.hub_arm_inertia_kg_m2),
        RigidBody("platform", c.radius * unit_along(c.alpha), c.alpha, rig.platform_mass_kg,
                  rig.platform_inertia_kg_m2),
        RigidBody("heave_rotor", origin, c.alpha + rig.heave_gear_ratio * c.phi, 0.0,
                  rig.heave_rotor_inertia_kg_m2),
        RigidBody("pitch_rotor", origin, c.alpha + rig.pitch_gear_ratio * c.theta, 0.0,
                  rig.pitch_rotor_inertia_kg_m2),
        RigidBody("heave_link", pivot + rig.heave_link_cg_distance_m * link, c.alpha + c.phi,
                  rig.heave_link_mass_kg, rig.heave_link_inertia_kg_m2),
        RigidBody("foil_assembly", pitch_axis + rig.foil_assembly_cg_offset_m * chord, c.alpha + c.theta,
                  rig.foil_assembly_mass_kg, rig.foil_assembly_inertia_kg_m2),
    ]


def rigid_mass_matrix(c: Coordinates, q: ca.SX, rig: RigParameters) -> ca.SX:
    """M(q) = sum over bodies of m J_v' J_v + I J_w' J_w (J_v, J_w: Jacobians of position and angle; eq. 4).

    Parameters
    ----------
    c, q : Coordinates and (nq,) casadi.SX
        The coordinates, and the configuration symbols (rad and m) they are expressions of: the bodies' Jacobians
        J_v and J_w are taken by q.
    rig : RigParameters
        Lengths, masses, inertias and gear ratios.

    Returns
    -------
    (nq, nq) casadi.SX
        M(q), kg, kg m and kg m^2 by entry.
    """
    nq = q.shape[0]
    mass = ca.SX.zeros(nq, nq)
    for body in rigid_bodies(c, rig):
        if body.mass_kg:
            jv = ca.jacobian(body.position, q)
            mass += body.mass_kg * (jv.T @ jv)
        jw = ca.jacobian(body.angle, q)
        mass += body.inertia_kg_m2 * (jw.T @ jw)
    return mass
