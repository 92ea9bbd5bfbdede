"""The emulated rig: swim_model's free vehicle behind encoder counters and current-mode amplifiers.

For dry runs and tests of everything above the device layer. Between two reads the vehicle
(q = (alpha, R, phi, theta), VehicleModel(constrained=False)) is integrated by RK4 with the joint torques held,
    tau = N Kt i      (heave, pitch; zero while the amplifiers are disabled),
and the encoders are quantized as an incremental encoder counts, n = floor((q - q_home) * counts_per_unit),
held in counters modulo 2**counter_bits that start at initial_counts.

Hard stops (option hard_stops, default on; hard_stops_rad, ((heave lower, upper), (pitch lower, upper)), None for
none): the rig's heave and pitch stops, at the bridge file's hard limits, as the simulator has them
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

import numpy as np
from swim_model import VehicleModel, load_rig
from swim_model.codegen import NativeFunction

from swim_hw_bridge.conversions import BridgeConfig
from swim_hw_bridge.device import CounterSample, Device, DeviceError

DEFAULT_CHARGE_PUMP_TIMEOUT_S = 0.05   # assumed: about 6 periods of 8 ms


class EmulatedDevice(Device):
    def __init__(self, config: dict[str, Any]) -> None:
        self.bridge = BridgeConfig.from_dict(config)
        self.counter_bits = int(config.get("counter_bits", 32))
        self.charge_pump_timeout_s = float(config.get("charge_pump_timeout_s", DEFAULT_CHARGE_PUMP_TIMEOUT_S))
        self.substeps = int(config.get("substeps", 8))
        self.max_integration_s = float(config.get("max_integration_s", 0.05))
        self.initial_counts = tuple(int(c) for c in config.get("initial_counts", (0, 0, 0, 0)))
        self.rig_path = str(config.get("rig_path", "")) or None
        limits = self.bridge
        self.hard_stops_rad: tuple[tuple[float, float], tuple[float, float]] | None = (
            ((limits.heave_lower_hard_limit_rad, limits.heave_upper_hard_limit_rad),
             (limits.pitch_lower_hard_limit_rad, limits.pitch_upper_hard_limit_rad))
            if bool(config.get("hard_stops", True)) else None)
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
            self.model = VehicleModel(load_rig(self.rig_path), constrained=False)
            # compile and load the integrator now, not in the first period of the loop; and the single step and
            # the inertia a read at a stop takes, through their native entry points (microseconds a call)
            self.model.integrate_rk4(self.q, self.qdot, self._torques, 1e-3)
            self._step = self.model.native_function("rk4_step")
            self._mass = self.model.native_function("mass_matrix")
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
        q, qdot = self.model.integrate_rk4(self.q, self.qdot, self._torques, step_s)
        first = self._first_past_a_stop(q)
        if first is None:
            self.q, self.qdot = q[-1], qdot[-1]
            return
        # exact up to the substep before a joint passed its stop, then substep by substep
        start = max(first - 1, 0)
        self.q, self.qdot = q[start].copy(), qdot[start].copy()
        assert self._step is not None
        step, nq = self._step, len(self.q)
        step.inputs[2][0] = step_s
        for k in range(start, self.substeps):
            step.inputs[0][:nq], step.inputs[0][nq:], step.inputs[1][:] = self.q, self.qdot, self._torques[k]
            step()
            self.q, self.qdot = step.outputs[0][:nq].copy(), step.outputs[0][nq:2 * nq].copy()
            self._stop_at_hard_stops()

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
