"""The emulated rig: swim_model's free vehicle behind encoder counters and current-mode amplifiers.

For dry runs and tests of everything above the device layer. Between two reads the vehicle
(q = (alpha, R, phi, theta), VehicleModel(constrained=False)) is integrated by RK4 with the joint torques held,
    tau = N Kt i      (heave, pitch; zero while the amplifiers are disabled),
and the encoders are quantized as an incremental encoder counts, n = floor((q - q_home) * counts_per_unit),
held in counters modulo 2**counter_bits that start at initial_counts.

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
        self.counts_per_unit = np.array(self.bridge.counts_per_unit)
        self.home = np.array(self.bridge.home_positions)
        self.torque_gains = np.array(self.bridge.motor_torque_gains_n_m_per_a)
        self.read_delay_s = 0.0
        self.repeat_samples = False
        self.fail_reads = False
        self.model: VehicleModel | None = None
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
            # compile and load the integrator now, not in the first period of the loop
            self.model.integrate_rk4(self.q, self.qdot, self._torques, 1e-3)
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
        q, qdot = self.model.integrate_rk4(self.q, self.qdot, self._torques, elapsed_s / self.substeps)
        self.q, self.qdot = q[-1], qdot[-1]
