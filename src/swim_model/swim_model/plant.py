"""The simulated vehicle: swim_model's dynamics plus the disturbances, one control period at a time. No ROS.

The one plant of the workspace: swim_sim's simulator steps it a fixed control period at a time, swim_hw_bridge's
emulated rig one read interval at a time (``Plant.step``'s period_s). ``PlantSettings`` are what either builds it
with (``make_plant``). The equations it integrates over a period (the held torque, the RK4 substeps, dry
friction's switch model, the flows, the hard stops) are in docs/disturbances.md, "How the plant applies them";
what keeps a period cheap is in docs/speed.md, "The plant alone".
"""
from __future__ import annotations

import dataclasses
import hashlib
import math
from typing import Optional

import casadi as ca
import numpy as np
import numpy.typing as npt

from swim_model import RigParameters, StateError, VehicleModel, codegen
from swim_model.disturbances import GRAVITY_M_S2, Disturbances
from swim_model.flow import FLOWS
from swim_model.limits import HardLimits
from swim_model.wake import compile_kernels
from swim_model.wake_coupling import WakeCoupling, WakeCouplingParameters, separation_drag

Array = npt.NDArray[np.float64]

#: a velocity this large (rad/s or m/s) is numerical blow-up, not swimming: the rig's fastest joint (pitch)
#: reaches about 10 rad/s (assumed bound, 100x that)
BLOW_UP_SPEED = 1.0e3


class SimulationError(RuntimeError):
    """The integration blew up (non-finite or absurd state): the simulator stops instead of publishing it.

    A state is absurd when a speed or lag state exceeds ``BLOW_UP_SPEED``.
    """


@dataclasses.dataclass(frozen=True)
class PlantState:
    """The plant's state at the end of a period, a copy (``Plant.state``, ``Plant.step``).

    Attributes
    ----------
    time_s : float
        Simulated time, s.
    q : (nq,) ndarray
        Configuration (alpha, [R,] phi, theta), rad and m.
    qdot : (nq,) ndarray
        Velocity, rad/s and m/s.
    torque : (2,) ndarray
        Joint torques (heave, pitch) applied over the last period, after the motor limits, N m.
    saturated : tuple of (bool, bool)
        Whether the heave and pitch commands were clipped at their motor limits over the last period.
    lag : (n_lag,) ndarray
        The circulatory flow's lag states z (``VehicleModel.lag_names``), m/s; empty for the ideal and wake flows.
    """

    time_s: float
    q: Array
    qdot: Array
    torque: Array               # the torque applied over the last period (after the limits), N m
    saturated: tuple[bool, bool]
    lag: Array = dataclasses.field(default_factory=lambda: np.zeros(0))
    # the circulatory flow's lag states z (VehicleModel.lag_names), m/s; empty for the ideal and wake flows


def vehicle_model(flow: str, rig: Optional[RigParameters] = None, constrained: bool = False,
                  lane_radius_m: Optional[float] = None) -> VehicleModel:
    """The VehicleModel a plant of this flow integrates.

    The circulatory model for "circulatory", else the ideal one (the wake's force is added by the plant).

    Parameters
    ----------
    flow : {"ideal", "circulatory", "wake"}
        One of swim_model.flow's FLOWS.
    rig : RigParameters, optional
        Rig parameters (default: the shipped rig file).
    constrained : bool, optional
        Lock the rails: q = (alpha, phi, theta).
    lane_radius_m : float, optional
        R of the locked rails, m (default: the rig's ``constrained_lane_radius_m``).

    Returns
    -------
    VehicleModel
        The model of ``FLOWS[flow]``.

    Raises
    ------
    ValueError
        For a flow not in FLOWS.
    """
    _check_flow(flow)
    return VehicleModel(rig, constrained=constrained, lane_radius_m=lane_radius_m, flow=FLOWS[flow])


def _check_flow(flow: str) -> None:
    """Raise ValueError naming FLOWS unless flow is one of them."""
    if flow not in FLOWS:
        raise ValueError(f"flow must be one of {', '.join(FLOWS)}, got {flow!r}")


def _parameter_vector(model: VehicleModel, disturbances: Disturbances, foil_drag: bool = True) -> Array:
    """Parameter vector of the compiled dynamics.

    p = (b per coordinate, k_foil_U, k_foil_V, k_platform, m g sin(tilt), tilt direction); the foil's drag
    factors k_foil zero without foil_drag (the circulatory flow carries its own).
    """
    rig = model.rig
    viscous = np.zeros(model.nq)
    viscous[0] = disturbances.hub_viscous_n_m_s
    if not model.constrained:
        viscous[1] = disturbances.rail_viscous_n_s_m
    half_rho = 0.5 * rig.water_density_kg_m3
    planform_m2 = rig.foil_chord_m * rig.foil_span_m if foil_drag else 0.0
    moving_mass_kg = rig.platform_mass_kg + rig.heave_link_mass_kg + rig.foil_assembly_mass_kg
    return np.concatenate([viscous, [
        half_rho * disturbances.foil_axial_drag_coefficient * planform_m2,
        half_rho * disturbances.foil_normal_drag_coefficient * planform_m2,
        half_rho * disturbances.platform_drag_area_m2,
        moving_mass_kg * GRAVITY_M_S2 * math.sin(disturbances.tilt_rad),
        disturbances.tilt_direction_rad]])


def _dynamics(model: VehicleModel, substeps: int) -> list[ca.Function]:
    """The plant's compiled functions, symbolic.

    The RK4 step, the force holding stopped coordinates, the tilt's potential energy, the wave force's shape and
    the whole period with and without a lock mask. The state is x = (q, qdot), or (q, qdot, z) with the
    circulatory flow (the flow's force in the bias, z's rate appended).
    """
    s = model.symbolic
    nq = model.nq
    q, qdot, tau = s.q, s.qdot, s.tau
    held = ca.SX.sym("f_held", nq)
    p = ca.SX.sym("p", nq + 5)
    coords = model.coordinates(q)
    foil_force = separation_drag(s.foil_velocity_map @ qdot, p[nq:nq + 2])
    radial_rate = ca.SX(0) if model.constrained else qdot[1]
    tangential = coords.radius * qdot[0]
    platform_speed = ca.sqrt(tangential ** 2 + radial_rate ** 2 + 1e-12)
    platform = ca.SX.zeros(nq)
    platform[0] = -p[nq + 2] * platform_speed * tangential * coords.radius
    tilt = ca.SX.zeros(nq)
    tilt[0] = p[nq + 3] * coords.radius * ca.sin(coords.alpha - p[nq + 4])
    if not model.constrained:
        platform[1] = -p[nq + 2] * platform_speed * radial_rate
        tilt[1] = -p[nq + 3] * ca.cos(coords.alpha - p[nq + 4])
    input_map = ca.vertcat(ca.SX.zeros(nq - 2, 2), ca.SX.eye(2))
    force = (input_map @ tau - p[:nq] * qdot + s.foil_velocity_map.T @ foil_force + platform + tilt + held)
    lag = [] if s.lag is None else [s.lag]
    bias = s.functions["generalized_force"](q, qdot, ca.SX.zeros(nq), *lag)   # Cm qdot [- Q_flow]
    free_qddot = ca.solve(s.mass, force - bias)
    # stopped coordinates (lock = 1) held by the constraint force lambda that makes their qddot zero:
    # (D Mm^-1 D + I - D) lambda = -D qddot_free, qddot = qddot_free + Mm^-1 D lambda, D = diag(lock)
    lock = ca.SX.sym("lock", nq)
    locked = ca.diag(lock)
    inverse_mass = ca.inv(s.mass)
    hold_force = ca.solve(locked @ inverse_mass @ locked + ca.SX.eye(nq) - locked, -locked @ free_qddot)
    qddot = free_qddot + inverse_mass @ locked @ hold_force
    x, h = ca.vertcat(q, qdot, *lag), ca.SX.sym("h")
    rates = [s.functions["lag_rate"](q, qdot, *lag)] if lag else []
    f = ca.Function("f", [x, tau, held, p, lock], [ca.vertcat(qdot, qddot, *rates)])
    k1 = f(x, tau, held, p, lock)
    k2 = f(x + 0.5 * h * k1, tau, held, p, lock)
    k3 = f(x + 0.5 * h * k2, tau, held, p, lock)
    k4 = f(x + h * k3, tau, held, p, lock)
    step = ca.Function("sim_rk4_step", [x, tau, held, p, lock, h], [x + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)])
    forward = ca.Function("sim_forward", [x, tau, held, p, lock], [hold_force])
    potential = ca.Function("sim_potential", [q, p], [p[nq + 3] * coords.radius * ca.cos(coords.alpha - p[nq + 4])])
    # the same step with no coordinate locked: the lock algebra drops out (exactly: it only ever added zeros)
    free_step = ca.Function("sim_rk4_step_unlocked", [x, tau, held, p, h],
                            [step(x, tau, held, p, ca.SX.zeros(nq), h)])
    # the wave force Q2' (0, c |v_foil|^2 w, 0) for a coefficient c and the filtered noise's value w
    coefficient, level = ca.SX.sym("coefficient"), ca.SX.sym("level")
    foil_velocity = s.foil_velocity_map @ qdot
    speed2 = foil_velocity[0] ** 2 + foil_velocity[1] ** 2
    wave = ca.Function("sim_wave_force", [q, qdot, coefficient, level],
                       [s.foil_velocity_map[1, :].T * (coefficient * speed2 * level)])
    # Mm(q) for the plastic impulse that stops a coordinate (here, not the model's own numeric functions: those
    # would be generated and loaded in the middle of a run, at the first stop, ~0.1 s)
    mass = ca.Function("sim_mass_matrix", [q], [s.mass])
    nx = model.nx
    return [step, forward, potential, wave, _period(step, "sim_period_locked", nq, nx, substeps),
            _period(free_step, "sim_period_unlocked", nq, nx, substeps), mass]


def _period(step: ca.Function, name: str, nq: int, nx: int, substeps: int) -> ca.Function:
    """Chain substeps steps with the inputs held into one function of the period.

    (x, tau, held, p, [lock,] h) -> (x at the end, crossing, highest, lowest), where crossing[i] is the smallest
    qdot_i(t_k) sign(qdot_i(t_0)) over the substeps: <= 0 where a velocity reached or crossed zero inside the
    period, and highest[i], lowest[i] are the largest and smallest q_i(t_k) over the substeps (past a hard stop:
    the plant then redoes the period substep by substep).
    """
    x0 = ca.MX.sym("x", nx)
    held_inputs = [ca.MX.sym(n, *step.size_in(i)) for i, n in enumerate(step.name_in()) if i > 0]
    states = step.mapaccum(substeps)(x0, *(ca.repmat(v, 1, substeps) for v in held_inputs))
    start_sign = ca.copysign(1.0, x0[nq:])
    crossing = ca.vertcat(*(ca.mmin(states[nq + i, :] * start_sign[i]) for i in range(nq)))
    highest = ca.vertcat(*(ca.mmax(states[i, :]) for i in range(nq)))
    lowest = ca.vertcat(*(ca.mmin(states[i, :]) for i in range(nq)))
    return ca.Function(name, [x0, *held_inputs], [states[:, -1], crossing, highest, lowest])


class Plant:
    """The vehicle and its disturbances, stepped by control periods. Deterministic for a seed.

    Each period holds the torque, clips it at the motor limits and integrates ``substeps`` RK4 steps of the
    vehicle's equations of motion (paper eqs. 6-7) with the disturbances' forces, dry friction's stick-slip and the
    joints' inelastic hard stops (docs/disturbances.md, "How the plant applies them").

    Parameters
    ----------
    model : VehicleModel
        The vehicle (``vehicle_model(flow, ...)`` makes the one a flow needs: the circulatory flow integrates
        VehicleModel(flow="circulatory"), the others the ideal one).
    disturbances : Disturbances, optional
        Sizes of the disturbances (default: the physical ones, ``Disturbances()``).
    sample_period_s : float, optional
        The control period ``step`` integrates by default, s (default: the rig's ``sample_period_s``).
    substeps : int, optional
        Classical RK4 steps per period, >= 1.
    seed : int, optional
        Seed of the surface waves' noise; ``reset`` restarts it.
    wake : WakeCoupling, optional
        The vortex wake's coupling for flow "wake" (default: built with WakeCouplingParameters' defaults).
    hard_limits_rad : HardLimits, optional
        The joints' hard stops ((heave lower, upper), (pitch lower, upper)), rad (default: no stops).
    flow : {"ideal", "circulatory", "wake"}, optional
        One of swim_model.flow's FLOWS (default: taken from the arguments, "circulatory" for a circulatory model,
        "wake" with a wake, else "ideal").

    Attributes
    ----------
    flow : str
        The flow the plant integrates, one of FLOWS.
    model : VehicleModel
        The vehicle.
    disturbances : Disturbances
        Sizes of the disturbances.
    wake : WakeCoupling or None
        The vortex wake's force, held over each period (swim_model.wake_coupling); None: off.
    sample_period_s : float
        The default period of ``step``, s.
    substeps : int
        RK4 steps per period.
    seed : int
        Seed of the waves' noise.
    time_s : float
        Simulated time, s.
    q, qdot : (nq,) ndarray
        Configuration (rad and m) and velocity (rad/s and m/s).
    lag : (n_lag,) ndarray
        The circulatory flow's lag states, m/s (empty for the other flows).
    torque : (2,) ndarray
        Joint torques (heave, pitch) applied over the last period, N m.
    saturated : tuple of (bool, bool)
        Whether the heave and pitch commands were clipped over the last period.
    stuck : dict of int to bool
        Coordinate index -> whether dry friction holds it at rest.
    at_stop : dict of int to int
        Joint index -> +1 held at its upper hard stop, -1 at its lower one, 0 free.
    rng : numpy.random.Generator
        The waves' noise.

    Raises
    ------
    ValueError
        For invalid disturbances, a flow not in FLOWS, a model or a wake that does not fit the flow, a hard stop
        without finite limits lower < upper, a sample period <= 0 or substeps < 1.
    """

    def __init__(self, model: VehicleModel, disturbances: Disturbances = Disturbances(),
                 sample_period_s: Optional[float] = None, substeps: int = 8, seed: int = 0,
                 wake: Optional[WakeCoupling] = None, hard_limits_rad: Optional[HardLimits] = None,
                 flow: Optional[str] = None) -> None:
        disturbances.validate()
        if flow is None:
            flow = "circulatory" if model.flow == "circulatory" else "wake" if wake is not None else "ideal"
        _check_flow(flow)
        if model.flow != FLOWS[flow]:
            raise ValueError(f"flow {flow!r} integrates VehicleModel(flow={FLOWS[flow]!r}), got a model of "
                             f"flow {model.flow!r} (vehicle_model makes the right one)")
        if wake is not None and flow != "wake":
            raise ValueError(f"a wake coupling is for flow 'wake', not {flow!r}")
        if flow == "wake" and wake is None:
            wake = WakeCoupling(model)
        self.flow = flow
        # joint index -> (lower, upper) of each hard stop
        self._stops: dict[int, tuple[float, float]] = {}
        if hard_limits_rad is not None:
            for index, (lower, upper) in zip((model.nq - 2, model.nq - 1), hard_limits_rad):
                if not (math.isfinite(lower) and math.isfinite(upper) and lower < upper):
                    raise ValueError(f"a hard stop needs finite limits lower < upper, got ({lower}, {upper})")
                self._stops[index] = (float(lower), float(upper))
        self.wake = wake   # the vortex wake's force, held over each period (wake_coupling.py); None: off
        self.model, self.disturbances = model, disturbances
        self.sample_period_s = float(sample_period_s or model.rig.sample_period_s)
        if not (self.sample_period_s > 0.0 and substeps >= 1):
            raise ValueError("the sample period must be > 0 and substeps >= 1")
        self.substeps = int(substeps)
        self._parameters = _parameter_vector(model, disturbances, foil_drag=flow != "circulatory")
        tag = f"sim_{model._codegen_tag()}_{hashlib.sha256(b'sim-dynamics-3').hexdigest()[:8]}"
        native = codegen.native(_dynamics(model, self.substeps), tag=tag)
        (self._step, self._forward, self._potential, self._wave, self._period_locked, self._period_unlocked,
         self._mass) = (native[n] for n in ("sim_rk4_step", "sim_forward", "sim_potential", "sim_wave_force",
                                            "sim_period_locked", "sim_period_unlocked", "sim_mass_matrix"))
        # the inputs that never change: parameters, the wave's coefficient; the substep length is the period's
        for function in (self._step, self._period_locked, self._period_unlocked):
            function.inputs[3][:] = self._parameters
        self._period_s = 0.0   # the period the substep length in the compiled inputs is for
        self._set_period(self.sample_period_s)
        self._forward.inputs[3][:] = self._parameters
        self._potential.inputs[1][:] = self._parameters
        self._wave.inputs[2][0] = disturbances.wave_force_per_speed2_n_s2_m2
        self._dry = disturbances.coulomb_and_static(model.constrained)
        self._limits = model.torque_limits()
        self.seed = seed
        self.lag = np.zeros(model.n_lag)
        self.reset(self.rest_positions(), np.zeros(model.nq))

    def rest_positions(self) -> Array:
        """Configuration of the vehicle at rest at the origin.

        Returns
        -------
        (nq,) ndarray
            q with every coordinate zero and R (free vehicle) on its lane, rad and m.
        """
        q = np.zeros(self.model.nq)
        if not self.model.constrained:
            q[1] = self.model.lane_radius_m
        return q

    # ----- state ---------------------------------------------------------------------------------
    @property
    def hard_limits_rad(self) -> dict[str, tuple[float, float]]:
        """Joint name -> (lower, upper) of its hard stop, rad (empty: no stops).

        Returns
        -------
        dict of str to (float, float)
            The stops by joint name ("phi", "theta"), rad.
        """
        return {self.model.joint_names[i]: limits for i, limits in self._stops.items()}

    def reset(self, q: npt.ArrayLike, qdot: npt.ArrayLike, time_s: float = 0.0,
              lag: Optional[npt.ArrayLike] = None) -> None:
        """Put the vehicle at (q, qdot) and restart the noise and the wake.

        The noise restarts from the seed and the wake from rest, so runs repeat bit for bit; a prepared period
        (``prepare_period``) is discarded.

        Parameters
        ----------
        q : (nq,) array_like
            Configuration, rad and m.
        qdot : (nq,) array_like
            Velocity, rad/s and m/s.
        time_s : float, optional
            Simulated time, s.
        lag : (n_lag,) array_like, optional
            The circulatory flow's lag states, m/s (default: zeros, the flow at rest; the other flows have none).

        Raises
        ------
        StateError
            For a non-finite entry, a wrong size or a joint past its hard stop; nothing changes then.
        """
        q, qdot = (self.model._vector(v, self.model.nq, n) for v, n in ((q, "q"), (qdot, "qdot")))
        lag = np.zeros(self.model.n_lag) if lag is None else self.model._vector(lag, self.model.n_lag, "lag")
        for i, (lower, upper) in self._stops.items():
            if not lower <= q[i] <= upper:
                raise StateError(f"{self.model.joint_names[i]} = {q[i]:g} rad is past its hard stop "
                                 f"[{lower:g}, {upper:g}] rad")
        self.time_s = float(time_s)
        self.q, self.qdot, self.lag = q.copy(), qdot.copy(), lag.copy()
        self.torque, self.saturated = np.zeros(2), (False, False)
        self.stuck = {i: qdot[i] == 0.0 for i, _, _ in self._dry}
        # joint index -> +1 held at its upper stop, -1 at its lower one, 0 free
        self.at_stop = {i: 0 for i in self._stops}
        self.rng = np.random.default_rng(self.seed)
        self._wave_state = 0.0
        if self.wake is not None:
            self.wake.reset()   # the fluid at rest again
        self._prepared_force: Optional[Array] = None   # the next period's, if prepare_period made it
        self._last_period_s: Optional[float] = None   # the length of the period that ended last, s

    @property
    def state(self) -> PlantState:
        """The state at the end of the last period, a copy.

        Returns
        -------
        PlantState
            Time, q, qdot, the applied torque, the saturation flags and the lag states.
        """
        return PlantState(self.time_s, self.q.copy(), self.qdot.copy(), self.torque.copy(), self.saturated,
                          self.lag.copy())

    def energy(self) -> float:
        """T + V: kinetic energy plus the tilt's gravity potential (the lag states hold none).

        Returns
        -------
        float
            T + V, J.

        References
        ----------
        Saimek & Li (2004), eq. 5 (T = 1/2 qdot' Mm qdot).
        """
        self._potential.inputs[0][:] = self.q
        self._potential()
        potential = float(self._potential.outputs[0][0])
        return self.model.kinetic_energy(self.q, self.qdot) + potential

    # ----- one period ----------------------------------------------------------------------------
    def step(self, torque: npt.ArrayLike, period_s: Optional[float] = None) -> PlantState:
        """Hold torque over one period and integrate.

        The torque is clipped at the motor limits (paper Sec. 2); a non-finite or wrongly sized one is taken as
        zero.

        Parameters
        ----------
        torque : (2,) array_like
            Commanded joint torques (heave, pitch), N m.
        period_s : float, optional
            This period's length, s (default: sample_period_s), for a caller whose periods vary (the emulated rig's
            reads); the disturbances held over it are stepped over the period that ended last (the first: over this
            one).

        Returns
        -------
        PlantState
            The state at the end of the period.

        Raises
        ------
        ValueError
            For a period_s that is not finite and > 0.
        SimulationError
            When the integration blows up (a non-finite state, or a speed or lag state above BLOW_UP_SPEED).
        """
        if period_s is None:
            period_s = self.sample_period_s
        elif not (math.isfinite(period_s) and period_s > 0.0):
            raise ValueError(f"a period must be finite and > 0 s, got {period_s!r}")
        if period_s != self._period_s:
            self._set_period(period_s)
        command = np.asarray(torque, dtype=float).reshape(-1)
        if command.shape != (2,) or not np.isfinite(command).all():
            command = np.zeros(2)
        applied = np.clip(command, -self._limits, self._limits)
        self.saturated = (bool(abs(command[0]) > self._limits[0]), bool(abs(command[1]) > self._limits[1]))
        wave = self._prepared_force if self._prepared_force is not None else self._period_force(period_s)
        self._prepared_force = None
        x = np.concatenate([self.q, self.qdot, self.lag])
        x_next = None if any(self.at_stop.values()) else self._fast_period(x, applied, wave)
        if x_next is None:
            x_next = self._substep_period(x, applied, wave)
        nq = self.model.nq
        if not np.isfinite(x_next).all() or np.abs(x_next[nq:]).max() > BLOW_UP_SPEED:   # speeds, lag states
            raise SimulationError(f"the integration blew up at t = {self.time_s:.3f} s (state {x_next}); "
                                  f"try more substeps or smaller disturbances")
        self.q, self.qdot, self.lag = x_next[:nq], x_next[nq:2 * nq], x_next[2 * nq:]
        self.torque = applied
        self.time_s += period_s
        self._last_period_s = period_s
        return self.state

    def _set_period(self, period_s: float) -> None:
        """Set the compiled steps' substep length for periods of period_s seconds."""
        step_s = period_s / self.substeps
        self._step.inputs[5][0] = self._period_locked.inputs[5][0] = self._period_unlocked.inputs[4][0] = step_s
        self._period_s = period_s

    def prepare_period(self) -> None:
        """Compute the next period's held disturbance forces now, ahead of its torque, for ``step`` to use.

        The waves' and the vortex wake's forces of a period depend on the state at its start and on the noise,
        never on its torque; a caller that waits for the torque (sim_node in lock-step, after publishing the state)
        can step the wake while the controller computes. ``step`` then gives the same numbers bit for bit as
        without it (the same computations in the same order, the noise drawn in the same sequence); ``reset``
        discards a prepared period. Once per period: a second call before ``step`` does nothing.
        """
        if self._prepared_force is None:
            self._prepared_force = self._period_force(self.sample_period_s)

    def _period_force(self, period_s: float) -> Array:
        """Generalized force held over the period of period_s seconds from the current state.

        The waves', plus the wake's, each stepped over the period that ended last (the first period: over
        period_s).
        """
        interval_s = period_s if self._last_period_s is None else self._last_period_s
        force = self._wave_force(interval_s)
        if self.wake is not None:
            force = force + self.wake.step(self.q, self.qdot, interval_s)
        return force

    def _wave_force(self, interval_s: float) -> Array:
        """Surface-wave generalized force for this period, the filter stepped over interval_s.

        Its standard deviation grows as |v_foil|^2; the noise is first-order filtered.
        """
        coefficient = self.disturbances.wave_force_per_speed2_n_s2_m2
        if coefficient == 0.0:
            return np.zeros(self.model.nq)
        decay = math.exp(-2.0 * math.pi * self.disturbances.wave_bandwidth_hz * interval_s)
        self._wave_state = decay * self._wave_state + math.sqrt(1.0 - decay ** 2) * self.rng.standard_normal()
        wave = self._wave
        wave.inputs[0][:], wave.inputs[1][:], wave.inputs[3][0] = self.q, self.qdot, self._wave_state
        wave()
        return wave.outputs[0].copy()

    def _fast_period(self, x: Array, torque: Array, wave: Array) -> Optional[Array]:
        """Integrate the whole period in one compiled call.

        None when a moving dry-friction coordinate's velocity reaches zero in it or a joint passes a hard stop: the
        caller then redoes the period substep by substep.
        """
        held, lock = self._friction(x, torque, wave)
        if lock.any():
            period = self._period_locked
            period.inputs[4][:] = lock
        else:
            period = self._period_unlocked
        period.inputs[0][:], period.inputs[1][:], period.inputs[2][:] = x, torque, held
        period()
        crossing, highest, lowest = period.outputs[1], period.outputs[2], period.outputs[3]
        for i, _, _ in self._dry:
            if not self.stuck[i] and crossing[i] <= 0.0:
                return None
        for i, (lower, upper) in self._stops.items():
            if highest[i] > upper or lowest[i] < lower:
                return None
        return self._pin_stopped(x, period.outputs[0].copy())

    def _pin_stopped(self, x: Array, x_next: Array) -> Array:
        """Put stopped coordinates (stuck by friction, held at a stop) exactly where they stopped.

        The constraint leaves round-off, ~1e-20.
        """
        for i, _, _ in self._dry:
            if self.stuck[i]:
                x_next[i], x_next[self.model.nq + i] = x[i], 0.0
        for i, side in self.at_stop.items():
            if side:
                x_next[i], x_next[self.model.nq + i] = x[i], 0.0
        return x_next

    def _substep_period(self, x: Array, torque: Array, wave: Array) -> Array:
        """Integrate the period substep by substep.

        Dry-friction coordinates stop where their velocity reaches zero, joints where they reach a hard stop.
        """
        nq = self.model.nq
        step = self._step
        for _ in range(self.substeps):
            held, lock = self._friction(x, torque, wave)
            step.inputs[0][:], step.inputs[1][:], step.inputs[2][:], step.inputs[4][:] = x, torque, held, lock
            step()
            x_next = step.outputs[0].copy()
            x_next = self._pin_stopped(x, x_next)
            for i, _, _ in self._dry:
                if not self.stuck[i] and x_next[nq + i] * x[nq + i] <= 0.0:
                    # the velocity reached zero: stopped; stiction decides next substep. Joints at a stop stay
                    self._stop(x_next, [i, *(j for j, side in self.at_stop.items() if side)])
                    self.stuck[i] = True
            for i, (lower, upper) in self._stops.items():
                if not self.at_stop[i] and not lower <= x_next[i] <= upper and math.isfinite(x_next[i]):
                    self.at_stop[i] = 1 if x_next[i] > upper else -1
                    x_next[i] = upper if x_next[i] > upper else lower   # the stop: at the limit, not past it
                    at_stops = [j for j, side in self.at_stop.items() if side and j != i]
                    self._stop(x_next, [i, *at_stops, *(j for j, _, _ in self._dry if self.stuck[j])])
            x = x_next
        return x

    def _stop(self, x: Array, indices: list[int]) -> None:
        """Stop coordinate indices[0] by a plastic impulse, the others (already stopped) staying stopped.

        For one coordinate i, qdot -= Mm^-1 e_i v_i / (Mm^-1)_ii; for a set S, qdot -= Mm^-1 E (E' Mm^-1 E)^-1 E'
        qdot (E the columns of I in S). The Mm-orthogonal projection onto v_S = 0, which never adds kinetic energy
        (for one coordinate it removes v_i^2 / (2 (Mm^-1)_ii)).
        """
        nq = self.model.nq
        self._mass.inputs[0][:] = x[:nq]
        self._mass()
        inverse_mass = np.linalg.inv(self._mass.outputs[0].reshape((nq, nq), order="F"))
        if len(indices) == 1:
            index = indices[0]
            x[nq:2 * nq] -= inverse_mass[:, index] * (x[nq + index] / inverse_mass[index, index])
        else:
            selected = np.array(indices)
            velocities = x[nq + selected]
            x[nq:2 * nq] -= inverse_mass[:, selected] @ np.linalg.solve(inverse_mass[np.ix_(selected, selected)],
                                                                        velocities)
        x[nq + np.array(indices)] = 0.0

    def _friction(self, x: Array, torque: Array, wave: Array) -> tuple[Array, Array]:
        """Return (held force, lock mask) for the next step.

        Stopped coordinates stay locked while the force holding them is within their static limit, else break away
        (against Coulomb friction); moving ones feel -Coulomb sign(v). A joint at a hard stop stays locked while
        the force holding it pushes back from the limit, and is released when it would have to pull. Mutates x
        only to give a breaking-away coordinate its direction of motion.
        """
        nq = self.model.nq
        held, lock = wave.copy(), np.zeros(nq)
        for i, _, _ in self._dry:
            lock[i] = 1.0 if self.stuck[i] else 0.0
        for i, side in self.at_stop.items():
            lock[i] = 1.0 if side else 0.0
        if lock.any():
            forward = self._forward
            forward.inputs[0][:], forward.inputs[1][:], forward.inputs[2][:], forward.inputs[4][:] = (
                x, torque, held, lock)
            forward()
            hold_force = forward.outputs[0]
            for i, _, static in self._dry:
                if self.stuck[i] and abs(hold_force[i]) > static:
                    self.stuck[i], lock[i] = False, 0.0
                    x[nq + i] = 1e-12 * math.copysign(1.0, hold_force[i] * -1.0)   # where the net force pushes
            for i, side in self.at_stop.items():
                if side and hold_force[i] * side > 0.0:   # the stop would have to pull the joint onto it
                    self.at_stop[i], lock[i] = 0, 0.0
        for i, coulomb, _ in self._dry:
            if not self.stuck[i]:
                held[i] -= coulomb * math.copysign(1.0, x[nq + i])
        return held, lock



@dataclasses.dataclass(frozen=True)
class PlantSettings:
    """What a plant integrates beyond its vehicle (``make_plant`` builds the plant of them).

    Attributes
    ----------
    flow : {"ideal", "circulatory", "wake"}
        The water, one of swim_model.flow's FLOWS.
    substeps : int
        Classical RK4 steps per period, an integer >= 1.
    disturbances : Disturbances
        Sizes of the disturbances (default: none, the water's model alone).
    hard_stops : bool
        Whether the joints meet their hard stops (the stops' values are the rig's, make_plant's
        hard_limits_rad).

    Raises
    ------
    ValueError
        For a flow not in FLOWS, substeps that is not an integer >= 1, or invalid disturbances.
    """

    flow: str = "ideal"
    substeps: int = 8
    disturbances: Disturbances = dataclasses.field(default_factory=Disturbances.none)   # the water's model alone
    hard_stops: bool = True

    def __post_init__(self) -> None:
        """Check the settings (the class's Raises)."""
        _check_flow(self.flow)
        if not (isinstance(self.substeps, int) and self.substeps >= 1):
            raise ValueError(f"substeps must be an integer >= 1, got {self.substeps!r}")
        self.disturbances.validate()

    @classmethod
    def flow_only(cls, flow: str) -> "PlantSettings":
        """The water of flow and none of the rig's own disturbances (friction, tilt, waves).

        The emulated rig's, on which a dry run on hardware adds the rig's own. The wake's water holds the
        separation drag the attached wake lacks (Disturbances.separation_drag, swim_model.wake_coupling); the
        other flows' water adds nothing.

        Parameters
        ----------
        flow : {"ideal", "circulatory", "wake"}
            The water, one of swim_model.flow's FLOWS.

        Returns
        -------
        PlantSettings
            The settings with 8 substeps and the hard stops on.

        Raises
        ------
        ValueError
            For a flow not in FLOWS.
        """
        return cls(flow, disturbances=Disturbances.separation_drag() if flow == "wake" else Disturbances.none())


def make_plant(settings: PlantSettings, rig: Optional[RigParameters], hard_limits_rad: HardLimits,
               constrained: bool = False, lane_radius_m: Optional[float] = None,
               sample_period_s: Optional[float] = None, seed: int = 0,
               wake_parameters: Optional[WakeCouplingParameters] = None) -> Plant:
    """Build the plant of settings for the rig's vehicle.

    Parameters
    ----------
    settings : PlantSettings
        The flow, substeps, disturbances and whether the hard stops are on.
    rig : RigParameters or None
        Rig parameters (None: the shipped rig file).
    hard_limits_rad : HardLimits
        The joints' hard stops ((heave lower, upper), (pitch lower, upper)), rad; used while settings.hard_stops.
    constrained : bool, optional
        Lock the rails: q = (alpha, phi, theta), as VehicleModel takes it.
    lane_radius_m : float, optional
        R of the locked rails, m (default: the rig's ``constrained_lane_radius_m``).
    sample_period_s : float, optional
        The control period, s (default: the rig's ``sample_period_s``).
    seed : int, optional
        Seed of the waves' noise.
    wake_parameters : WakeCouplingParameters, optional
        The wake's parameters in flow "wake" (default: WakeCouplingParameters' defaults).

    Returns
    -------
    Plant
        The plant, at rest at the origin; in flow "wake" with the wake's compiled kernels loaded (numba's cache, a
        second or more on a loaded host), so that its first periods do not load them.

    Raises
    ------
    ValueError
        For hard limits that are not finite with lower < upper, or a sample period <= 0.
    """
    model = vehicle_model(settings.flow, rig, constrained, lane_radius_m)
    wake = None
    if settings.flow == "wake":
        wake = WakeCoupling(model, wake_parameters or WakeCouplingParameters())
        compile_kernels()
    return Plant(model, settings.disturbances, sample_period_s, settings.substeps, seed, wake,
                 hard_limits_rad if settings.hard_stops else None, flow=settings.flow)
