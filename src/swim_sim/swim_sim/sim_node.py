"""sim_node: the simulated rig (swim_model.plant) behind the same topics the hardware bridge serves.

Topics, services, flows, hard stops, modes (lock-step, real time), the held start and the parameters: see
src/swim_sim/README.md, section "sim_node". Why the per-period path reuses its messages and creates its topics
without QoS event handlers: see docs/speed.md, section "The closed loop over DDS".
"""
from __future__ import annotations

import dataclasses
import math
import time
from typing import Any, Optional, Sequence, cast

import numpy as np
from builtin_interfaces.msg import Time
from rclpy.node import Node
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from swim_interfaces.msg import WakeStatistics, WakeVortices
from swim_interfaces.srv import SetVehicleState

from swim_control.trajectory import MAX_ABS_START_ALPHA_RAD
from swim_model import StateError, SwimModelError, load_rig
from swim_model.disturbances import Disturbances
from swim_model.flow import FLOWS
from swim_model.plant import Plant, PlantSettings, SimulationError, make_plant
from swim_ros.codecs import MessageError, float_array, joint_state_arrays, stamp_of, torque_from_command
from swim_ros.entry import run_node
from swim_ros.parameters import NodeSettings, ParameterSpec, ParameterValue, finite, one_of
from swim_ros.qos import per_period_publisher, per_period_subscription
from swim_sim.sensors import SensorNoise, Sensors
from swim_sim.wake_coupling import parameter_defaults, parameters_from_values


def finite_entries(value: Any) -> Optional[str]:
    """A parameter check: every entry of an array must be a finite number."""
    return None if all(math.isfinite(v) for v in value) else "must have finite entries"


#: sim_node's parameters (swim_ros.parameters). Everything the plant, its model, its wake, its clock or its noise
#: sequence is built from at start is read-only (setting seed at run time could not restart the noise it seeded);
#: the velocities' source, the resend delay and the sensors' noise take effect when set. Upper bounds are assumed,
#: each far past any sensible value: they keep a typo (an extra zero, a wrong unit) out.
#: the largest value of a sensors.* parameter (counts of noise, a noise fraction, counts per line). Assumed: a
#: million counts of noise is far past any encoder, and keeps the noise and its quantization finite
SENSOR_PARAMETER_BOUND = 1.0e6
#: wake_vortices at 10 Hz: a few hundred vortices (the default merging bound: 300) at every 8 ms period would be
#: ~1 MB/s of bag; 10 Hz still shows a vortex move less than a centimetre between frames at the foil's 0.1 m/s
DEFAULT_VORTICES_PERIOD_S = 0.1
PARAMETERS: tuple[ParameterSpec, ...] = (
    ParameterSpec("rig_path", "", "rig YAML file (empty: swim_model's shipped rig)", read_only=True),
    ParameterSpec("constrained", False, "simulate the laterally constrained vehicle (no R)", read_only=True),
    ParameterSpec("flow", "ideal", "the water's model: 'ideal' (added mass), 'circulatory' (the reduced flow model, "
                  "its own foil drag), 'wake' (the vortex wake plus the disturbances' foil separation drag)",
                  check=one_of(*FLOWS), read_only=True),
    ParameterSpec("lane_radius_m", 0.0, "the constrained vehicle's lane radius, m (0: the rig's)",
                  range=(0.0, 10.0), read_only=True),
    ParameterSpec("sample_period_s", 0.008, "control period, s (the paper's 8 ms)", range=(1e-4, 1.0),
                  read_only=True),
    ParameterSpec("substeps", 8, "RK4 steps per period", range=(1, 10_000), read_only=True),
    ParameterSpec("mode", "lockstep", "'lockstep': a period per command; 'realtime': a period per timer tick",
                  check=one_of("lockstep", "realtime"), read_only=True),
    ParameterSpec("seed", 0, "seed of the disturbances' and the sensors' noise", range=(0, 2 ** 63 - 1),
                  read_only=True),
    ParameterSpec("start_time_s", 1.0, "simulated time at start, s (a zero stamp means 'not stamped')",
                  range=(0.0, 1.0e9), read_only=True),
    ParameterSpec("initial_positions", [0.0], "initial q, one entry per coordinate (alpha, [R,] phi, theta), rad "
                  "and m; any other length: at rest", check=finite_entries, read_only=True),
    ParameterSpec("velocity_source", "model", "'model': the model's velocities with noise; 'none': positions only",
                  check=one_of("model", "none")),
    ParameterSpec("resend_after_s", 0.5, "lock-step: an unanswered state is published again after this long, s",
                  range=(1e-3, 3600.0)),
    ParameterSpec("hold_until_torque", False, "lock-step: hold the initial state until the first nonzero torque",
                  read_only=True),
    *(ParameterSpec(f"disturbances.{f.name}", float(cast(float, f.default)),
                    f"swim_model.disturbances.Disturbances.{f.name}", check=finite, read_only=True)
      for f in dataclasses.fields(Disturbances)),
    *(ParameterSpec(f"sensors.{f.name}", cast(ParameterValue, f.default), f"swim_sim.sensors.SensorNoise.{f.name}",
                    range=None if isinstance(f.default, bool) else (0.0, SENSOR_PARAMETER_BOUND))
      for f in dataclasses.fields(SensorNoise)),
    *(ParameterSpec(f"wake.{name}", default, f"the vortex wake's {name} (swim_sim.wake_coupling)", check=finite,
                    read_only=True)
      for name, default in parameter_defaults().items()),
    ParameterSpec("wake.vortices_period_s", DEFAULT_VORTICES_PERIOD_S, "flow 'wake': wake_vortices is published at "
                  "most once per this much simulated time, s", range=(1e-3, 3600.0), read_only=True),
)


@dataclasses.dataclass(frozen=True)
class SimSettings:
    """PARAMETERS' values (swim_ros.parameters.NodeSettings).

    The disturbances.* and sensors.* groups come as their dataclasses, the wake.* group by name.
    """

    rig_path: str
    constrained: bool
    flow: str
    lane_radius_m: float
    sample_period_s: float
    substeps: int
    mode: str
    seed: int
    start_time_s: float
    initial_positions: list[float]
    velocity_source: str
    resend_after_s: float
    hold_until_torque: bool
    disturbances: Disturbances
    sensors: SensorNoise
    wake: dict[str, float]


def sensor_noise_reason(settings: SimSettings) -> Optional[str]:
    """The sensors' noise checked as a whole (it validates itself): why it is not valid, or None."""
    try:
        settings.sensors.validate()
    except ValueError as err:
        return str(err)
    return None


@dataclasses.dataclass(frozen=True)
class StateBounds:
    """What set_state accepts, per coordinate name: (lower, upper) positions and the largest speed.

    Each bound comes with where it comes from (said in a refusal, with how to change it).
    """

    positions: dict[str, tuple[float, float, str]]
    speeds: dict[str, tuple[float, str]]

    @classmethod
    def of(cls, plant: Plant) -> "StateBounds":
        """The bounds of a plant's rig: positions inside the rig's reach, speeds within its limits.

        The coordinate alpha stays within the plans' start-alpha bound (float64 keeps alpha to 1e-10 rad up to
        there), R inside the tank, heave and pitch within their hard stops; speeds within the rig's physically
        possible joint speeds (its limits).
        """
        rig = plant.model.rig
        where = f"the limits of {rig.source_path}; parameter rig_path"
        alpha = MAX_ABS_START_ALPHA_RAD
        positions = {"alpha": (-alpha, alpha, "swim_control.trajectory.MAX_ABS_START_ALPHA_RAD"),
                     "R": (0.0, 0.5 * rig.tank_diameter_m, f"the tank's radius (tank_diameter in {rig.source_path})")}
        for (name, (lower, upper)), joint in zip(plant.hard_limits_rad.items(), ("heave", "pitch")):
            positions[name] = (lower, upper, f"the hard stops ({joint}_hard_stop in {where})")
        speeds = {name: (speed, f"the physically possible speed ({key}_max_speed in {where})")
                  for name, key, speed in zip(("alpha", "R", "phi", "theta"), ("hub", "rail", "heave", "pitch"),
                                              rig.limits.max_speeds)}
        return cls(positions, speeds)

    def check(self, names: Sequence[str], q: np.ndarray, qdot: np.ndarray) -> None:
        """ValueError naming the first coordinate past its bound, the bound and where it comes from."""
        for name, position, speed in zip(names, q, qdot):
            lower, upper, position_source = self.positions[name]
            if not lower <= position <= upper:
                raise ValueError(f"{name} = {position:g} is outside [{lower:g}, {upper:g}], {position_source}")
            largest, speed_source = self.speeds[name]
            if abs(speed) > largest:
                raise ValueError(f"{name} velocity {speed:g} is faster than {largest:g}, {speed_source}")


class SimNode(Node):
    """The simulated rig's node (module docstring)."""

    def __init__(self) -> None:
        super().__init__("sim_node")
        self.parameters = NodeSettings(self, PARAMETERS, SimSettings, on_change=self._apply_parameters,
                                       check=sensor_noise_reason)
        settings = self.settings = self.parameters.current
        self.mode = settings.mode
        rig = load_rig(settings.rig_path or None)
        flow = settings.flow
        wake_parameters = parameters_from_values(settings.wake) if flow == "wake" else None
        # the plant's integrator and a wake's kernels load here, before the first state, which tells a controller
        # and a run's client that the loop is up
        self.plant = make_plant(PlantSettings(flow, settings.substeps, settings.disturbances), rig,
                                rig.hard_limits_rad, settings.constrained, settings.lane_radius_m or None,
                                settings.sample_period_s, settings.seed, wake_parameters)
        model = self.plant.model
        self.state_bounds = StateBounds.of(self.plant)
        self.sensors = Sensors(model, settings.sensors, self.plant.sample_period_s)
        self.start_time_s = float(settings.start_time_s)
        initial = settings.initial_positions   # nq entries, or at rest
        self.initial_q = np.asarray(initial, dtype=float) if len(initial) == model.nq else self.plant.rest_positions()
        self.plant.reset(self.initial_q, np.zeros(model.nq), self.start_time_s)
        self.failed: Optional[str] = None
        self.rejected_commands = 0
        self._latest_torque = np.zeros(2)
        self._published_stamp: Optional[Time] = None
        self._velocity_source = settings.velocity_source
        self._state_message = JointState(name=list(model.joint_names))   # reused every period
        self._clock_message = Clock()
        self._efforts = np.zeros(model.nq)   # the unactuated coordinates' entries stay zero
        self._hold_enabled = settings.hold_until_torque and self.mode == "lockstep"
        self.holding = self._hold_enabled
        self._held_state_answered = False

        self.state_publisher = per_period_publisher(self, JointState, "joint_states")
        self.clock_publisher = per_period_publisher(self, Clock, "/clock", 10)
        self.wake_publisher = per_period_publisher(self, WakeStatistics, "wake_statistics") \
            if self.plant.wake is not None else None
        self.vortices_publisher = per_period_publisher(self, WakeVortices, "wake_vortices") \
            if self.plant.wake is not None else None
        self._vortices_period_s = float(settings.wake["vortices_period_s"])
        self._vortices_due_s = -math.inf   # simulated time from which the next wake_vortices is sent
        per_period_subscription(self, JointState, "joint_commands", self._on_command)
        self.create_service(Trigger, "reset", self._on_reset)
        self.create_service(SetVehicleState, "set_state", self._on_set_state)
        if self.mode == "realtime":
            self.create_timer(self.plant.sample_period_s, self._on_tick)
        else:
            # a controller that starts late, or missed a state, still gets it
            self.create_timer(0.25 * settings.resend_after_s, self._resend)
            if self._hold_enabled:
                self.create_timer(self.plant.sample_period_s, self._republish_held_state)
        self._publish_state()
        self._prepare_period()
        self.get_logger().info(f"simulating the {'constrained' if model.constrained else 'free'} vehicle, "
                               f"flow {flow}, {self.mode}, period {self.plant.sample_period_s * 1e3:g} ms")

    # ----- parameters ------------------------------------------------------------------------------
    def _apply_parameters(self, previous: SimSettings, current: SimSettings) -> None:
        """Post-set: accepted values take effect (resend_after_s is read from the settings where it is used)."""
        self.settings = current
        if current.velocity_source != previous.velocity_source:
            self._velocity_source = current.velocity_source
            self._state_message.velocity = float_array(())   # the reused message's velocities: filled or left out
        if current.sensors != previous.sensors:
            self.sensors = Sensors(self.plant.model, current.sensors, self.plant.sample_period_s)

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
        if self.failed is None and waited_s >= self.settings.resend_after_s:
            self._publish_state(advance=False)

    def _republish_held_state(self) -> None:
        """Holding: the held state again, at most once a period of wall time and only once it was answered.

        A zero command answered at once would otherwise make an idle loop as fast as the CPU allows.
        """
        if self.holding and self._held_state_answered and self.failed is None:
            self._held_state_answered = False
            self._publish_state(advance=False)

    def _step(self, torque: np.ndarray) -> None:
        if self.failed is not None:
            return
        try:
            self.plant.step(torque)
        except (SimulationError, SwimModelError) as err:   # SwimModelError: the wake met a non-finite value
            self._fail(err)
            return
        self._publish_state()
        if self.wake_publisher is not None:
            self._publish_wake(self.plant.time_s - self.plant.sample_period_s)
            if self.plant.time_s >= self._vortices_due_s:
                self._publish_vortices()
        self._prepare_period()

    def _prepare_period(self) -> None:
        """The next period's wake and waves, computed while the controller computes its torque.

        They do not depend on the torque (Plant.prepare_period).
        """
        try:
            self.plant.prepare_period()
        except SwimModelError as err:   # the wake met a non-finite value
            self._fail(err)

    def _fail(self, err: Exception) -> None:
        self.failed = str(err)
        self.get_logger().error(f"simulation stopped: {err} (call reset or set_state to restart)")

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

    def _publish_vortices(self) -> None:
        """The free vortices (the newest WakeVortices.MAX_VORTEX_COUNT), stamped with the state they belong to."""
        wake, publisher = self.plant.wake, self.vortices_publisher
        assert wake is not None and publisher is not None   # called only with the wake on
        vortices = wake.vortices()
        newest = slice(-WakeVortices.MAX_VORTEX_COUNT, None)
        positions = vortices.positions_m[newest]
        message = WakeVortices(vortex_count=len(vortices.positions_m),
                               trailing_edge_x_m=vortices.trailing_edge_m.real,
                               trailing_edge_y_m=vortices.trailing_edge_m.imag)
        message.x_m, message.y_m = float_array(positions.real), float_array(positions.imag)
        message.circulations_m2_s = float_array(vortices.circulations_m2_s[newest])
        message.header.stamp = stamp_of(self.plant.time_s)
        publisher.publish(message)
        # simulated time is a sum of periods: a nanosecond (the stamps' resolution) absorbs its round-off
        self._vortices_due_s = self.plant.time_s + self._vortices_period_s - 1e-9

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
        """(q, qdot) of a set_state request (no velocities: at rest); ValueError if unusable or past a bound."""
        joint_names = self.plant.model.joint_names
        q, qdot = joint_state_arrays(state.name, state.position, state.velocity, joint_names)
        qdot = qdot if qdot is not None else np.zeros_like(q)
        self.state_bounds.check(joint_names, q, qdot)
        return q, qdot

    def _restart(self, q: np.ndarray, qdot: np.ndarray) -> None:
        """Put the vehicle at (q, qdot) at the current simulated time (time never runs backwards)."""
        time_s = self.plant.time_s
        try:
            self.plant.reset(q, qdot, time_s)
        except StateError as err:
            raise ValueError(str(err)) from err
        self.failed = None
        self.holding, self._held_state_answered = self._hold_enabled, False
        self._vortices_due_s = -math.inf   # the fresh wake's first vortices are sent at once
        self._publish_state()
        self._prepare_period()


def main(args: list[str] | None = None) -> None:
    """Run sim_node until shut down; args are ROS's command-line arguments."""
    run_node(SimNode, args, name="sim_node", fatal_errors=(ValueError, SwimModelError))


if __name__ == "__main__":
    main()

