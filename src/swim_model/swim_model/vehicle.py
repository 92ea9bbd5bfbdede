"""The swimming machine's equations of motion (paper Sec. 3, eqs. 4-7, 14-15, 22-23; Appendix A).

q = (alpha, R, phi, theta) for the free vehicle (eq. 6), q = (alpha, phi, theta) with the rails locked at
R = lane radius for the laterally constrained one (eq. 7). The energy route and the partition into unactuated
and shape coordinates are derived in docs/model_and_method.md, Sec. 2.3; ``flow="circulatory"``'s generalized
force and lag states in docs/flow_model.md, Sec. 1. The hydrodynamic-force route (A.2) is
:mod:`swim_model.hydrodynamics`.

All expressions are CasADi SX (for optimization and exact Jacobians, ``VehicleModel.symbolic``); the numeric
methods evaluate the same expressions compiled to C (:mod:`swim_model.codegen`).
"""
from __future__ import annotations

import dataclasses
import hashlib
import math
import threading
from functools import cached_property
from typing import Sequence

import casadi as ca
import numpy as np
import numpy.typing as npt

from swim_model import codegen
from swim_model.errors import FlowModelError, StateError
from swim_model.flow import FLOW_MODELS, CirculatoryFlow, FlowParameters
from swim_model.joukowski import AddedMass, JoukowskiFoil
from swim_model.kinematics import Coordinates, foil_reference_point, foil_velocity_map, rigid_mass_matrix
from swim_model.rig import RigParameters, load_rig

Array = npt.NDArray[np.float64]

JOINT_NAMES_UNCONSTRAINED = ("alpha", "R", "phi", "theta")
JOINT_NAMES_CONSTRAINED = ("alpha", "phi", "theta")
#: kinematics.py's chord direction dir(a) = (-sin a, cos a) lies at angle a + pi/2 in the tank frame: the foil pose's
#: angle is alpha + theta + this (the convention of swim_model.wake's pose)
FOIL_CHORD_ANGLE_OFFSET_RAD = 0.5 * math.pi
#: step counts of integrate_rk4's compiled chunks: powers of two, so n steps take at most log2(n) + n / 512 calls, each
#: one C call on buffers (no conversion to CasADi's DM and back: that costs as much as the arithmetic at 1000 steps)
RK4_CHUNK_STEPS = tuple(2 ** k for k in range(10))


def coriolis_from_mass(mass: ca.SX, q: ca.SX, qdot: ca.SX) -> ca.SX:
    """Cm(q, qdot) from the Christoffel symbols of a configuration-dependent mass matrix.

    Written as ``Cm = 1/2 (Mmdot + d(Mm qdot)/dq - d(Mm qdot)/dq')``, so that ``Mmdot - 2 Cm`` is skew-symmetric.

    Parameters
    ----------
    mass : (n, n) casadi.SX
        Mass matrix as an expression of q, kg, kg m and kg m^2 by entry.
    q : (n,) casadi.SX
        Configuration symbols the mass matrix depends on, rad and m.
    qdot : (n,) casadi.SX
        Velocity symbols, rad/s and m/s.

    Returns
    -------
    (n, n) casadi.SX
        Cm, linear in qdot.

    References
    ----------
    Saimek & Li (2004), eqs. 6-7 and Appendix A.1.
    """
    mass_dot = ca.jtimes(mass, q, qdot)
    d_momentum = ca.jacobian(mass @ qdot, q)
    return 0.5 * (mass_dot + d_momentum - d_momentum.T)


@dataclasses.dataclass(frozen=True)
class SymbolicModel:
    """CasADi symbols, expressions and functions of one vehicle model (``VehicleModel.symbolic``).

    Attributes
    ----------
    q, qdot, qddot : (nq,) casadi.SX
        Configuration (rad and m), velocity and acceleration symbols.
    tau : (2,) casadi.SX
        Joint torques (heave, pitch), N m.
    u : (2,) casadi.SX
        Prescribed foil accelerations psiddot = (phiddot, thetaddot), rad/s^2 (eqs. 14-15).
    foil_velocity_map : (3, nq) casadi.SX
        Q2(q): (U, V, Omega) = Q2 qdot (eq. 40).
    rigid_mass : (nq, nq) casadi.SX
        M(q), the mechanism's mass matrix without the fluid.
    mass : (nq, nq) casadi.SX
        Mm(q) = M + Q2' M_A Q2 (eq. 41).
    coriolis : (nq, nq) casadi.SX
        Cm(q, qdot) (eq. 6).
    functions : dict of str to casadi.Function
        The model's functions by name (``mass_matrix``, ``forward_dynamics``, ...).
    lag : (2,) casadi.SX or None
        The flow's lag states z, m/s (circulatory flow only).
    flow_force : (3,) casadi.SX or None
        (fx, fy, mz) in foil axes at the foil frame's origin, N, N and N m (circulatory flow only).
    generalized_flow_force : (nq,) casadi.SX or None
        Q_flow = Q2' f, one entry per coordinate (circulatory flow only).
    """

    q: ca.SX
    qdot: ca.SX
    qddot: ca.SX
    tau: ca.SX
    u: ca.SX
    foil_velocity_map: ca.SX
    rigid_mass: ca.SX
    mass: ca.SX
    coriolis: ca.SX
    functions: dict[str, ca.Function]
    lag: ca.SX | None = None          # the flow's lag states z (circulatory flow), m/s
    flow_force: ca.SX | None = None   # (fx, fy, mz) in foil axes at the foil frame's origin (circulatory flow)
    generalized_flow_force: ca.SX | None = None  # Q2' f, one entry per coordinate (circulatory flow)


class VehicleModel:
    """Equations of motion of the free (4-DOF) or laterally constrained (3-DOF) vehicle.

    All numeric methods take and return numpy arrays: q and qdot of length nq (4 free: alpha rad, R m, phi rad,
    theta rad; 3 constrained: alpha, phi, theta), tau the (2,) joint torques (heave, pitch) in N m. With the
    circulatory flow the dynamics methods also take ``lag``, the (2,) lag states in m/s (``lag=`` is refused by the
    ideal model, required by the circulatory one); the state for integrators is x = (q, qdot, lag),
    nx = 2 nq + n_lag. The equations are in docs/model_and_method.md, Sec. 2.3.

    Parameters
    ----------
    rig : RigParameters, optional
        The rig's lengths, masses, inertias, foil and gear ratios (default: the shipped rig file, ``load_rig()``).
    constrained : bool, optional
        Lock the rails: q = (alpha, phi, theta).
    lane_radius_m : float, optional
        R of the locked rails, m (default: the rig's ``constrained_lane_radius_m``).
    flow : {"ideal", "circulatory"}, optional
        "ideal" (the paper's added mass only) or "circulatory" (plus swim_model.flow's lift, suction, drag and
        stall, with its n_lag lag states: 2, or 4 with the trailing edge separating).
    flow_parameters : FlowParameters, optional
        The circulatory model's coefficients (default: FlowParameters()); refused with ``flow="ideal"``.

    Raises
    ------
    FlowModelError
        For an unknown flow, or flow_parameters with the ideal flow.

    References
    ----------
    Saimek & Li (2004), Sec. 3, eqs. 4-7, 14-15, 22-23, Appendix A.
    """

    def __init__(self, rig: RigParameters | None = None, constrained: bool = False,
                 lane_radius_m: float | None = None, flow: str = "ideal",
                 flow_parameters: FlowParameters | None = None) -> None:
        if flow not in FLOW_MODELS:
            raise FlowModelError(f"VehicleModel: flow must be one of {FLOW_MODELS}, got {flow!r}")
        if flow == "ideal" and flow_parameters is not None:
            raise FlowModelError("VehicleModel: flow_parameters are for flow='circulatory'")
        self.rig = rig if rig is not None else load_rig()
        self.constrained = bool(constrained)
        self.lane_radius_m = float(lane_radius_m if lane_radius_m is not None
                                   else self.rig.constrained_lane_radius_m)
        self.joint_names: tuple[str, ...] = JOINT_NAMES_CONSTRAINED if constrained else JOINT_NAMES_UNCONSTRAINED
        self.nq = len(self.joint_names)
        self.n_unactuated = self.nq - 2
        self.foil = JoukowskiFoil(self.rig.foil_chord_m, self.rig.foil_max_thickness_m, self.rig.foil_span_m)
        self.added_mass: AddedMass = self.foil.added_mass(self.rig.water_density_kg_m3)
        self.flow = flow
        self.circulatory_flow: CirculatoryFlow | None = (
            CirculatoryFlow(self.foil, self.rig.water_density_kg_m3, flow_parameters) if flow == "circulatory"
            else None)
        self.lag_names: tuple[str, ...] = (
            self.circulatory_flow.lag_state_names if self.circulatory_flow is not None else ())
        self.n_lag = len(self.lag_names)
        self.nx = 2 * self.nq + self.n_lag

    # ----- symbolic model ----------------------------------------------------------------------
    def coordinates(self, q: ca.SX) -> Coordinates:
        """Map the model's q to (alpha, R, phi, theta).

        Parameters
        ----------
        q : (nq,) casadi.SX
            Configuration, rad and m.

        Returns
        -------
        Coordinates
            The four coordinates; R is the lane radius for the constrained vehicle.
        """
        if self.constrained:
            return Coordinates(alpha=q[0], radius=ca.SX(self.lane_radius_m), phi=q[1], theta=q[2])
        return Coordinates(alpha=q[0], radius=q[1], phi=q[2], theta=q[3])

    @cached_property
    def symbolic(self) -> SymbolicModel:
        """The model's CasADi symbols, expressions and functions, built once (eqs. 5-7, 14-15, 22-23, 41)."""
        nq, ny = self.nq, self.n_unactuated
        q, qdot, qddot = ca.SX.sym("q", nq), ca.SX.sym("qdot", nq), ca.SX.sym("qddot", nq)
        tau, u = ca.SX.sym("tau", 2), ca.SX.sym("u", 2)
        coords = self.coordinates(q)
        q2 = foil_velocity_map(coords, q, self.rig)
        rigid = rigid_mass_matrix(coords, q, self.rig)
        mass = rigid + q2.T @ ca.SX(self.added_mass.matrix()) @ q2
        coriolis = coriolis_from_mass(mass, q, qdot)
        input_map = ca.vertcat(ca.SX.zeros(ny, 2), ca.SX.eye(2))
        # Cm qdot = Mmdot qdot - dT/dq (Euler-Lagrange): one forward and one reverse derivative, far
        # cheaper for optimizers to differentiate twice than the matrix Cm times qdot
        bias = ca.jtimes(mass @ qdot, q, qdot) - ca.gradient(0.5 * qdot.T @ mass @ qdot, q)
        lag, flow_force, generalized_flow, lag_rate = None, None, None, None
        if self.circulatory_flow is not None:
            # the flow's force moves to the left-hand side with the bias: Mm qddot + (Cm qdot - Q_flow) = B tau
            lag = ca.SX.sym("lag", self.n_lag)
            terms = self.circulatory_flow.terms(q2 @ qdot, lag)
            flow_force, lag_rate = terms.force, terms.lag_rate
            generalized_flow = q2.T @ flow_force
            bias = bias - generalized_flow
        extra, extra_names = ([lag], ["lag"]) if lag is not None else ([], [])
        acceleration = ca.solve(mass, input_map @ tau - bias)
        generalized_force = mass @ qddot + bias
        # partition (eqs. 14-15, 22-23)
        m11, m12 = mass[:ny, :ny], mass[:ny, ny:]
        m21, m22 = mass[ny:, :ny], mass[ny:, ny:]
        m11_inv_m12 = ca.solve(m11, m12)
        m11_inv_c1 = ca.solve(m11, bias[:ny])
        mio = m22 - m21 @ m11_inv_m12
        cio_qdot = bias[ny:] - m21 @ m11_inv_c1
        yddot = -(m11_inv_m12 @ u + m11_inv_c1)
        shape_qddot = ca.vertcat(yddot, u)
        shape_tau = mio @ u + cio_qdot
        energy = 0.5 * qdot.T @ mass @ qdot
        functions = {
            "mass_matrix": ca.Function("mass_matrix", [q], [mass], ["q"], ["Mm"]),
            "coriolis_matrix": ca.Function("coriolis_matrix", [q, qdot], [coriolis], ["q", "qdot"], ["Cm"]),
            "forward_dynamics": ca.Function("forward_dynamics", [q, qdot, tau, *extra], [acceleration],
                                            ["q", "qdot", "tau", *extra_names], ["qddot"]),
            "generalized_force": ca.Function("generalized_force", [q, qdot, qddot, *extra], [generalized_force],
                                             ["q", "qdot", "qddot", *extra_names], ["force"]),
            "kinetic_energy": ca.Function("kinetic_energy", [q, qdot], [energy], ["q", "qdot"], ["T"]),
            "momentum": ca.Function("momentum", [q, qdot], [mass @ qdot], ["q", "qdot"], ["p"]),
            "io_linearization": ca.Function("io_linearization", [q, qdot, *extra], [mio, cio_qdot],
                                            ["q", "qdot", *extra_names], ["Mio", "Cio_qdot"]),
            "shape_dynamics": ca.Function("shape_dynamics", [q, qdot, u, *extra], [shape_qddot, shape_tau],
                                          ["q", "qdot", "u", *extra_names], ["qddot", "tau"]),
            "foil_velocity_map": ca.Function("foil_velocity_map", [q], [q2], ["q"], ["Q2"]),
            "rigid_mass_matrix": ca.Function("rigid_mass_matrix", [q], [rigid], ["q"], ["M"]),
        }
        if lag is not None:
            # the circulatory flow sets these with lag
            assert flow_force is not None and generalized_flow is not None and lag_rate is not None
            functions["flow_force"] = ca.Function("flow_force", [q, qdot, lag], [flow_force, generalized_flow],
                                                  ["q", "qdot", "lag"], ["f", "Q_flow"])
            functions["lag_rate"] = ca.Function("lag_rate", [q, qdot, lag], [lag_rate],
                                                ["q", "qdot", "lag"], ["lag_dot"])
        return SymbolicModel(q=q, qdot=qdot, qddot=qddot, tau=tau, u=u, foil_velocity_map=q2,
                             rigid_mass=rigid, mass=mass, coriolis=coriolis, functions=functions, lag=lag,
                             flow_force=flow_force, generalized_flow_force=generalized_flow)

    def state_derivative_function(self) -> ca.Function:
        """The state equation for integrators.

        Returns
        -------
        casadi.Function
            f(x, tau) = (qdot, qddot[, lag_dot]) with x = (q, qdot[, lag]), (nx,), and tau (2,), N m.
        """
        s = self.symbolic
        if s.lag is None:
            x = ca.vertcat(s.q, s.qdot)
            qddot = s.functions["forward_dynamics"](s.q, s.qdot, s.tau)
            return ca.Function("state_derivative", [x, s.tau], [ca.vertcat(s.qdot, qddot)], ["x", "tau"], ["xdot"])
        x = ca.vertcat(s.q, s.qdot, s.lag)
        qddot = s.functions["forward_dynamics"](s.q, s.qdot, s.tau, s.lag)
        lag_dot = s.functions["lag_rate"](s.q, s.qdot, s.lag)
        return ca.Function("state_derivative", [x, s.tau], [ca.vertcat(s.qdot, qddot, lag_dot)], ["x", "tau"],
                           ["xdot"])

    def rk4_step_function(self) -> ca.Function:
        """One classical Runge-Kutta step with tau held, as a CasADi function.

        Returns
        -------
        casadi.Function
            (x (nx,), tau (2,) N m, h s) -> x(t + h), (nx,).
        """
        f = self.state_derivative_function()
        x, tau, h = ca.SX.sym("x", self.nx), ca.SX.sym("tau", 2), ca.SX.sym("h")
        k1 = f(x, tau)
        k2 = f(x + 0.5 * h * k1, tau)
        k3 = f(x + 0.5 * h * k2, tau)
        k4 = f(x + h * k3, tau)
        x_next = x + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        return ca.Function("rk4_step", [x, tau, h], [x_next], ["x", "tau", "h"], ["x_next"])

    def _rk4_chunk_functions(self, step: ca.Function) -> list[ca.Function]:
        """``rk4_steps_<n>`` for n in RK4_CHUNK_STEPS past 1: n RK4 steps in one function.

        (x, tau (2, n), h) -> the states after each of n steps of ``step`` (the RK4 step, tau[:, k] held over step
        k), (nx, n); generated as calls of the same step function, so they compute bit for bit what n calls of it
        do.
        """
        functions = []
        for steps in RK4_CHUNK_STEPS[1:]:
            x, tau, h = ca.MX.sym("x", self.nx), ca.MX.sym("tau", 2, steps), ca.MX.sym("h")
            states = step.mapaccum(steps)(x, tau, ca.repmat(h, 1, steps))
            functions.append(ca.Function(_rk4_chunk_name(steps), [x, tau, h], [states], ["x", "tau", "h"],
                                         ["states"]))
        return functions

    def foil_pose_function(self) -> ca.Function:
        """The foil frame's origin F and its chord's angle in the tank frame, as a CasADi function.

        The pose swim_model.wake.Wake.step takes. A CasADi SX function (map it over many q, or differentiate it); made
        once per model, not part of the compiled ``numeric`` set.

        Returns
        -------
        casadi.Function
            q (nq,) -> (x_F m, y_F m, chord angle alpha + theta + pi/2 rad).
        """
        cache: dict[str, ca.Function] = self.__dict__.setdefault("_foil_pose", {})
        if "pose" not in cache:
            q = self.symbolic.q
            coords = self.coordinates(q)
            pose = ca.vertcat(foil_reference_point(coords, self.rig),
                              coords.alpha + coords.theta + FOIL_CHORD_ANGLE_OFFSET_RAD)
            cache["pose"] = ca.Function("foil_pose", [q], [pose], ["q"], ["pose"])
        return cache["pose"]

    def foil_pose(self, q: npt.ArrayLike) -> Array:
        """The foil frame's pose in the tank frame (``foil_pose_function``).

        Parameters
        ----------
        q : (nq,) array_like
            Configuration of the rig, rad and m.

        Returns
        -------
        (3,) ndarray
            (x_F m, y_F m, chord angle rad).
        """
        return np.asarray(self.foil_pose_function()(self._vector(q, self.nq, "q")), dtype=float).reshape(-1)

    # ----- numeric path ----------------------------------------------------------------------------
    @cached_property
    def numeric(self) -> dict[str, ca.Function]:
        """The symbolic functions compiled to C (cached on disk), plus the RK4 step."""
        return codegen.compiled(self._numeric_functions(), tag=self._codegen_tag())

    def native_function(self, name: str) -> codegen.NativeFunction:
        """One of ``numeric``'s functions called through its C entry point on buffers it owns.

        The same numbers as ``numeric[name]``, ~1 us a call instead of CasADi's ~45 us, for loops that call it every
        period. One instance per name and model: copy what you keep of its outputs.

        Parameters
        ----------
        name : str
            The function's name in ``numeric`` (dense arguments only).

        Returns
        -------
        codegen.NativeFunction
            Fill its ``inputs`` buffers, call it, read its ``outputs``.
        """
        # made on first use, like ``numeric``
        loaded: dict[str, codegen.NativeFunction] = self.__dict__.setdefault("_native", {})
        if name not in loaded:
            loaded.update(codegen.native(self._numeric_functions(), self._codegen_tag(), names=[name]))
        return loaded[name]

    def _numeric_functions(self) -> list[ca.Function]:
        functions = dict(self.symbolic.functions)
        functions["rk4_step"] = step = self.rk4_step_function()
        return [*functions.values(), *self._rk4_chunk_functions(step)]

    def _codegen_tag(self) -> str:
        kind = "constrained" if self.constrained else "free"
        key = f"{self.rig.digest()}:{self.lane_radius_m!r}".encode()
        if self.circulatory_flow is not None:
            key += f":circulatory:{self.circulatory_flow.params.digest()}".encode()
            kind += "_circulatory"
        return f"vehicle_{kind}_{hashlib.sha256(key).hexdigest()[:16]}"

    def _vector(self, value: npt.ArrayLike, size: int, name: str) -> Array:
        array = np.asarray(value, dtype=float).reshape(-1)
        if array.shape != (size,):
            if size == self.nq:
                names = ", ".join(self.joint_names)
            elif name == "lag":
                names = ", ".join(self.lag_names)
            elif name == "x":
                names = f"q, qdot{', lag' if self.n_lag else ''}"
            else:
                names = "heave, pitch"
            raise StateError(f"{name} must have {size} entries ({names}), got shape {np.shape(value)}")
        if not np.all(np.isfinite(array)):
            raise StateError(f"{name} has a non-finite entry: {array}")
        return array

    def _lag(self, lag: npt.ArrayLike | None) -> list[Array]:
        """The lag argument as the compiled functions take it: none for the ideal flow, checked for the other."""
        if self.n_lag == 0:
            if lag is not None and np.size(lag) != 0:
                raise StateError("the ideal-flow model has no lag states: call it without lag "
                                 "(VehicleModel(..., flow='circulatory') has them)")
            return []
        if lag is None:
            raise StateError(f"flow='circulatory' needs the flow's lag states: lag=({', '.join(self.lag_names)}), "
                             "m/s (zeros for a flow at rest)")
        return [self._vector(lag, self.n_lag, "lag")]

    def _require_circulatory(self, method: str, missing: str) -> None:
        """Refuse a method of the circulatory flow's on the ideal-flow model, which has no ``missing``."""
        if self.n_lag == 0:
            raise StateError(f"{method}: the ideal-flow model has no {missing}")

    def _call(self, name: str, *args: Array) -> Sequence[Array]:
        outputs = self.numeric[name].call(list(args))
        return [np.asarray(o, dtype=float) for o in outputs]

    def mass_matrix(self, q: npt.ArrayLike) -> Array:
        """Mm(q), the mass matrix with the fluid's added mass (eq. 41).

        Parameters
        ----------
        q : (nq,) array_like
            Configuration, rad and m.

        Returns
        -------
        (nq, nq) ndarray
            Mm, kg, kg m and kg m^2 by entry.

        Raises
        ------
        StateError
            For a q of the wrong length or with a non-finite entry (as every numeric method).
        """
        return self._call("mass_matrix", self._vector(q, self.nq, "q"))[0]

    def coriolis_matrix(self, q: npt.ArrayLike, qdot: npt.ArrayLike) -> Array:
        """Cm(q, qdot), linear in qdot (eq. 6).

        Parameters
        ----------
        q, qdot : (nq,) array_like
            Configuration (rad and m) and velocity (rad/s and m/s).

        Returns
        -------
        (nq, nq) ndarray
            Cm, so that Cm qdot is in N and N m by row.
        """
        return self._call("coriolis_matrix", self._vector(q, self.nq, "q"), self._vector(qdot, self.nq, "qdot"))[0]

    def forward_dynamics(self, q: npt.ArrayLike, qdot: npt.ArrayLike, tau: npt.ArrayLike,
                         lag: npt.ArrayLike | None = None) -> Array:
        """Qddot = Mm^-1 (B tau - Cm qdot [+ Q_flow]) (eqs. 6-7).

        Parameters
        ----------
        q, qdot : (nq,) array_like
            The state: configuration, rad and m, and velocity, rad/s and m/s.
        tau : (2,) array_like
            Joint torques (heave, pitch), N m.
        lag : (n_lag,) array_like, optional
            The flow's lag states, m/s (circulatory flow only, and required there).

        Returns
        -------
        (nq,) ndarray
            qddot, rad/s^2 and m/s^2.
        """
        out = self._call("forward_dynamics", self._vector(q, self.nq, "q"), self._vector(qdot, self.nq, "qdot"),
                         self._vector(tau, 2, "tau"), *self._lag(lag))[0]
        return out.reshape(-1)

    def generalized_force(self, q: npt.ArrayLike, qdot: npt.ArrayLike, qddot: npt.ArrayLike,
                          lag: npt.ArrayLike | None = None) -> Array:
        """Mm qddot + Cm qdot [- Q_flow]: the force the joints must supply on every coordinate.

        Zero on the unactuated coordinates when the motion is feasible.

        Parameters
        ----------
        q, qdot, qddot : (nq,) array_like
            Configuration, velocity and acceleration: rad and m, then per s, then per s^2.
        lag : (n_lag,) array_like, optional
            The flow's lag states, m/s (circulatory flow only).

        Returns
        -------
        (nq,) ndarray
            Generalized force, N m and N by coordinate.
        """
        return self._call("generalized_force", self._vector(q, self.nq, "q"), self._vector(qdot, self.nq, "qdot"),
                          self._vector(qddot, self.nq, "qddot"), *self._lag(lag))[0].reshape(-1)

    def inverse_dynamics(self, q: npt.ArrayLike, qdot: npt.ArrayLike, qddot: npt.ArrayLike,
                         lag: npt.ArrayLike | None = None) -> Array:
        """Tau = (Mm qddot + Cm qdot [- Q_flow]) on the actuated rows (heave, pitch).

        Parameters
        ----------
        q, qdot, qddot, lag
            As for ``generalized_force``, whose actuated rows this is.

        Returns
        -------
        (2,) ndarray
            Joint torques (heave, pitch), N m.
        """
        return self.generalized_force(q, qdot, qddot, lag)[self.n_unactuated:]

    def kinetic_energy(self, q: npt.ArrayLike, qdot: npt.ArrayLike, lag: npt.ArrayLike | None = None) -> float:
        """T = 1/2 qdot' Mm qdot (eq. 5).

        Parameters
        ----------
        q, qdot : (nq,) array_like
            Configuration and velocity, rad and m, rad/s and m/s.
        lag : (n_lag,) array_like, optional
            The flow's lag states, m/s: they hold no energy, so ``lag`` is only checked.

        Returns
        -------
        float
            T, J.
        """
        if lag is not None:
            self._lag(lag)
        energy = self._call("kinetic_energy", self._vector(q, self.nq, "q"), self._vector(qdot, self.nq, "qdot"))[0]
        return energy.item()

    def momentum(self, q: npt.ArrayLike, qdot: npt.ArrayLike, lag: npt.ArrayLike | None = None) -> Array:
        """Generalized momentum p = dT/dqdot = Mm qdot.

        p[0] = p_alpha is conserved (Prop. 1) by the ideal model and changes at Q_flow[0] with the circulatory flow.

        Parameters
        ----------
        q, qdot : (nq,) array_like
            The state at which p is taken: rad and m, rad/s and m/s.
        lag : (n_lag,) array_like, optional
            The flow's lag states, m/s: they hold no momentum, so ``lag`` is only checked.

        Returns
        -------
        (nq,) ndarray
            p, kg m^2/s and kg m/s by coordinate.
        """
        if lag is not None:
            self._lag(lag)
        return self._call("momentum", self._vector(q, self.nq, "q"), self._vector(qdot, self.nq, "qdot"))[0].reshape(-1)

    def io_linearization(self, q: npt.ArrayLike, qdot: npt.ArrayLike,
                         lag: npt.ArrayLike | None = None) -> tuple[Array, Array]:
        """(Mio, Cio qdot) of eqs. 22-23: tau = Mio psiddot + Cio qdot.

        Parameters
        ----------
        q, qdot : (nq,) array_like
            The state Mio and Cio are evaluated at (rad and m, rad/s and m/s).
        lag : (n_lag,) array_like, optional
            The flow's lag states, m/s (circulatory flow only): the flow's force enters Cio qdot.

        Returns
        -------
        mio : (2, 2) ndarray
            Mio = Mm22 - Mm21 Mm11^-1 Mm12, kg m^2.
        cio_qdot : (2,) ndarray
            Cio qdot, N m (includes the flow's force).
        """
        mio, cio = self._call("io_linearization", self._vector(q, self.nq, "q"), self._vector(qdot, self.nq, "qdot"),
                              *self._lag(lag))
        return mio, cio.reshape(-1)

    def shape_dynamics(self, q: npt.ArrayLike, qdot: npt.ArrayLike, psi_ddot: npt.ArrayLike,
                       lag: npt.ArrayLike | None = None) -> tuple[Array, Array]:
        """(qddot, tau) with the foil accelerations u = psiddot prescribed (eqs. 14-15).

        Parameters
        ----------
        q, qdot : (nq,) array_like
            The state (rad and m, rad/s and m/s), as in the class docstring.
        psi_ddot : (2,) array_like
            (phiddot, thetaddot), rad/s^2.
        lag : (n_lag,) array_like, optional
            The flow's lag states, m/s (circulatory flow only).

        Returns
        -------
        qddot : (nq,) ndarray
            Acceleration, rad/s^2 and m/s^2.
        tau : (2,) ndarray
            Joint torques (heave, pitch), N m.
        """
        qddot, tau = self._call("shape_dynamics", self._vector(q, self.nq, "q"),
                                self._vector(qdot, self.nq, "qdot"), self._vector(psi_ddot, 2, "psi_ddot"),
                                *self._lag(lag))
        return qddot.reshape(-1), tau.reshape(-1)

    def foil_velocity_map(self, q: npt.ArrayLike) -> Array:
        """Q2(q): (U, V, Omega) = Q2 qdot (eq. 40).

        Parameters
        ----------
        q : (nq,) array_like
            Configuration at which Q2 is taken, rad and m.

        Returns
        -------
        (3, nq) ndarray
            Q2: maps qdot to the foil frame's (U m/s, V m/s, Omega rad/s) in foil axes.
        """
        return self._call("foil_velocity_map", self._vector(q, self.nq, "q"))[0]

    def angle_of_attack(self, q: npt.ArrayLike, qdot: npt.ArrayLike) -> float:
        """atan2(-V, U) of the foil frame's velocity in foil axes (eq. 40; swim_model.flow.angle_of_attack).

        Parameters
        ----------
        q, qdot : (nq,) array_like
            The state at which the foil's velocity Q2(q) qdot is taken: rad and m, rad/s and m/s.

        Returns
        -------
        float
            Angle of attack, rad.
        """
        u, v, _ = self.foil_velocity_map(q) @ self._vector(qdot, self.nq, "qdot")
        return math.atan2(-v, u)

    def flow_force(self, q: npt.ArrayLike, qdot: npt.ArrayLike, lag: npt.ArrayLike) -> tuple[Array, Array]:
        """The circulatory flow's force on the foil and its generalized force.

        Parameters
        ----------
        q, qdot : (nq,) array_like
            Configuration and velocity; the foil's velocity Q2(q) qdot sets the flow.
        lag : (n_lag,) array_like
            The flow's lag states, m/s.

        Returns
        -------
        force : (3,) ndarray
            (fx N, fy N, mz N m) in foil axes at the foil frame's origin.
        generalized : (nq,) ndarray
            Q_flow = Q2' f, N m and N by coordinate.

        Raises
        ------
        StateError
            On the ideal-flow model, which has no circulatory force.
        """
        self._require_circulatory("flow_force", "circulatory force")
        f, generalized = self._call("flow_force", self._vector(q, self.nq, "q"), self._vector(qdot, self.nq, "qdot"),
                                    *self._lag(lag))
        return f.reshape(-1), generalized.reshape(-1)

    def lag_rate(self, q: npt.ArrayLike, qdot: npt.ArrayLike, lag: npt.ArrayLike) -> Array:
        """d(lag)/dt of Jones's two-state Wagner lag (swim_model.flow).

        Parameters
        ----------
        q, qdot, lag
            The state, as for ``flow_force``.

        Returns
        -------
        (n_lag,) ndarray
            Lag rate, m/s^2.

        Raises
        ------
        StateError
            On the ideal-flow model, which has no lag states.
        """
        self._require_circulatory("lag_rate", "lag states")
        return self._call("lag_rate", self._vector(q, self.nq, "q"), self._vector(qdot, self.nq, "qdot"),
                          *self._lag(lag))[0].reshape(-1)

    def rk4_step(self, q: npt.ArrayLike, qdot: npt.ArrayLike, tau: npt.ArrayLike, step_s: float,
                 lag: npt.ArrayLike | None = None) -> tuple[Array, ...]:
        """One RK4 step with tau held.

        Parameters
        ----------
        q, qdot : (nq,) array_like
            The state at the step's start, rad and m, rad/s and m/s.
        tau : (2,) array_like
            Joint torques (heave, pitch), N m.
        step_s : float
            Step length, s.
        lag : (n_lag,) array_like, optional
            The lag states at the step's start, m/s (circulatory flow only).

        Returns
        -------
        tuple of ndarray
            (q, qdot) after the step, each (nq,); with the circulatory flow (q, qdot, lag), lag (n_lag,).
        """
        x = np.concatenate([self._vector(q, self.nq, "q"), self._vector(qdot, self.nq, "qdot"), *self._lag(lag)])
        x_next = self._call("rk4_step", x, self._vector(tau, 2, "tau"), np.array(float(step_s)))[0].reshape(-1)
        return self._split(x_next)

    def _split(self, x: Array) -> tuple[Array, ...]:
        nq = self.nq
        if self.n_lag == 0:
            return x[..., :nq], x[..., nq:]
        return x[..., :nq], x[..., nq:2 * nq], x[..., 2 * nq:]

    def integrate_rk4(self, q: npt.ArrayLike, qdot: npt.ArrayLike, torques: npt.ArrayLike,
                      step_s: float, lag: npt.ArrayLike | None = None) -> tuple[Array, ...]:
        """RK4 steps of step_s seconds, torques[k] held over step k, in a few compiled calls.

        The steps are the compiled ``rk4_step``'s, bit for bit (chunks of RK4_CHUNK_STEPS steps called on buffers).
        Safe to call from several threads (the chunks' buffers are used by one call at a time).

        Parameters
        ----------
        q : (nq,) array_like
            Initial configuration, rad and m.
        qdot : (nq,) array_like
            Initial velocity, rad/s and m/s.
        torques : (n, 2) array_like
            Heave and pitch torques, N m.
        step_s : float
            Step length, s.
        lag : (n_lag,) array_like, optional
            The flow's lag states at the start, m/s (circulatory flow only).

        Returns
        -------
        tuple of ndarray
            (q, qdot) at the n + 1 step boundaries, shapes (n + 1, nq); with the circulatory flow (q, qdot, lag), lag
            of shape (n + 1, n_lag).

        Raises
        ------
        StateError
            For torques that are not a finite (n, 2) array, or a bad initial state.
        """
        torque_array = np.asarray(torques, dtype=float)
        if torque_array.ndim != 2 or torque_array.shape[1] != 2 or not np.all(np.isfinite(torque_array)):
            raise StateError(f"torques must be a finite (n, 2) array, got shape {torque_array.shape}")
        x0 = np.concatenate([self._vector(q, self.nq, "q"), self._vector(qdot, self.nq, "qdot"), *self._lag(lag)])
        steps = len(torque_array)
        trajectory = np.empty((steps + 1, self.nx))
        trajectory[0] = x0
        step = float(step_s)
        # the chunks' buffers are shared by every call on this model: one call at a time
        with self.__dict__.setdefault("_rk4_lock", threading.Lock()):
            chunks = self._rk4_chunks()
            done = 0
            while done < steps:
                size = min(1 << ((steps - done).bit_length() - 1), RK4_CHUNK_STEPS[-1])
                chunk = chunks[size]
                chunk.inputs[0][:] = trajectory[done]
                chunk.inputs[1][:] = torque_array[done:done + size].ravel()   # (2, size) column-major
                chunk.inputs[2][0] = step
                chunk()
                trajectory[done + 1:done + size + 1] = chunk.outputs[0].reshape(size, self.nx)
                done += size
        return self._split(trajectory)

    def _rk4_chunks(self) -> dict[int, codegen.NativeFunction]:
        """integrate_rk4's compiled chunks by step count, with buffers of their own.

        Not native_function's, which callers fill between their own calls.
        """
        chunks: dict[int, codegen.NativeFunction] | None = self.__dict__.get("_rk4_chunk_cache")
        if chunks is None:
            names = {steps: _rk4_chunk_name(steps) for steps in RK4_CHUNK_STEPS}
            loaded = codegen.native(self._numeric_functions(), self._codegen_tag(), names=list(names.values()))
            chunks = self.__dict__["_rk4_chunk_cache"] = {steps: loaded[name] for steps, name in names.items()}
        return chunks

    def torque_limits(self) -> Array:
        """(heave, pitch) joint torque limits, N m (paper Sec. 2)."""
        return np.array(self.rig.torque_limits_n_m)


def _rk4_chunk_name(steps: int) -> str:
    """The compiled function of ``steps`` RK4 steps: the step itself for one."""
    return "rk4_step" if steps == 1 else f"rk4_steps_{steps}"
