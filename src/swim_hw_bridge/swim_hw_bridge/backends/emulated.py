"""The emulated rig: swim_model's free vehicle behind encoder counters and current-mode amplifiers.

For dry runs and tests of everything above the device layer. Between two reads the vehicle
(q = (alpha, R, phi, theta), VehicleModel(constrained=False)) is integrated by RK4 with the joint torques held,
    tau = N Kt i      (heave, pitch; zero while the amplifiers are disabled),
and the encoders are quantized as an incremental encoder counts, n = floor((q - q_home) * counts_per_unit),
held in counters modulo 2**counter_bits that start at initial_counts.

Flow (option flow, default "ideal"; bridge_node's parameter flow): the water the emulated rig swims in, the same
choice as the simulator's (swim_model.wake_coupling.FLOWS): "ideal", the paper's added mass only; "circulatory",
VehicleModel(flow="circulatory") with its two lag states z (m/s) integrated with (q, qdot), from rest at open();
"wake", the ideal model plus the free-vortex wake's force (swim_model.wake_coupling.WakeCoupling, stepped once per
read over the time since the last one and held over the next, as the simulator holds it over a period) plus the
flat-plate separation drag the wake lacks, -1/2 rho Cd A |v| v on the foil's chordwise and normal velocities
(options foil_axial_drag_coefficient, foil_normal_drag_coefficient). Nothing else of the simulator's disturbances
is emulated: the rig's own friction is what a dry run on hardware adds.

Hard stops (option hard_stops, default on; hard_stops_rad, ((heave lower, upper), (pitch lower, upper)), None for
none): the rig's heave and pitch hard stops (swim_model's limits record), as the simulator has them
(swim_sim/plant.py). A joint reaching its stop meets an inelastic stop: its position is held at the stop and its
velocity into it removed by a plastic impulse, the Mm-orthogonal projection onto qdot_S = 0 for the set S of joints
at their stops, qdot -= Mm^-1 E (E' Mm^-1 E)^-1 E' qdot (E the columns of I in S), which only removes kinetic
energy; while the load pushes it into the stop this repeats each substep (the stop pushes, never pulls), and it
leaves the stop as soon as the load pulls it back into its range. A read interval in which no joint passes a stop
is integrated exactly as without stops; one in which a joint does is redone substep by substep.

The enable line is emulated as the rig wires it (see bridge_node's docstring): the amplifiers conduct only while
enable() has been called and the last toggle_enable() edge is at most charge_pump_timeout_s old, so a bridge that
stops toggling (hung, crashed, faulted) finds the emulated amplifiers disabled.

Write log (option write_log_size, default 0: off): the last N writes as rows (time.monotonic(), heave_a, pitch_a)
in a preallocated array, write_log[:write_count % N], to see what the motors got and when (the latency benchmark).

Fault injection for tests (attributes, off by default): read_delay_s (every read takes this long), repeat_samples
(reads return the previous sample, same sequence), fail_reads (reads raise DeviceError).
"""
from __future__ import annotations

import math
import time
from typing import Any, cast

import casadi as ca
import numpy as np
from swim_model import SwimModelError, VehicleModel, codegen
from swim_model.codegen import NativeFunction
from swim_model.wake_coupling import FLOWS, MODEL_FLOWS, WakeCoupling, separation_drag

from swim_hw_bridge.conversions import BridgeConfig
from swim_model.limits import HardLimits
from swim_hw_bridge.device import CounterSample, Device, DeviceError

DEFAULT_CHARGE_PUMP_TIMEOUT_S = 0.05   # assumed: about 6 periods of 8 ms
#: steps of the throwaway wake open() swims to load the wake's kernels: enough to shed and move vortices
WAKE_WARM_UP_STEPS = 4
#: the wake flow's separation drag coefficients when the options leave them out: a flat plate broadside (Hoerner,
#: Fluid-Dynamic Drag, 1965, Ch. 3) and a thin section's skin friction (assumed, as swim_sim's Disturbances)
DEFAULT_NORMAL_DRAG_COEFFICIENT = 1.2
DEFAULT_AXIAL_DRAG_COEFFICIENT = 0.01


def _forced_step(model: VehicleModel) -> ca.Function:
    """One RK4 step of the ideal vehicle with a held generalized force and the foil's separation drag:
    (x = (q, qdot), tau, held force per coordinate, drag factors (k_U, k_V) = 1/2 rho Cd A, h) -> x_next."""
    s = model.symbolic
    nq = model.nq
    held, factors, h = ca.SX.sym("held", nq), ca.SX.sym("factors", 2), ca.SX.sym("h")
    input_map = ca.vertcat(ca.SX.zeros(nq - 2, 2), ca.SX.eye(2))
    drag = s.foil_velocity_map.T @ separation_drag(s.foil_velocity_map @ s.qdot, factors)
    bias = s.functions["generalized_force"](s.q, s.qdot, ca.SX.zeros(nq))
    x = ca.vertcat(s.q, s.qdot)
    f = ca.Function("f", [x, s.tau, held, factors],
                    [ca.vertcat(s.qdot, ca.solve(s.mass, input_map @ s.tau + drag + held - bias))])
    k1 = f(x, s.tau, held, factors)
    k2 = f(x + 0.5 * h * k1, s.tau, held, factors)
    k3 = f(x + 0.5 * h * k2, s.tau, held, factors)
    k4 = f(x + h * k3, s.tau, held, factors)
    return ca.Function("emulated_wake_rk4_step", [x, s.tau, held, factors, h],
                       [x + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)])


class EmulatedDevice(Device):
    def __init__(self, config: dict[str, Any]) -> None:
        self.bridge = BridgeConfig.from_dict(config)
        self.counter_bits = int(config.get("counter_bits", 32))
        self.charge_pump_timeout_s = float(config.get("charge_pump_timeout_s", DEFAULT_CHARGE_PUMP_TIMEOUT_S))
        self.substeps = int(config.get("substeps", 8))
        self.max_integration_s = float(config.get("max_integration_s", 0.05))
        self.initial_counts = tuple(int(c) for c in config.get("initial_counts", (0, 0, 0, 0)))
        self.flow = str(config.get("flow", "ideal"))
        if self.flow not in FLOWS:
            raise ValueError(f"emulated device: flow must be one of {', '.join(FLOWS)}, got {self.flow!r}")
        self.drag_coefficients = (float(config.get("foil_axial_drag_coefficient", DEFAULT_AXIAL_DRAG_COEFFICIENT)),
                                  float(config.get("foil_normal_drag_coefficient", DEFAULT_NORMAL_DRAG_COEFFICIENT)))
        if not all(math.isfinite(c) and c >= 0.0 for c in self.drag_coefficients):
            raise ValueError(f"emulated device: drag coefficients must be finite and >= 0, got "
                             f"{self.drag_coefficients}")
        self.hard_stops_rad: HardLimits | None = (
            self.bridge.hard_limits_rad if bool(config.get("hard_stops", True)) else None)
        self.counts_per_unit = np.array(self.bridge.counts_per_unit)
        self.home = np.array(self.bridge.home_positions)
        self.torque_gains = np.array(self.bridge.motor_torque_gains_n_m_per_a)
        self.read_delay_s = 0.0
        self.repeat_samples = False
        self.fail_reads = False
        self.model: VehicleModel | None = None
        self._step: NativeFunction | None = None   # the model's RK4 step and Mm(q), set by open()
        self._mass: NativeFunction | None = None
        self.q = self.home.copy()
        self.qdot = np.zeros(4)
        self.lag = np.zeros(0)   # the circulatory flow's lag states, m/s (set by open())
        self.wake: WakeCoupling | None = None   # the vortex wake (flow "wake", set by open())
        self._wake_force = np.zeros(4)   # the wake's generalized force held over the next read interval
        self._wake_interval_s = 0.0   # the last read interval, s (0: none yet)
        self.commanded_currents_a = (0.0, 0.0)
        self.enable_requested = False
        self.enable_level = False
        self.toggle_count = 0
        self._last_toggle_s = -math.inf
        self._time_s = 0.0
        self._sequence = 0
        self._last_sample: CounterSample | None = None
        self._torques = np.zeros((self.substeps, 2))
        self.write_log = np.zeros((int(config.get("write_log_size", 0)), 3))
        self.write_count = 0

    # --- the Device interface --------------------------------------------------------------------------
    def open(self) -> None:
        if self.model is None:
            self.model = VehicleModel(self.bridge.rig, constrained=False, flow=MODEL_FLOWS[self.flow])
            self.lag = np.zeros(self.model.n_lag)   # the flow at rest
            # compile and load the integrator now, not in the first period of the loop; and the single step and
            # the inertia a read at a stop takes, through their native entry points (microseconds a call)
            self.model.integrate_rk4(self.q, self.qdot, self._torques, 1e-3, lag=self.lag if self.lag.size else None)
            self._step = self.model.native_function("rk4_step")
            self._mass = self.model.native_function("mass_matrix")
            if self.flow == "wake":
                rig = self.model.rig
                half_rho_area = 0.5 * rig.water_density_kg_m3 * rig.foil_chord_m * rig.foil_span_m
                self._step = codegen.native([_forced_step(self.model)], tag=f"emulated_{self.model._codegen_tag()}")[
                    "emulated_wake_rk4_step"]
                self._step.inputs[3][:] = [half_rho_area * c for c in self.drag_coefficients]
                self.wake = WakeCoupling(self.model)
                self._wake_interval_s = 0.0
                # load the wake's compiled kernels now (numba's import and its cache, about 0.3-0.5 s), not in the
                # I/O loop's first periods: a throwaway wake swims a few steps of a pitching foil
                warm_up = WakeCoupling(self.model)
                for k in range(WAKE_WARM_UP_STEPS):
                    warm_up.step(self.q, np.array([0.0, 0.0, 0.0, 1.0 if k % 2 else -1.0]), 1e-3)
        self.commanded_currents_a = (0.0, 0.0)
        self.enable_requested = False
        self._last_toggle_s = -math.inf
        self._time_s = time.monotonic()

    def read_counters(self) -> CounterSample:
        if self.model is None:
            raise DeviceError("emulated device: read before open()")
        if self.read_delay_s > 0.0:
            time.sleep(self.read_delay_s)
        if self.fail_reads:
            raise DeviceError("emulated device: injected read failure")
        if self.repeat_samples and self._last_sample is not None:
            return self._last_sample
        now_s = time.monotonic()
        self._advance(now_s)
        self._sequence += 1
        self._last_sample = CounterSample(self.counts(), now_s, self._sequence)
        return self._last_sample

    def write_currents(self, heave_a: float, pitch_a: float) -> None:
        if self.model is None:
            raise DeviceError("emulated device: write before open()")
        self.commanded_currents_a = (float(heave_a), float(pitch_a))
        if len(self.write_log):
            self.write_log[self.write_count % len(self.write_log)] = (time.monotonic(), heave_a, pitch_a)
            self.write_count += 1

    def toggle_enable(self) -> None:
        self.enable_level = not self.enable_level
        self.toggle_count += 1
        self._last_toggle_s = time.monotonic()

    def enable(self) -> None:
        self.enable_requested = True

    def disable(self) -> None:
        self.commanded_currents_a = (0.0, 0.0)
        self.enable_requested = False
        self._last_toggle_s = -math.inf

    def close(self) -> None:
        self.disable()
        self.model = None

    # --- the emulated rig ---------------------------------------------------------------------------------
    def amplifiers_enabled(self, now_s: float | None = None) -> bool:
        """The charge pump's output: enable requested and an edge within the timeout."""
        now_s = time.monotonic() if now_s is None else now_s
        return self.enable_requested and now_s - self._last_toggle_s <= self.charge_pump_timeout_s

    def motor_currents_a(self, now_s: float | None = None) -> tuple[float, float]:
        """The currents flowing: the command while the amplifiers are enabled, else zero."""
        return self.commanded_currents_a if self.amplifiers_enabled(now_s) else (0.0, 0.0)

    def counts(self) -> tuple[int, int, int, int]:
        """The counter registers for the present state (quantized, wrapped)."""
        modulus = 1 << self.counter_bits
        steps = np.floor((self.q - self.home) * self.counts_per_unit)
        return cast(tuple[int, int, int, int],
                    tuple((initial + int(n)) % modulus for initial, n in zip(self.initial_counts, steps)))

    def _advance(self, now_s: float) -> None:
        elapsed_s = min(now_s - self._time_s, self.max_integration_s)
        self._time_s = now_s
        if elapsed_s <= 0.0:
            return
        assert self.model is not None   # read_counters checked it
        currents = self.motor_currents_a(now_s)
        self._torques[:, 0] = currents[0] * self.torque_gains[0]
        self._torques[:, 1] = currents[1] * self.torque_gains[1]
        step_s = elapsed_s / self.substeps
        if self.wake is not None:
            # the wake stepped to now over the last interval (the first: over this one), its force held over this
            try:
                self._wake_force = self.wake.step(self.q, self.qdot, self._wake_interval_s or elapsed_s)
            except SwimModelError as err:
                raise DeviceError(f"emulated device: the vortex wake failed: {err}") from err
            self._wake_interval_s = elapsed_s
            for k in range(self.substeps):   # a joint past its stop is stopped at the substep it passes it
                self._single_step(self._torques[k], step_s)
                if self.hard_stops_rad is not None:
                    self._stop_at_hard_stops()
            return
        q, qdot, *lag = self.model.integrate_rk4(self.q, self.qdot, self._torques, step_s,
                                                 lag=self.lag if self.lag.size else None)
        first = self._first_past_a_stop(q)
        if first is None:
            self.q, self.qdot = q[-1], qdot[-1]
            if lag:
                self.lag = lag[0][-1]
            return
        # exact up to the substep before a joint passed its stop, then substep by substep
        start = max(first - 1, 0)
        self.q, self.qdot = q[start].copy(), qdot[start].copy()
        if lag:
            self.lag = lag[0][start].copy()
        for k in range(start, self.substeps):
            self._single_step(self._torques[k], step_s)
            self._stop_at_hard_stops()

    def _single_step(self, torque: np.ndarray, step_s: float) -> None:
        """One substep of step_s seconds with torque held (and, in the wake, the wake's force and the drag):
        the model's RK4 step on x = (q, qdot[, lag]) through its native entry point."""
        assert self._step is not None
        step, nq = self._step, len(self.q)
        step.inputs[0][:nq], step.inputs[0][nq:2 * nq], step.inputs[0][2 * nq:] = self.q, self.qdot, self.lag
        step.inputs[1][:] = torque
        if self.wake is not None:
            step.inputs[2][:] = self._wake_force
        step.inputs[-1][0] = step_s
        step()
        x = step.outputs[0]
        self.q, self.qdot, self.lag = x[:nq].copy(), x[nq:2 * nq].copy(), x[2 * nq:].copy()

    def _first_past_a_stop(self, q: np.ndarray) -> int | None:
        """The first row of q (positions at the substeps' boundaries) with a joint past its stop; None: none."""
        if self.hard_stops_rad is None:
            return None
        past = np.zeros(len(q), dtype=bool)
        for j, (lower, upper) in enumerate(self.hard_stops_rad):
            past |= (q[:, 2 + j] < lower) | (q[:, 2 + j] > upper)
        return int(np.argmax(past)) if past.any() else None

    def _stop_at_hard_stops(self) -> None:
        """Joints past their stops held at them, their velocities into the stops removed by the plastic impulse
        (see the module docstring)."""
        assert self._mass is not None and self.hard_stops_rad is not None
        stopped = []
        for j, (lower, upper) in enumerate(self.hard_stops_rad):
            index = 2 + j
            if self.q[index] > upper or self.q[index] < lower:
                side = 1.0 if self.q[index] > upper else -1.0
                self.q[index] = upper if side > 0 else lower
                if self.qdot[index] * side > 0.0:
                    stopped.append(index)
        if stopped:
            nq = len(self.q)
            self._mass.inputs[0][:] = self.q
            self._mass()
            inverse_mass = np.linalg.inv(self._mass.outputs[0].reshape((nq, nq), order="F"))
            selected = np.array(stopped)
            self.qdot -= inverse_mass[:, selected] @ np.linalg.solve(inverse_mass[np.ix_(selected, selected)],
                                                                      self.qdot[selected])
            self.qdot[selected] = 0.0
