"""sim_node: the simulated rig (swim_sim.plant) behind the same topics the hardware bridge serves.

Topics:
    joint_commands (sub, sensor_msgs/JointState)  torque command: names phi, theta; effort in N m
    joint_states (pub, sensor_msgs/JointState)    alpha, [R,] phi, theta: measured positions (quantized, noisy),
                                                  velocities (velocity_source "model") and applied efforts
    /clock (pub, rosgraph_msgs/Clock)             simulated time, one tick per period
    wake_statistics (pub, swim_interfaces/WakeStatistics)  with wake.enabled: the vortex wake after each period
                                                  (vortex count, circulations, the vortical force and its Q)
Services: ``reset`` (std_srvs/Trigger: back to the initial state, noise restarted from the seed; time runs on),
``set_state`` (swim_interfaces/SetVehicleState).

Modes: ``lockstep`` (default): each state is published, the step waits for the command stamped with that
state's stamp, then integrates one period and publishes the next: deterministic for a seed and as fast as the
controller answers. ``realtime``: a timer steps every period with the latest command held.
With ``hold_until_torque`` (lock-step only; false by default, true in swim_bringup's sim.yaml) the vehicle is held
at its initial state, simulated time and the noise sequence stopped, until the first command with a nonzero torque
(after start, reset or set_state); an all-zero command for the held state is answered by publishing the same
state again one period of wall time later. So a maneuver starts at the same simulated step, with the same
disturbance sequence, however long the system idled before its goal: runs with the same seed and plan repeat bit
for bit (the experiments compare sliding mode on and off this way).
A state with a non-finite or absurd value is never published: the simulator stops with an error (reset or
set_state restarts it). Malformed commands are rejected and counted.

Simulated time starts at ``start_time_s`` (1 s by default: a zero stamp means "not stamped" to consumers).
Parameters: rig_path, constrained, lane_radius_m, sample_period_s, substeps, mode, seed, start_time_s,
initial_positions, velocity_source, resend_after_s, hold_until_torque, disturbances.<field>
(swim_sim.disturbances.Disturbances), sensors.<field> (swim_sim.sensors.SensorNoise), wake.enabled (false: the
ideal-flow model alone) and wake.<field> (swim_sim.wake_coupling.parameter_defaults); read at start.

Speed (lock-step: each period waits for a round trip through the controller). The per-period path reuses its
messages and fills their arrays with array('d') (rosidl's setters check a list element by element), and the
per-period topics have no QoS event handlers: rclpy gives every publisher and subscription two by default
(incompatible QoS and type), each a waitable the executor re-adds to its wait set on every spin, in Python.
"""
from __future__ import annotations

import dataclasses
import time
from typing import Optional, cast

import numpy as np
from builtin_interfaces.msg import Time
from rclpy.node import Node
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from swim_interfaces.msg import WakeStatistics
from swim_interfaces.srv import SetVehicleState

from swim_model import StateError, SwimModelError, VehicleModel, load_rig
from swim_ros.codecs import MessageError, float_array, joint_state_arrays, stamp_of, torque_from_command
from swim_ros.entry import run_node
from swim_ros.qos import per_period_publisher, per_period_subscription
from swim_sim.disturbances import Disturbances
from swim_sim.plant import Plant, SimulationError
from swim_sim.sensors import SensorNoise, Sensors
from swim_sim.wake_coupling import WakeCoupling, parameter_defaults, parameters_from_values

class SimNode(Node):
    def __init__(self) -> None:
        super().__init__("sim_node")
        declare = self.declare_parameter
        declare("rig_path", "")
        declare("constrained", False)
        declare("lane_radius_m", 0.0)
        declare("sample_period_s", 0.008)
        declare("substeps", 8)
        declare("mode", "lockstep")
        declare("seed", 0)
        declare("start_time_s", 1.0)
        declare("initial_positions", [0.0])
        declare("velocity_source", "model")
        declare("resend_after_s", 0.5)
        declare("hold_until_torque", False)
        for field in dataclasses.fields(Disturbances):
            declare(f"disturbances.{field.name}", float(cast(float, field.default)))   # every field has one
        for field in dataclasses.fields(SensorNoise):
            declare(f"sensors.{field.name}", field.default)
        for name, default in parameter_defaults().items():
            declare(f"wake.{name}", default)
        value = lambda name: self.get_parameter(name).value  # noqa: E731
        self.mode = value("mode")
        if self.mode not in ("lockstep", "realtime"):
            raise ValueError(f"parameter mode must be 'lockstep' or 'realtime', got {self.mode!r}")
        if value("velocity_source") not in ("model", "none"):
            raise ValueError(f"parameter velocity_source must be 'model' or 'none', got {value('velocity_source')!r}")
        rig = load_rig(value("rig_path") or None)
        model = VehicleModel(rig, constrained=value("constrained"), lane_radius_m=value("lane_radius_m") or None)
        fields = dataclasses.fields
        disturbances = Disturbances(**{f.name: value(f"disturbances.{f.name}") for f in fields(Disturbances)})
        noise = SensorNoise(**{f.name: value(f"sensors.{f.name}") for f in fields(SensorNoise)})
        wake = None
        if value("wake.enabled"):
            wake = WakeCoupling(model, parameters_from_values({n: value(f"wake.{n}") for n in parameter_defaults()}))
        self.plant = Plant(model, disturbances, value("sample_period_s"), value("substeps"), value("seed"), wake)
        self.sensors = Sensors(model, noise, self.plant.sample_period_s)
        self.start_time_s = float(value("start_time_s"))
        initial = value("initial_positions")   # nq entries, or at rest
        self.initial_q = np.asarray(initial, dtype=float) if len(initial) == model.nq else self.plant.rest_positions()
        self.plant.reset(self.initial_q, np.zeros(model.nq), self.start_time_s)
        self.failed: Optional[str] = None
        self.rejected_commands = 0
        self._latest_torque = np.zeros(2)
        self._published_stamp: Optional[Time] = None
        self._velocity_source = value("velocity_source")
        self._state_message = JointState(name=list(model.joint_names))   # reused every period
        self._clock_message = Clock()
        self._efforts = np.zeros(model.nq)   # the unactuated coordinates' entries stay zero
        self._hold_enabled = bool(value("hold_until_torque")) and self.mode == "lockstep"
        self.holding = self._hold_enabled
        self._held_state_answered = False

        self.state_publisher = per_period_publisher(self, JointState, "joint_states")
        self.clock_publisher = per_period_publisher(self, Clock, "/clock", 10)
        self.wake_publisher = per_period_publisher(self, WakeStatistics, "wake_statistics") \
            if wake is not None else None
        per_period_subscription(self, JointState, "joint_commands", self._on_command)
        self.create_service(Trigger, "reset", self._on_reset)
        self.create_service(SetVehicleState, "set_state", self._on_set_state)
        if self.mode == "realtime":
            self.create_timer(self.plant.sample_period_s, self._on_tick)
        else:
            # a controller that starts late, or missed a state, still gets it
            self.create_timer(0.25 * value("resend_after_s"), self._resend)
            if self._hold_enabled:
                self.create_timer(self.plant.sample_period_s, self._republish_held_state)
        self._publish_state()
        self.get_logger().info(f"simulating the {'constrained' if model.constrained else 'free'} vehicle, "
                               f"{self.mode}, period {self.plant.sample_period_s * 1e3:g} ms")

    # ----- stepping ------------------------------------------------------------------------------
    def _on_command(self, message: JointState) -> None:
        try:
            torque = np.array(torque_from_command(message.name, message.effort))
        except MessageError as err:
            self.rejected_commands += 1
            self.get_logger().warning(f"command rejected ({self.rejected_commands} so far): {err}",
                                      throttle_duration_sec=1.0)
            return
        self._latest_torque = torque
        if self.mode == "lockstep" and message.header.stamp == self._published_stamp:
            if self.holding and not np.any(torque):
                self._held_state_answered = True   # the hold timer publishes it again
                return
            self.holding = False
            self._step(torque)

    def _on_tick(self) -> None:
        self._step(self._latest_torque)

    def _resend(self) -> None:
        """Lock-step: publish the waiting state again if no command has come for it within resend_after_s."""
        waited_s = time.monotonic() - self._published_monotonic
        if self.failed is None and waited_s >= self.get_parameter("resend_after_s").value:
            self._publish_state(advance=False)

    def _republish_held_state(self) -> None:
        """Holding: the held state again, at most once a period of wall time and only once it was answered (a
        zero command answered at once would otherwise make an idle loop as fast as the CPU allows)."""
        if self.holding and self._held_state_answered and self.failed is None:
            self._held_state_answered = False
            self._publish_state(advance=False)

    def _step(self, torque: np.ndarray) -> None:
        if self.failed is not None:
            return
        try:
            self.plant.step(torque)
        except (SimulationError, SwimModelError) as err:   # SwimModelError: the wake met a non-finite value
            self.failed = str(err)
            self.get_logger().error(f"simulation stopped: {err} (call reset or set_state to restart)")
            return
        self._publish_state()
        if self.wake_publisher is not None:
            self._publish_wake(self.plant.time_s - self.plant.sample_period_s)

    def _publish_state(self, advance: bool = True) -> None:
        plant = self.plant
        stamp = stamp_of(plant.time_s)
        message = self._state_message
        message.header.stamp = stamp
        if advance:   # a resend repeats the last measurement: the noise sequence depends on steps only
            self._last_measurement = self.sensors.measure(plant.q, plant.qdot, plant.rng)
        positions, velocities = self._last_measurement
        message.position = float_array(positions)
        if self._velocity_source == "model":
            message.velocity = float_array(velocities)
        self._efforts[-2:] = plant.torque
        message.effort = float_array(self._efforts)
        self._published_stamp, self._published_monotonic = stamp, time.monotonic()
        self._clock_message.clock = stamp
        self.clock_publisher.publish(self._clock_message)
        self.state_publisher.publish(message)

    def _publish_wake(self, time_s: float) -> None:
        """The wake's statistics, stamped with the start of the period its force was held over."""
        wake, publisher = self.plant.wake, self.wake_publisher
        assert wake is not None and publisher is not None   # called only with the wake on
        statistics = wake.statistics()
        message = WakeStatistics(
            vortex_count=statistics.vortex_count, shed_circulation_m2_s=statistics.shed_circulation_m2_s,
            total_circulation_m2_s=statistics.total_circulation_m2_s, force_x_n=statistics.foil_force[0],
            force_y_n=statistics.foil_force[1], moment_n_m=statistics.foil_force[2], thrust_n=statistics.thrust_n,
            joint_names=list(self.plant.model.joint_names), generalized_force=list(statistics.generalized_force),
            clipped_count=statistics.clipped_count, merged_count=statistics.merged_count,
            reflected_count=statistics.reflected_count)
        message.header.stamp = stamp_of(time_s)
        publisher.publish(message)

    # ----- services ------------------------------------------------------------------------------
    def _on_reset(self, request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        self._restart(self.initial_q, np.zeros(self.plant.model.nq))
        response.success, response.message = True, "vehicle back at its initial state"
        return response

    def _on_set_state(self, request: SetVehicleState.Request,
                      response: SetVehicleState.Response) -> SetVehicleState.Response:
        try:
            q, qdot = self._state_from_request(request.state)
        except ValueError as err:
            response.success, response.message = False, str(err)
            return response
        self._restart(q, qdot)
        response.success, response.message = True, "state set"
        return response

    def _state_from_request(self, state: JointState) -> tuple[np.ndarray, np.ndarray]:
        """(q, qdot) of a set_state request (no velocities: at rest); MessageError (a ValueError) if unusable."""
        q, qdot = joint_state_arrays(state.name, state.position, state.velocity, self.plant.model.joint_names)
        return q, qdot if qdot is not None else np.zeros_like(q)

    def _restart(self, q: np.ndarray, qdot: np.ndarray) -> None:
        """Put the vehicle at (q, qdot) at the current simulated time (time never runs backwards)."""
        time_s = self.plant.time_s
        try:
            self.plant.reset(q, qdot, time_s)
        except StateError as err:
            raise ValueError(str(err)) from err
        self.failed = None
        self.holding, self._held_state_answered = self._hold_enabled, False
        self._publish_state()


def main(args: list[str] | None = None) -> None:
    run_node(SimNode, args, name="sim_node", fatal_errors=(ValueError, SwimModelError))


if __name__ == "__main__":
    main()

