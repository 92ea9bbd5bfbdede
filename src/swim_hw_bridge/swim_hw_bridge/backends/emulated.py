"""The emulated rig: swim_model's plant (the free vehicle) behind encoder counters and current-mode amplifiers.

For dry runs and tests of everything above the device layer. Between two reads the vehicle
(q = (alpha, R, phi, theta), the free vehicle) is stepped by swim_model.plant's Plant, the simulator's, over the
time since the last read (at most max_integration_s) with the joint torques held,
    tau = N Kt i      (heave, pitch; zero while the amplifiers are disabled),
and the encoders are quantized as an incremental encoder counts, n = floor((q - q_home) * counts_per_unit),
held in counters modulo 2**counter_bits that start at initial_counts.

The plant's settings (option plant, a swim_model.plant.PlantSettings: the flow, the substeps, the disturbances and
the hard stops' switch) are the plant's, not the device's; bridge_node passes
PlantSettings.flow_only(flow) for its parameter flow: the water the emulated rig swims in, the same choice as the
simulator's, with none of the simulator's disturbances (the rig's own friction is what a dry run on hardware
adds), and the rig's hard stops at its limits record's (the rig the bridge file is loaded with).

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

from swim_hw_bridge.conversions import BridgeConfig
from swim_hw_bridge.device import CounterSample, Device, DeviceError
from swim_model import SwimModelError
from swim_model.plant import Plant, PlantSettings, SimulationError, make_plant

DEFAULT_CHARGE_PUMP_TIMEOUT_S = 0.05   # assumed: about 6 periods of 8 ms
#: options that are the plant's settings (PlantSettings), refused as the device's
PLANT_OPTIONS = ("flow", "substeps", "hard_stops", "foil_axial_drag_coefficient", "foil_normal_drag_coefficient")


class EmulatedDevice(Device):
    """The emulated rig behind the Device interface (module docstring)."""

    def __init__(self, config: dict[str, Any]) -> None:
        misplaced = [name for name in PLANT_OPTIONS if name in config]
        if misplaced:
            raise ValueError(f"emulated device: {', '.join(misplaced)} are the plant's settings, not the device's: "
                             f"give option plant a swim_model.plant.PlantSettings")
        self.bridge = BridgeConfig.from_dict(config)
        self.plant_settings = config.get("plant", PlantSettings.flow_only("ideal"))
        if not isinstance(self.plant_settings, PlantSettings):
            raise ValueError(f"emulated device: option plant must be a PlantSettings, got {self.plant_settings!r}")
        self.counter_bits = int(config.get("counter_bits", 32))
        self.charge_pump_timeout_s = float(config.get("charge_pump_timeout_s", DEFAULT_CHARGE_PUMP_TIMEOUT_S))
        self.max_integration_s = float(config.get("max_integration_s", 0.05))
        self.initial_counts = tuple(int(c) for c in config.get("initial_counts", (0, 0, 0, 0)))
        self.counts_per_unit = np.array(self.bridge.counts_per_unit)
        self.home = np.array(self.bridge.home_positions)
        self.torque_gains = np.array(self.bridge.motor_torque_gains_n_m_per_a)
        self.read_delay_s = 0.0
        self.repeat_samples = False
        self.fail_reads = False
        self.plant: Plant | None = None   # the vehicle, built by the first open() at the home pose, at rest
        self.is_open = False
        self.commanded_currents_a = (0.0, 0.0)
        self.enable_requested = False
        self.enable_level = False
        self.toggle_count = 0
        self._last_toggle_s = -math.inf
        self._time_s = 0.0
        self._sequence = 0
        self._last_sample: CounterSample | None = None
        self._torque = np.zeros(2)
        self.write_log = np.zeros((int(config.get("write_log_size", 0)), 3))
        self.write_count = 0

    # --- the Device interface --------------------------------------------------------------------------
    def open(self) -> None:
        """Build the plant (once) and load its compiled code; outputs at zero, amplifiers disabled."""
        if self.plant is None:
            # compiles and loads the plant's integrator (and a wake's kernels) now, not in the loop's periods
            self.plant = make_plant(self.plant_settings, self.bridge.rig, self.bridge.rig.hard_limits_rad)
            self.plant.reset(self.home, np.zeros(self.plant.model.nq))
        self.is_open = True
        self.commanded_currents_a = (0.0, 0.0)
        self.enable_requested = False
        self._last_toggle_s = -math.inf
        self._time_s = time.monotonic()

    def read_counters(self) -> CounterSample:
        """The counters after stepping the plant to now; raises DeviceError before open() or as injected."""
        if not self.is_open:
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
        """Hold (heave, pitch) currents, A, until the next write; logged when a write log is kept."""
        if not self.is_open:
            raise DeviceError("emulated device: write before open()")
        self.commanded_currents_a = (float(heave_a), float(pitch_a))
        if len(self.write_log):
            self.write_log[self.write_count % len(self.write_log)] = (time.monotonic(), heave_a, pitch_a)
            self.write_count += 1

    def toggle_enable(self) -> None:
        """Flip the emulated enable line, an edge for the charge pump."""
        self.enable_level = not self.enable_level
        self.toggle_count += 1
        self._last_toggle_s = time.monotonic()

    def enable(self) -> None:
        """Ask for the amplifiers on; they are on while the line keeps toggling."""
        self.enable_requested = True

    def disable(self) -> None:
        """Zero the currents and drop the enable request and the last edge."""
        self.commanded_currents_a = (0.0, 0.0)
        self.enable_requested = False
        self._last_toggle_s = -math.inf

    def close(self) -> None:
        """Disable, then mark the device closed."""
        self.disable()
        self.is_open = False

    # --- the emulated rig ---------------------------------------------------------------------------------
    def amplifiers_enabled(self, now_s: float | None = None) -> bool:
        """The charge pump's output: enable requested and an edge within the timeout."""
        now_s = time.monotonic() if now_s is None else now_s
        return self.enable_requested and now_s - self._last_toggle_s <= self.charge_pump_timeout_s

    def motor_currents_a(self, now_s: float | None = None) -> tuple[float, float]:
        """The currents flowing: the command while the amplifiers are enabled, else zero."""
        return self.commanded_currents_a if self.amplifiers_enabled(now_s) else (0.0, 0.0)

    @property
    def q(self) -> np.ndarray:
        """The vehicle's positions now (alpha rad, R m, phi rad, theta rad): the home pose until open()."""
        return self.home if self.plant is None else self.plant.q

    def counts(self) -> tuple[int, int, int, int]:
        """The counter registers for the present state (quantized, wrapped)."""
        modulus = 1 << self.counter_bits
        steps = np.floor((self.q - self.home) * self.counts_per_unit)
        return cast(tuple[int, int, int, int],
                    tuple((initial + int(n)) % modulus for initial, n in zip(self.initial_counts, steps)))

    def _advance(self, now_s: float) -> None:
        """The plant stepped from the last read to now_s (at most max_integration_s) with the motors' torques."""
        elapsed_s = min(now_s - self._time_s, self.max_integration_s)
        self._time_s = now_s
        if elapsed_s <= 0.0:
            return
        assert self.plant is not None   # read_counters checked the device is open
        currents = self.motor_currents_a(now_s)
        self._torque[0] = currents[0] * self.torque_gains[0]
        self._torque[1] = currents[1] * self.torque_gains[1]
        try:
            self.plant.step(self._torque, elapsed_s)
        except (SimulationError, SwimModelError) as err:
            raise DeviceError(f"emulated device: the plant failed: {err}") from err
