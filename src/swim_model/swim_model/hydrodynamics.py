"""The hydrodynamic-force route to the equations of motion (paper Appendix A.2, eqs. 44-48).

The mechanism alone, ``M(q) qddot + C(q, qdot) qdot = B tau + Q2(q)' (Fx, Fy, tau_z)`` (eqs. 44, 47),
with the fluid's force and moment on the foil in Kirchhoff's form (eq. 46), in the foil frame:

    Fx    = -m11 Udot + m22 Omega V + m26 Omega^2
    Fy    = -m22 Vdot - m26 Omegadot - m11 Omega U
    tau_z = -m62 Vdot - m66 Omegadot - m26 Omega U + (m11 - m22) U V

and ``(Udot, Vdot, Omegadot) = Q2 qddot + Qdot2 qdot`` by differentiating eq. 40. Printed eq. 47 is
incomplete in the extracted text; the map from foil-frame forces to generalized forces is Q2(q)'
by virtual work. The paper states (and tests/test_vehicle_properties.py checks) that this gives
exactly the equations of the energy route.
"""
from __future__ import annotations

import casadi as ca

from swim_model.joukowski import AddedMass
from swim_model.vehicle import VehicleModel, coriolis_from_mass


def kirchhoff_force(added: AddedMass, velocity: ca.SX, acceleration: ca.SX) -> ca.SX:
    """(Fx, Fy, tau_z) on the foil from its frame velocity (U, V, Omega) and its rate (eq. 46).

    Parameters
    ----------
    added : AddedMass
        The foil's added mass.
    velocity : (3,) casadi.SX
        (U m/s, V m/s, Omega rad/s) in foil axes.
    acceleration : (3,) casadi.SX
        Its rate, m/s^2 and rad/s^2.

    Returns
    -------
    (3,) casadi.SX
        (Fx N, Fy N, tau_z N m) in foil axes.
    """
    u, v, w = velocity[0], velocity[1], velocity[2]
    inertial = -ca.SX(added.matrix()) @ acceleration
    coupling = ca.vertcat(added.m22 * w * v + added.m26 * w * w,
                          -added.m11 * w * u,
                          -added.m26 * w * u + (added.m11 - added.m22) * u * v)
    return inertial + coupling


def force_route_forward_dynamics(model: VehicleModel) -> ca.Function:
    """qddot(q, qdot, tau) from eqs. 44-47, solved for qddot (linear in it).

    Parameters
    ----------
    model : VehicleModel
        The vehicle (its mechanism, Q2 and added mass).

    Returns
    -------
    casadi.Function
        (q (nq,), qdot (nq,), tau (2,) N m) -> qddot (nq,), rad/s^2 and m/s^2.
    """
    s = model.symbolic
    q2 = s.foil_velocity_map
    q2dot_qdot = ca.jtimes(q2 @ s.qdot, s.q, s.qdot)
    velocity = q2 @ s.qdot
    mechanism_bias = coriolis_from_mass(s.rigid_mass, s.q, s.qdot) @ s.qdot
    input_map = ca.vertcat(ca.SX.zeros(model.n_unactuated, 2), ca.SX.eye(2))
    # residual(qddot) = M qddot + C qdot - B tau - Q2' F(qddot): affine in qddot
    force = kirchhoff_force(model.added_mass, velocity, q2 @ s.qddot + q2dot_qdot)
    residual = s.rigid_mass @ s.qddot + mechanism_bias - input_map @ s.tau - q2.T @ force
    jac = ca.jacobian(residual, s.qddot)
    offset = ca.substitute(residual, s.qddot, ca.SX.zeros(model.nq))
    qddot = ca.solve(jac, -offset)
    return ca.Function("force_route_forward_dynamics", [s.q, s.qdot, s.tau], [qddot],
                       ["q", "qdot", "tau"], ["qddot"])
