"""bridge_node: the lifecycle node that runs our controller's torques on the rig's motors.

Topics, services, the lifecycle, the parameters and the amplifier-enable wiring: see src/swim_hw_bridge/README.md,
sections "bridge_node" and "Modules and API". The real-time means: docs/realtime.md, section "The means"; why the
I/O loop is a thread of this process: docs/realtime.md, section "Thread or process for the I/O loop".
"""
from __future__ import annotations

import collections
import dataclasses
import functools
import time
from typing import Optional

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.duration import Duration
from rclpy.lifecycle import Node as LifecycleNode
from rclpy.lifecycle import State, TransitionCallbackReturn
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool
from std_srvs.srv import Trigger

from swim_hw_bridge.backends import BACKENDS, UnknownBackend, make_device
from swim_hw_bridge.braking import joint_dynamics_bounds
from swim_hw_bridge.conversions import BridgeConfigError, Conversions, load_bridge_config
from swim_hw_bridge.device import Device, DeviceError
from swim_hw_bridge.io_loop import IoLoop, Snapshot
from swim_hw_bridge.safety import Command, FaultCode, SafetyLayer, SafetyLimits, WatchdogState, fault_names
from swim_hw_bridge.timing import LatencyHistogram
from swim_model import RigConfigError, load_rig
from swim_model.flow import FLOWS
from swim_model.plant import PlantSettings
from swim_model.vehicle import JOINT_NAMES_UNCONSTRAINED
from swim_ros.codecs import MessageError, torque_from_command
from swim_ros.entry import run_node
from swim_ros.lifecycle import configure_and_activate, guard_change_state_service
from swim_ros.parameters import NodeSettings, ParameterSpec, RealtimeParameterSettings, one_of, realtime_parameters
from swim_ros.qos import RECORDABLE_QOS
from swim_ros.realtime import (
    NO_REALTIME_MEANS,
    RealtimeOutcome,
    RealtimeSettings,
    make_process_ordinary,
    make_process_realtime,
    memory_locked_kib,
)
from swim_ros.transport import use_real_time_transport

#: the bridge's parameters (swim_ros.parameters). The lifecycle node reads them when it is configured: a value set
#: while configured or active takes effect at the next configure. What the node builds at start (the diagnostics
#: timer, autostart) is read-only.
PARAMETERS = (
    ParameterSpec("backend", "emulated", f"device backend: {' | '.join(BACKENDS)}",
                  check=lambda value: None if value in BACKENDS else f"must be one of {', '.join(BACKENDS)}"),
    ParameterSpec("config_path", "", "bridge parameter YAML (empty: the shipped config/bridge.yaml)"),
    ParameterSpec("rig_path", "", "rig YAML file: encoder lines, gear ratios, joint limits (empty: the shipped rig)"),
    ParameterSpec("flow", "ideal", f"the emulated rig's water: {' | '.join(FLOWS)}, as sim_node's flow (the other "
                  "backends swim in real water)", check=one_of(*FLOWS)),
    ParameterSpec("sample_period_s", 0.008, "I/O loop period, s (the paper's 8 ms)", range=(0.0005, 0.1)),
    ParameterSpec("watchdog_periods", 5, "periods without a command before the torque is zeroed", range=(1, 10000)),
    ParameterSpec("overrun_limit", 3, "overruns in a row that latch the OVERRUN fault", range=(1, 10000)),
    ParameterSpec("stale_read_limit", 3, "repeated device samples in a row that latch STALE_READ", range=(1, 10000)),
    ParameterSpec("read_failure_limit", 3, "failed device reads in a row that latch READ_FAILED", range=(1, 10000)),
    ParameterSpec("diagnostics_rate_hz", 2.0, "/diagnostics publication rate, Hz", range=(0.1, 100.0),
                  read_only=True),
    ParameterSpec("autostart", False, "configure and activate at start-up", read_only=True),
    ParameterSpec("io_loop_priority", 80, "real-time priority of the I/O loop's thread (1-98), above "
                  "realtime_priority so that nothing of the node's own delays a period", range=(1, 98),
                  read_only=True),
) + realtime_parameters(70, "node's threads while active (executor, middleware; the I/O loop: io_loop_priority)")


@dataclasses.dataclass(frozen=True)
class BridgeSettings(RealtimeParameterSettings):
    """PARAMETERS' values (swim_ros.parameters.NodeSettings), as the node was last configured with them."""

    backend: str
    config_path: str
    rig_path: str
    flow: str
    sample_period_s: float
    watchdog_periods: int
    overrun_limit: int
    stale_read_limit: int
    read_failure_limit: int
    diagnostics_rate_hz: float
    autostart: bool
    io_loop_priority: int


#: how many published states the node remembers, to find the state a command answers (its stamp): 0.5 s at 8 ms
STATES_REMEMBERED = 64


class BridgeNode(LifecycleNode):
    """The hardware bridge's lifecycle node (module docstring).

    owns_process: the node is its process's (main() makes it so) and applies the real-time means to it; a node
    made in another's process (a test's, a benchmark's) leaves that process's scheduling and collector alone.
    """

    def __init__(self, owns_process: bool = False) -> None:
        super().__init__("bridge_node")
        self.owns_process = owns_process
        guard_change_state_service(self)
        self.parameters = NodeSettings(self, PARAMETERS, BridgeSettings)
        self.settings = self.parameters.current   # what the last configure took
        self.state_publisher = self.create_lifecycle_publisher(JointState, "joint_states", RECORDABLE_QOS)
        self.diagnostics_publisher = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
        self.create_subscription(JointState, "joint_commands", self._on_command, 10)
        self.create_subscription(Bool, "emergency_stop", self._on_emergency_stop_topic, 10)
        self.create_service(Trigger, "emergency_stop", self._on_emergency_stop)
        self.create_service(Trigger, "reset_emergency_stop", self._on_reset)
        self.device: Device | None = None
        self.loop: IoLoop | None = None
        self.active = False
        self.malformed_commands = 0
        self._estop_pending = False   # an e-stop asked for while no device is configured
        self._state_label = "unconfigured"
        self._last_published_period = -1
        self._reported_faults = FaultCode.NONE
        # the I/O loop triggers it after each period: the state goes out right after the period that read it
        self._state_ready = self.create_guard_condition(self._publish_state)
        self.realtime_outcome: Optional[RealtimeOutcome] = None   # what the last activation got
        self._reset_command_timing()
        self._diagnostics_timer = self.create_timer(1.0 / self.settings.diagnostics_rate_hz,
                                                    self._publish_diagnostics)

    # --- lifecycle --------------------------------------------------------------------------------------------
    def on_configure(self, state: State) -> TransitionCallbackReturn:
        """Load the bridge and rig files, open the device at zero current and build the I/O loop."""
        self.settings = self.parameters.current
        try:
            config = load_bridge_config(self.settings.config_path or None, load_rig(self.settings.rig_path or None))
            device_config = config.device_config(self.settings.backend)
            if self.settings.backend == "emulated":
                device_config["plant"] = PlantSettings.flow_only(self.settings.flow)
            device = make_device(self.settings.backend, device_config)
            device.open()
        except (ValueError, BridgeConfigError, RigConfigError, UnknownBackend, DeviceError) as err:
            self.get_logger().error(f"configure failed: {err}")
            return TransitionCallbackReturn.FAILURE
        try:
            device.write_currents(0.0, 0.0)
            limits = SafetyLimits.from_config(config, self.settings.sample_period_s, self.settings.watchdog_periods,
                                              self.settings.stale_read_limit, self.settings.read_failure_limit,
                                              joint_dynamics_bounds(config.rig))
            self.loop = IoLoop(device, Conversions(config), SafetyLayer(limits), self.settings.sample_period_s,
                               self.settings.overrun_limit, self._realtime(), self.settings.io_loop_priority,
                               on_period=self._state_ready.trigger)
        except DeviceError as err:
            self.get_logger().error(f"configure failed: cannot zero the outputs: {err}")
            device.close()
            return TransitionCallbackReturn.FAILURE
        self.device = device
        if self._estop_pending:
            self.loop.emergency_stop()
        self._restart_diagnostics_timer()
        self._state_label = "inactive"
        water = f" (flow {self.settings.flow})" if self.settings.backend == "emulated" else ""
        self.get_logger().info(f"configured: backend {self.settings.backend}{water}, config {config.source_path}, rig "
                               f"{config.rig.source_path}")
        return super().on_configure(state)

    def on_activate(self, state: State) -> TransitionCallbackReturn:
        """Enable the amplifiers, take the real-time means and start the I/O loop."""
        assert self.device is not None and self.loop is not None
        try:
            self.device.enable()
        except DeviceError as err:
            self.get_logger().error(f"activate failed: cannot enable the amplifiers: {err}")
            return TransitionCallbackReturn.FAILURE
        self._make_realtime()
        self._reset_command_timing()
        self.loop.start(enable_toggling=True)
        self.active = True
        self._state_label = "active"
        self.get_logger().info("active: amplifiers enabled, I/O loop running")
        return super().on_activate(state)

    def _realtime(self) -> RealtimeSettings:
        """The means this node applies: its parameters' if it owns its process, none otherwise."""
        return self.settings.realtime if self.owns_process else NO_REALTIME_MEANS

    def _make_realtime(self) -> None:
        """The process's threads at realtime_priority while active, memory locked.

        The I/O loop sets its own thread above them. Said once at info level, or as one warning with what was
        refused and why.
        """
        if not self.owns_process:
            return
        outcome = make_process_realtime(self._realtime())
        if outcome != self.realtime_outcome:
            log = self.get_logger()
            (log.warning if outcome.refused else log.info)(outcome.summary())
        self.realtime_outcome = outcome

    def _reset_command_timing(self) -> None:
        """The command and state timing of an activation, from its start.

        The latency is the receipt of each command past the state it answers; the jitter its receipt past the
        command before, less the period. The state interval is the time between two states published, and the
        state publish the time the middleware's publish took: a plant silent for longer than a period shows in the
        first, and one whose publish blocked in the second as well (the loop's own lateness shows a stalled loop).
        """
        self.command_latency = LatencyHistogram()
        self.command_jitter = LatencyHistogram()
        self.state_interval = LatencyHistogram()
        self.state_publish = LatencyHistogram()
        self._last_state_published_s = float("nan")
        self._state_samples: collections.OrderedDict[int, float] = collections.OrderedDict()
        self._last_command_received_s = float("nan")

    def on_deactivate(self, state: State) -> TransitionCallbackReturn:
        """Zero the outputs and disable the amplifiers; ERROR when the device did not confirm both."""
        if not self._stop_outputs():
            # the outputs are not known to be safe: error processing (on_error) instead of "inactive"
            self.get_logger().error("deactivate failed: the device did not take the zero current or the disable")
            return TransitionCallbackReturn.ERROR
        self._state_label = "inactive"
        return super().on_deactivate(state)

    def on_cleanup(self, state: State) -> TransitionCallbackReturn:
        """Close the device."""
        self._close_device()
        self._state_label = "unconfigured"
        return super().on_cleanup(state)

    def on_shutdown(self, state: State) -> TransitionCallbackReturn:
        """Release the device (zero, disable, close)."""
        self.release()
        self._state_label = "finalized"
        return super().on_shutdown(state)

    def on_error(self, state: State) -> TransitionCallbackReturn:
        """Release the device and return to unconfigured."""
        self.get_logger().error("error processing: zero current, amplifiers disabled, device closed")
        self.release()
        self._state_label = "unconfigured"
        return TransitionCallbackReturn.SUCCESS

    def release(self) -> None:
        """Zero, then disable, then close, whatever state we are in (also on process exit)."""
        self._stop_outputs()
        self._close_device()

    def _stop_outputs(self) -> bool:
        """Stop the loop, zero, disable; True when all of it was done (or there is no device)."""
        self.active = False
        done = True
        if self.loop is not None and not self.loop.stop():
            self.get_logger().error("the I/O loop did not stop within 1 s (device call hung?)")
            done = False
        if self._realtime().realtime:
            make_process_ordinary()   # what runs next (a configure's compilation) is no period
        if self.device is None:
            return done
        for action, call in (("zero the currents", lambda: self.device.write_currents(0.0, 0.0)),
                             ("disable the amplifiers", self.device.disable)):
            try:
                call()
            except DeviceError as err:
                self.get_logger().error(f"cannot {action}: {err}")
                done = False
        return done

    def _close_device(self) -> None:
        if self.device is not None:
            try:
                self.device.close()
            except DeviceError as err:
                self.get_logger().error(f"cannot close the device: {err}")
        self.device, self.loop = None, None

    # --- commands and e-stop -----------------------------------------------------------------------------------
    def _on_command(self, message: JointState) -> None:
        received_s = time.monotonic()
        if not self.active or self.loop is None:
            return
        try:
            heave_n_m, pitch_n_m = torque_from_command(message.name, message.effort)
        except MessageError as err:
            self.malformed_commands += 1
            self.get_logger().warning(f"joint_commands refused ({self.malformed_commands} so far): {err}",
                                      throttle_duration_sec=1.0)
            return
        stamp_ns = message.header.stamp.sec * 1_000_000_000 + message.header.stamp.nanosec
        self.loop.set_command(Command(heave_n_m, pitch_n_m, received_s, stamp_ns))
        self.command_jitter.add(abs(received_s - self._last_command_received_s - self.settings.sample_period_s))
        self._last_command_received_s = received_s
        sample_s = self._state_samples.get(stamp_ns)
        if sample_s is not None:
            self.command_latency.add(received_s - sample_s)

    def _emergency_stop(self) -> None:
        self._estop_pending = True
        if self.loop is not None:
            self.loop.emergency_stop()
        self.get_logger().error("EMERGENCY STOP: zero current, amplifier enable stopped, latched until reset")

    def _on_emergency_stop(self, request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        self._emergency_stop()
        response.success, response.message = True, "emergency stop latched until reset_emergency_stop"
        return response

    def _on_emergency_stop_topic(self, message: Bool) -> None:
        if message.data:
            self._emergency_stop()
        else:
            self.get_logger().warning("emergency_stop false ignored: only the reset_emergency_stop service resets",
                                      throttle_duration_sec=5.0)

    def _on_reset(self, request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        self._estop_pending = False
        if self.loop is not None:
            self.loop.reset(time.monotonic())
        self.get_logger().info("emergency stop and faults reset: torque resumes with the next command")
        response.success, response.message = True, "reset: torque resumes with a command received from now on"
        return response

    # --- publishing --------------------------------------------------------------------------------------------
    def _publish_state(self) -> None:
        snapshot = self.loop.snapshot() if self.loop is not None else None
        if snapshot is None or snapshot.periods == self._last_published_period:
            return
        self._last_published_period = snapshot.periods
        message = JointState()
        age_s = max(time.monotonic() - snapshot.monotonic_s, 0.0)
        stamp = self.get_clock().now() - Duration(nanoseconds=int(age_s * 1e9))
        message.header.stamp = stamp.to_msg()
        self._state_samples[stamp.nanoseconds] = snapshot.monotonic_s
        if len(self._state_samples) > STATES_REMEMBERED:
            self._state_samples.popitem(last=False)
        message.name = list(JOINT_NAMES_UNCONSTRAINED)   # the rig's free vehicle: the bridge reads every encoder
        message.position = list(snapshot.positions)
        message.velocity = list(snapshot.velocities)
        message.effort = [0.0, 0.0, snapshot.torques_n_m[0], snapshot.torques_n_m[1]]
        publish_start_s = time.monotonic()
        self.state_publisher.publish(message)
        published_s = time.monotonic()
        self.state_publish.add(published_s - publish_start_s)
        self.state_interval.add(published_s - self._last_state_published_s)   # NaN, not counted, for the first
        self._last_state_published_s = published_s

    def _restart_diagnostics_timer(self) -> None:
        self.destroy_timer(self._diagnostics_timer)
        self._diagnostics_timer = self.create_timer(1.0 / self.settings.diagnostics_rate_hz,
                                                    self._publish_diagnostics)

    def _publish_diagnostics(self) -> None:
        snapshot = self.loop.snapshot() if self.loop is not None else None
        self._log_new_faults(snapshot)
        array = DiagnosticArray()
        array.header.stamp = self.get_clock().now().to_msg()
        array.status = [self.diagnostic_status(snapshot)]
        self.diagnostics_publisher.publish(array)

    def _log_new_faults(self, snapshot: Snapshot | None) -> None:
        faults = snapshot.faults if snapshot is not None else FaultCode.NONE
        new = faults & ~self._reported_faults
        if new:
            self.get_logger().error(f"fault latched: {fault_names(new)} (zero current until reset)")
        self._reported_faults = faults

    def _timing_values(self, snapshot: Snapshot) -> dict[str, object]:
        """How the periods went since the activation.

        Overruns by cause and the worst one, the wake-up lateness, the commands' latency and jitter (median and
        p99, ms), and the real-time means in effect.
        """
        loop = self.loop
        by_cause = dict(zip(("late_wakeup", "slow_read", "slow_write", "slow_work"), snapshot.overruns_by_cause))
        values: dict[str, object] = {f"overruns_{cause}": count for cause, count in by_cause.items()}
        values["worst_lateness_ms"] = f"{snapshot.worst_lateness_s * 1e3:.3f}"
        values["worst_lateness_cause"] = snapshot.worst_lateness_cause.name
        for name, histogram in (("wake_lateness", loop.wake_lateness if loop is not None else None),
                                ("command_latency", self.command_latency), ("command_jitter", self.command_jitter),
                                ("state_interval", self.state_interval), ("state_publish", self.state_publish)):
            for percent in (50, 99):
                value_s = histogram.percentile_s(percent) if histogram is not None else float("nan")
                values[f"{name}_p{percent}_ms"] = f"{value_s * 1e3:.3f}"
            values[f"{name}_max_ms"] = f"{histogram.largest_s * 1e3:.3f}" if histogram is not None else "nan"
        if loop is not None:
            policy, priority = loop.thread_policy
            values["io_loop_scheduling"] = f"SCHED_{policy.upper()} {priority}"
            values["gc_longest_ms"] = f"{loop.collector.longest_s * 1e3:.3f}" if loop.collector is not None else "off"
        values["memory_locked_kib"] = memory_locked_kib()
        refused = list(self.realtime_outcome.refused) if self.realtime_outcome is not None else []
        if loop is not None and loop.policy_refused is not None:
            refused.append(f"I/O loop: {loop.policy_refused}")
        values["realtime_refused"] = "; ".join(refused)
        return values

    def _loop_running(self) -> bool:
        return self.loop is not None and self.loop.running

    def diagnostic_status(self, snapshot: Snapshot | None) -> DiagnosticStatus:
        """The I/O loop's diagnostics at a snapshot (None: the loop has not run yet)."""
        status = DiagnosticStatus(name=f"{self.get_fully_qualified_name()}: I/O loop",
                                  hardware_id=self.settings.backend)
        values = {"lifecycle_state": self._state_label, "malformed_commands": self.malformed_commands,
                  "emergency_stop_pending": self._estop_pending}
        if snapshot is None:
            status.level, status.message = DiagnosticStatus.WARN, f"{self._state_label}: I/O loop not running yet"
        else:
            running = self._loop_running()
            # a stopped loop's last period is not what the device holds: a deactivate stops the loop, then writes
            # zero; one that cannot write it ends in on_error, which drops the loop
            currents_a, torques_n_m = (snapshot.currents_a, snapshot.torques_n_m) if running else ((0.0, 0.0),) * 2
            values.update(
                loop_rate_hz=f"{snapshot.loop_rate_hz:.2f}", periods=snapshot.periods, overruns=snapshot.overruns,
                consecutive_overruns=snapshot.consecutive_overruns, watchdog=snapshot.watchdog.name,
                saturation_count=snapshot.saturation_count, fault_code=int(snapshot.faults),
                faults=fault_names(snapshot.faults), loop_running=running,
                enable_toggling=snapshot.enable_toggling and running,
                heave_current_a=currents_a[0], pitch_current_a=currents_a[1],
                heave_torque_n_m=torques_n_m[0], pitch_torque_n_m=torques_n_m[1])
            values.update(self._timing_values(snapshot))
            if snapshot.faults:
                status.level, status.message = DiagnosticStatus.ERROR, f"fault: {fault_names(snapshot.faults)}"
                if snapshot.faults & FaultCode.OVERRUN:
                    status.message += f" ({overrun_phrase(snapshot)})"
            elif not self.active or snapshot.watchdog is not WatchdogState.OK:
                status.level = DiagnosticStatus.WARN
                status.message = f"{self._state_label}, watchdog {snapshot.watchdog.name}: zero torque"
            else:
                status.level, status.message = DiagnosticStatus.OK, "active"
        status.values = [KeyValue(key=key, value=str(value)) for key, value in values.items()]
        return status


def overrun_phrase(snapshot: Snapshot) -> str:
    """The worst overrun and its cause, as the fault's message says it: "worst 12.3 ms late, late wake-up"."""
    cause = snapshot.worst_lateness_cause.name.lower().replace("_", " ").replace("wakeup", "wake-up")
    return f"worst {snapshot.worst_lateness_s * 1e3:.1f} ms late, {cause}"


def autostart(node: BridgeNode) -> None:
    """With the autostart parameter: configure, then activate (each only if the one before succeeded)."""
    if node.settings.autostart:
        configure_and_activate(node)


def main(args: list[str] | None = None) -> None:
    """Run bridge_node until shut down; args are ROS's command-line arguments."""
    # release: zero, then disable, then close, however the node stops: never leave the amplifiers driven
    # UDP only: a reader's shared-memory port opened mid-run would hold a state's publish (swim_ros.transport)
    run_node(functools.partial(BridgeNode, owns_process=True), args, name="bridge_node", start=autostart,
             stop=BridgeNode.release, transport=use_real_time_transport)


if __name__ == "__main__":
    main()
