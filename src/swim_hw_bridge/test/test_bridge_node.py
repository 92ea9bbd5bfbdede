"""bridge_node over DDS: the real node in its own process with the emulated rig, driven from the test side.

The test side closes a PD loop (the role tracker_node plays) over joint_states -> joint_commands, and drives the
lifecycle through bridge_node/change_state as a lifecycle manager would.
"""
import math
import os
import sys
import textwrap
import time

import pytest

from swim_ros.calls import ParameterCalls, RetryPolicy, spin_until
from swim_ros.processes import start_child
from swim_ros.testing.fixtures import MESSAGE_TIMEOUT_S, STARTUP_TIMEOUT_S, fast_dds_shared_memory, running_node

#: the bridge answers its services within a period or two; a try waits 10 s for a loaded host, a lost answer is
#: asked again (lifecycle transitions only after reading the node's state)
POLICY = RetryPolicy(attempt_timeout_s=10.0, attempts=3, discovery_timeout_s=STARTUP_TIMEOUT_S)

PERIOD_S = 0.008
# a long watchdog (200 ms) keeps "the old command is still within the watchdog after a reset" observable
WATCHDOG_PERIODS = 25
WATCHDOG_S = WATCHDOG_PERIODS * PERIOD_S
#: a PD hold (a command answering each state): 37 periods, so the watchdog reads OK and what is watched during it
#: is seen; with the heave loop's 3 rad/s it also brings the foil most of the way back to rest
HOLD_S = 0.3
#: after the saturating command of test_diagnostics_report_the_loop: the foil brought back toward rest for the next
#: test (about one and a half time constants of the 3 rad/s heave loop)
RECOVER_HOLD_S = 0.5
#: the PD's approach to a target (heave about 3 rad/s): within 0.03 rad in about a second; 10 s for a loaded host
TARGET_TIMEOUT_S = 10.0
#: how long the states are watched past the watchdog's expiry (the test holds for the watchdog period and this): the
#: first zero torque is expected within 0.15 s of the expiry (asserted), and the states after it must all be zero
PAST_WATCHDOG_S = 0.3
#: states published before a transition may still be in flight when its service answers: 0.1 s, 12 periods, for
#: them to arrive before the silence that should follow is watched
IN_FLIGHT_S = 0.1
#: a bridge that publishes would show states within this window (37 periods at 125 Hz, 12 at the serial test's
#: 40 Hz): how long silence is watched
SILENCE_WINDOW_S = 0.3
#: the states counted after activate: 62 periods at 125 Hz (at least 40 asserted); ends at the 40th state
RATE_WINDOW_S = 0.5
#: a message that must change nothing (emergency_stop false) reaches the bridge within milliseconds here; 0.1 s
#: before the check that it did not
NO_EFFECT_WINDOW_S = 0.1
#: the command sent just before the reset must reach the bridge first (a topic arrives within milliseconds here),
#: and the reset must come well inside that command's 200 ms watchdog window: nothing to wait on, 10 ms
COMMAND_BEFORE_RESET_S = 0.01
#: after the reset, watched for torque: 10 periods, inside the old command's watchdog window, so torque here would
#: be the old command's
AFTER_RESET_WINDOW_S = 0.08
#: between malformed commands: more than one 8 ms period, so a bad command the bridge used would show in a state of
#: its own
BAD_COMMAND_SPACING_S = 0.01
#: readers that join the running bridge from processes whose shared-memory port has been idle (a viewer or a
#: recorder started mid-run): one in 8 to 40 held a publish of Fast DDS's default transport for 333 ms
#: (docs/realtime.md); 30 joiners meet that at least once with a probability of 0.5 to 0.98
IDLE_JOINERS = 30
#: how long the joiners' participants idle before the first subscribes, s (Fast DDS's health watchdog looks at a
#: port once a second), and the time between two subscriptions, s
JOINERS_IDLE_S, JOINERS_SPACING_S = 2.5, 0.3
#: how long the joiners' process may take, s: its idle time, the joiners' spacing and 5 s for the last states,
#: with room for starting 30 participants on a loaded host
JOINERS_TIMEOUT_S = 120.0
#: a state's publish that takes longer than this, ms, was held by the middleware: the bridge's publish takes well
#: under a millisecond, a held one 333 ms
HELD_PUBLISH_MS = 50.0
#: the emulated serial board's own command and enable-toggle timeouts (its firmware watchdogs): generous for a
#: loaded host
FIRMWARE_TIMEOUT_MS = 300
#: the serial backend's wait for the board's STATE reply (default 5 ms): 20 ms for the emulated firmware, a thread of
#: this test process on a loaded host, still within the serial test's 25 ms loop
SERIAL_READ_TIMEOUT_S = 0.02
#: how long the serial backend's open keeps sending HELLO until the board answers (default 2 s): the emulated
#: firmware answers in milliseconds; 5 s for a loaded host
SERIAL_OPEN_TIMEOUT_S = 5.0


class BridgeClient:
    """The test's side of the bridge: lifecycle and e-stop services, commands out, states and diagnostics in."""

    def __init__(self, context, namespace="", log_path=None):
        import rclpy
        from diagnostic_msgs.msg import DiagnosticArray
        from lifecycle_msgs.srv import ChangeState, GetState
        from rclpy.executors import SingleThreadedExecutor
        from sensor_msgs.msg import JointState
        from std_msgs.msg import Bool
        from std_srvs.srv import Trigger
        self.log_path = log_path   # the bridge's output, shown when it does not answer
        self.node = rclpy.create_node("bridge_test_client", namespace=namespace or "/", context=context)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        prefix = f"{namespace}/" if namespace else ""
        self.fully_qualified = f"{namespace}/bridge_node" if namespace else "/bridge_node"
        self.change_state = self.node.create_client(ChangeState, f"{prefix}bridge_node/change_state")
        self.get_state = self.node.create_client(GetState, f"{prefix}bridge_node/get_state")
        self.estop = self.node.create_client(Trigger, f"{prefix}emergency_stop")
        self.reset = self.node.create_client(Trigger, f"{prefix}reset_emergency_stop")
        self.commands = self.node.create_publisher(JointState, f"{prefix}joint_commands", 10)
        self.estop_topic = self.node.create_publisher(Bool, f"{prefix}emergency_stop", 10)
        self.states = []        # (monotonic receive time, JointState)
        self.diagnostics = []   # (stamp ns, DiagnosticStatus) of this bridge
        self.node.create_subscription(JointState, f"{prefix}joint_states",
                                      lambda m: self.states.append((time.monotonic(), m)), 50)
        self.node.create_subscription(DiagnosticArray, "/diagnostics", self._on_diagnostics, 10)
        assert self.change_state.wait_for_service(timeout_sec=STARTUP_TIMEOUT_S), "bridge_node did not come up"

    def _on_diagnostics(self, array):
        stamp_ns = array.header.stamp.sec * 1_000_000_000 + array.header.stamp.nanosec
        self.diagnostics += [(stamp_ns, s) for s in array.status if s.name.startswith(self.fully_qualified + ":")]

    def close(self):
        self.executor.shutdown()
        self.node.destroy_node()

    def spin(self, seconds):
        """Serve callbacks for seconds: a window in which something must (or must not) happen."""
        end = time.monotonic() + seconds
        while (remaining := end - time.monotonic()) > 0.0:
            self.executor.spin_once(timeout_sec=remaining)

    def wait_for(self, condition, timeout_s=MESSAGE_TIMEOUT_S):
        """Serve callbacks until condition() holds (True) or timeout_s passes (False)."""
        return spin_until(self.executor, condition, timeout_s)

    def call(self, client, request):
        """An idempotent service's answer (asked again if lost); fails the test with the bridge's log if none."""
        from swim_ros.calls import CallFailed, call_service
        try:
            return call_service(self.executor, client, request, POLICY)
        except CallFailed as err:
            raise AssertionError(f"{err}; the bridge's log ends:\n{self.log_tail()}") from err

    def log_tail(self, characters=3000):
        return self.log_path.read_text()[-characters:] if self.log_path is not None else "(not kept)"

    def transition(self, transition_id):
        """A lifecycle transition, asked again only if the node's state shows it was not made (swim_ros.calls)."""
        from swim_ros.calls import CallFailed, change_lifecycle_state
        try:
            return change_lifecycle_state(self.node, self.executor, self.fully_qualified, transition_id, POLICY)
        except CallFailed as err:
            raise AssertionError(f"{err}; the bridge's log ends:\n{self.log_tail()}") from err

    def state_label(self):
        from lifecycle_msgs.srv import GetState
        return self.call(self.get_state, GetState.Request()).current_state.label

    def trigger(self, client):
        from std_srvs.srv import Trigger
        return self.call(client, Trigger.Request())

    def send(self, efforts, names=("phi", "theta")):
        from sensor_msgs.msg import JointState
        message = JointState(name=list(names), effort=[float(e) for e in efforts])
        message.header.stamp = self.node.get_clock().now().to_msg()
        self.commands.publish(message)

    def hold(self, seconds, target=(0.0, 0.0), until=None):
        """PD on (phi, theta) to target from each joint_states, as a controller would, for seconds, or until
        until() holds (then True)."""
        gains = ((1.0, 0.3), (0.1, 0.02))   # N m/rad, N m s/rad: heave, pitch (about 3 and 8 rad/s)
        end = time.monotonic() + seconds
        answered = len(self.states)
        while (remaining := end - time.monotonic()) > 0.0:
            if until is not None and until():
                return True
            self.executor.spin_once(timeout_sec=remaining)
            if len(self.states) > answered:
                answered = len(self.states)
                state = self.states[-1][1]
                self.send([-kp * (state.position[j] - target[j - 2]) - kd * state.velocity[j]
                           for j, (kp, kd) in zip((2, 3), gains)])
        return until is not None and until()

    def diagnosed_since(self, since_ns, condition):
        """Whether a status of the bridge made at or after since_ns (wall clock, ns) has values satisfying
        condition({key: value})."""
        return any(stamp_ns >= since_ns and condition({kv.key: kv.value for kv in status.values})
                   for stamp_ns, status in self.diagnostics)

    def latest_diagnostic(self, timeout_s=MESSAGE_TIMEOUT_S):
        """The bridge's first status made after this call began (the bridge stamps /diagnostics with the wall
        clock when it reads its loop): one already in flight or queued would describe the loop before."""
        called_ns = time.time_ns()
        self.diagnostics.clear()
        self.wait_for(lambda: any(stamp_ns >= called_ns for stamp_ns, _ in self.diagnostics), timeout_s)
        fresh = [status for stamp_ns, status in self.diagnostics if stamp_ns >= called_ns]
        assert fresh, "no /diagnostics from the bridge"
        return fresh[0], {kv.key: kv.value for kv in fresh[0].values}


def efforts(client, since):
    return [tuple(m.effort[2:]) for t, m in client.states if t >= since]


@pytest.fixture(scope="module")
def bridge_process(ros_domain, tmp_path_factory):
    """The shared bridge's process and its log."""
    log = tmp_path_factory.mktemp("bridge_node") / "log.txt"
    with running_node("swim_hw_bridge", "bridge_node", log, "-p", f"watchdog_periods:={WATCHDOG_PERIODS}",
                      "-p", "diagnostics_rate_hz:=20.0") as process:
        yield process, log


@pytest.fixture(scope="module")
def bridge_log(bridge_process):
    return bridge_process[1]


@pytest.fixture()
def bridge(bridge_log, rclpy_context):
    """The shared bridge, active, no e-stop, the foil held at rest."""
    from lifecycle_msgs.msg import Transition
    client = BridgeClient(rclpy_context, log_path=bridge_log)
    if client.state_label() == "unconfigured":
        assert client.transition(Transition.TRANSITION_CONFIGURE)
    if client.state_label() == "inactive":
        assert client.transition(Transition.TRANSITION_ACTIVATE)
    assert client.trigger(client.reset).success
    client.hold(HOLD_S)
    yield client
    client.hold(HOLD_S)
    client.close()


def thread_policies(pid):
    """{thread id: (scheduling policy, priority)} of every thread of the process pid."""
    policies = {}
    for name in os.listdir(f"/proc/{pid}/task"):
        try:
            policies[int(name)] = (os.sched_getscheduler(int(name)), os.sched_getparam(int(name)).sched_priority)
        except ProcessLookupError:
            pass   # a thread that ended meanwhile
    return policies


def test_lifecycle_transitions_open_enable_and_release_the_device(ros_domain, rclpy_context, tmp_path):
    from lifecycle_msgs.msg import Transition
    with running_node("swim_hw_bridge", "bridge_node", tmp_path / "log.txt", "-r", "__ns:=/lifecycle_test",
                      "-p", "diagnostics_rate_hz:=20.0") as process:
        client = BridgeClient(rclpy_context, "/lifecycle_test", tmp_path / "log.txt")
        try:
            assert client.state_label() == "unconfigured"
            assert not client.transition(Transition.TRANSITION_ACTIVATE)   # not from unconfigured
            assert client.transition(Transition.TRANSITION_CONFIGURE)
            assert client.state_label() == "inactive"
            client.spin(SILENCE_WINDOW_S)
            assert not client.states   # inactive: the loop is not running, nothing published
            _, values = client.latest_diagnostic()
            assert values["lifecycle_state"] == "inactive"
            assert set(thread_policies(process.pid).values()) == {(os.SCHED_OTHER, 0)}   # configuring: ordinary

            assert client.transition(Transition.TRANSITION_ACTIVATE)
            client.wait_for(lambda: len(client.states) >= 40, RATE_WINDOW_S)
            assert client.state_label() == "active"
            assert len(client.states) >= 40   # about 62 at 125 Hz
            state = client.states[-1][1]
            assert list(state.name) == ["alpha", "R", "phi", "theta"]
            assert state.position[1] == pytest.approx(0.43, abs=1e-3)   # the rig's home lane
            assert len(state.velocity) == 4 and list(state.effort) == [0.0] * 4   # no command yet: zero
            status, values = client.latest_diagnostic()
            assert values["lifecycle_state"] == "active" and values["enable_toggling"] == "True"
            assert values["watchdog"] == "WAITING"
            if os.geteuid() == 0:   # the real-time means (CI runs as root): the I/O loop above the rest
                policies = sorted(thread_policies(process.pid).values())
                assert set(policies) == {(os.SCHED_FIFO, 70), (os.SCHED_FIFO, 80)}
                assert policies.count((os.SCHED_FIFO, 80)) == 1
                assert values["io_loop_scheduling"] == "SCHED_FIFO 80" and values["realtime_refused"] == ""
                assert int(values["memory_locked_kib"]) > 0

            assert client.transition(Transition.TRANSITION_DEACTIVATE)
            client.spin(IN_FLIGHT_S)
            client.states.clear()
            client.spin(SILENCE_WINDOW_S)
            assert not client.states
            _, values = client.latest_diagnostic()
            assert values["lifecycle_state"] == "inactive" and values["enable_toggling"] == "False"
            assert set(thread_policies(process.pid).values()) == {(os.SCHED_OTHER, 0)}   # given up

            assert client.transition(Transition.TRANSITION_CLEANUP)
            assert client.state_label() == "unconfigured"
            assert client.transition(Transition.TRANSITION_CONFIGURE)   # and round again
            assert client.transition(Transition.TRANSITION_ACTIVATE)
            client.wait_for(lambda: bool(client.states))
            assert client.states
            assert client.transition(Transition.TRANSITION_ACTIVE_SHUTDOWN)
            assert client.state_label() == "finalized"
        finally:
            client.close()


def test_a_bad_configuration_fails_configure_and_the_node_carries_on(ros_domain, rclpy_context, tmp_path):
    from lifecycle_msgs.msg import Transition
    with running_node("swim_hw_bridge", "bridge_node", tmp_path / "log.txt", "-r", "__ns:=/bad_config",
                      "-p", f"config_path:={tmp_path / 'missing.yaml'}") as process:
        client = BridgeClient(rclpy_context, "/bad_config", tmp_path / "log.txt")
        try:
            assert not client.transition(Transition.TRANSITION_CONFIGURE)
            assert client.state_label() == "unconfigured" and process.poll() is None
        finally:
            client.close()
    assert "cannot read the bridge file" in (tmp_path / "log.txt").read_text()


def test_commands_reach_the_motors_and_the_watchdog_zeroes_the_torque(bridge):
    def on_target():
        position = bridge.states[-1][1].position if bridge.states else None
        return position is not None and abs(position[2] - 0.1) <= 0.03 and abs(position[3] + 0.1) <= 0.03
    bridge.hold(TARGET_TIMEOUT_S, target=(0.1, -0.1), until=on_target)
    state = bridge.states[-1][1]
    assert state.position[2] == pytest.approx(0.1, abs=0.03) and state.position[3] == pytest.approx(-0.1, abs=0.03)
    bridge.send([0.05, -0.01])   # one last command, then silence
    last_sent = time.monotonic()
    bridge.wait_for(lambda: (0.05, -0.01) in [pytest.approx(e) for e in efforts(bridge, last_sent)])
    assert (0.05, -0.01) in [pytest.approx(e) for e in efforts(bridge, last_sent)]
    status, values = bridge.latest_diagnostic()
    assert values["watchdog"] == "OK" and status.level == status.OK
    bridge.spin(WATCHDOG_S + PAST_WATCHDOG_S)
    zeroed = [t for t, m in bridge.states if t > last_sent and tuple(m.effort[2:]) == (0.0, 0.0)]
    assert zeroed, "the watchdog never zeroed the torque"
    assert WATCHDOG_S - 0.01 < zeroed[0] - last_sent < WATCHDOG_S + 0.15
    assert all(e == (0.0, 0.0) for e in efforts(bridge, zeroed[0]))
    _, values = bridge.latest_diagnostic()
    assert values["watchdog"] == "EXPIRED"


@pytest.mark.parametrize("how", ["service", "topic"])
def test_emergency_stop_latches_until_reset_and_a_fresh_command(bridge, how):
    from std_msgs.msg import Bool
    bridge.hold(HOLD_S)
    asked_ns = time.time_ns()
    if how == "service":
        assert bridge.trigger(bridge.estop).success
    else:
        bridge.estop_topic.publish(Bool(data=True))
    # the latch reported on /diagnostics: from then on every state must show zero torque
    bridge.wait_for(lambda: bridge.diagnosed_since(asked_ns,
                                                   lambda values: "EMERGENCY_STOP" in values.get("faults", "")))
    stopped = time.monotonic()
    bridge.hold(HOLD_S, target=(0.3, 0.3))   # commands keep coming: all refused while latched
    assert efforts(bridge, stopped) and all(e == (0.0, 0.0) for e in efforts(bridge, stopped))
    status, values = bridge.latest_diagnostic()
    assert status.level == status.ERROR and "EMERGENCY_STOP" in values["faults"]
    assert values["enable_toggling"] == "False"
    bridge.estop_topic.publish(Bool(data=False))   # false does not reset
    bridge.send([0.05, 0.0])
    bridge.spin(NO_EFFECT_WINDOW_S)
    assert "EMERGENCY_STOP" in bridge.latest_diagnostic()[1]["faults"]
    # reset: the last command is still inside the watchdog window, but it predates the reset: no torque
    bridge.send([0.05, 0.0])
    bridge.spin(COMMAND_BEFORE_RESET_S)
    assert bridge.trigger(bridge.reset).success
    reset_at = time.monotonic()
    bridge.spin(AFTER_RESET_WINDOW_S)
    assert all(e == (0.0, 0.0) for e in efforts(bridge, reset_at))
    _, values = bridge.latest_diagnostic()
    assert values["faults"] == "NONE" and values["watchdog"] == "WAITING"
    bridge.send([0.05, 0.0])
    sent = time.monotonic()
    bridge.wait_for(lambda: (0.05, 0.0) in [pytest.approx(e) for e in efforts(bridge, sent)])
    assert (0.05, 0.0) in [pytest.approx(e) for e in efforts(bridge, sent)]


def test_malformed_commands_are_counted_and_ignored(bridge):
    before = int(bridge.latest_diagnostic()[1]["malformed_commands"])
    bridge.send([0.01, 0.0])
    sent = time.monotonic()
    bad = [dict(efforts=[0.2, 0.2], names=("phi", "alpha")), dict(efforts=[0.2], names=("phi", "theta")),
           dict(efforts=[0.2, 0.2, 0.2], names=("phi", "theta", "R")), dict(efforts=[math.nan, 0.2]),
           dict(efforts=[0.2, math.inf]), dict(efforts=[0.2, 0.2], names=("phi", "phi"))]
    for message in bad:
        bridge.send(**message)
        bridge.spin(BAD_COMMAND_SPACING_S)
    # every bad command counted, as /diagnostics reports
    last_bad_ns = time.time_ns()
    bridge.wait_for(lambda: bridge.diagnosed_since(
        last_bad_ns, lambda values: int(values["malformed_commands"]) >= before + len(bad)))
    applied = efforts(bridge, sent)
    assert not [e for e in applied if 0.2 in (pytest.approx(abs(e[0])), pytest.approx(abs(e[1])))]   # never used
    assert applied[-1] == pytest.approx((0.01, 0.0))   # the good command still holds: none replaced it
    _, values = bridge.latest_diagnostic()
    assert int(values["malformed_commands"]) == before + len(bad)
    assert values["faults"] == "NONE"


def test_diagnostics_report_the_loop(bridge):
    bridge.hold(HOLD_S)
    status, values = bridge.latest_diagnostic()
    assert status.level == status.OK and status.hardware_id == "emulated"
    assert float(values["loop_rate_hz"]) == pytest.approx(1 / PERIOD_S, rel=0.1)
    for key in ("overruns", "consecutive_overruns", "saturation_count", "fault_code", "periods"):
        assert int(values[key]) >= 0
    assert values["fault_code"] == "0" and values["watchdog"] == "OK"
    interval_p50_ms = float(values["state_interval_p50_ms"])
    assert interval_p50_ms == pytest.approx(PERIOD_S * 1e3, rel=0.25)   # one state a period
    assert float(values["state_interval_max_ms"]) >= interval_p50_ms
    assert 0.0 < float(values["state_publish_p50_ms"]) < PERIOD_S * 1e3
    saturated = int(values["saturation_count"])
    bridge.send([50.0, 0.0])   # far past the 1.25 N m heave limit: clipped and counted
    sent = time.monotonic()
    limit_n_m = 177 * 0.00706155181422604
    bridge.wait_for(lambda: any(abs(e[0]) >= limit_n_m * (1 - 1e-6) for e in efforts(bridge, sent)))
    assert max(abs(e[0]) for e in efforts(bridge, sent)) == pytest.approx(limit_n_m, rel=1e-6)
    assert int(bridge.latest_diagnostic()[1]["saturation_count"]) > saturated
    bridge.hold(RECOVER_HOLD_S)


def test_parameters_are_validated(bridge):
    from rclpy.parameter import Parameter
    parameters = ParameterCalls(bridge.node, bridge.executor, "bridge_node", POLICY)
    for name, value in [("sample_period_s", 5.0), ("watchdog_periods", 0), ("backend", "ethercat"),
                        ("flow", "potential"), ("diagnostics_rate_hz", 5.0),
                        ("autostart", True)]:   # the last two: read-only
        result = parameters.set([Parameter(name, value=value)])[0]
        assert not result.successful and name in result.reason
    described = {d.name: d for d in parameters.describe(["sample_period_s", "autostart"])}
    assert described["autostart"].read_only and described["sample_period_s"].floating_point_range


def test_a_device_lost_while_active_takes_deactivate_into_error_processing(ros_domain, rclpy_context, tmp_path):
    """The board is unplugged while the bridge is active (serial backend on a pty behind a stable name, the emulated
    firmware in this process). The I/O loop latches the fault and writes zero. Deactivate cannot zero or disable a
    lost device, so it returns ERROR and rclpy runs error processing: the bridge's on_error releases the device and,
    returning SUCCESS, leaves the node unconfigured (rclpy's rule; FAILURE would finalize it). /diagnostics'
    lifecycle_state "unconfigured" is on_error's own doing: rclpy's default on_error would leave "active" there.
    Plugged in again, configure reconnects with zero current and the amplifiers disabled, and the bridge runs again.
    """
    import yaml
    from lifecycle_msgs.msg import Transition

    from swim_hw_bridge.conversions import default_config_path
    from swim_hw_bridge.testing.fake_serial_firmware import PtyRig
    rig = PtyRig(tmp_path / "ttyRIG", command_timeout_ms=FIRMWARE_TIMEOUT_MS, toggle_timeout_ms=FIRMWARE_TIMEOUT_MS)
    config = yaml.safe_load(default_config_path().read_text())
    config["backend_options"]["serial"].update(port=str(rig.link), read_timeout_s=SERIAL_READ_TIMEOUT_S,
                                               open_timeout_s=SERIAL_OPEN_TIMEOUT_S)
    config_path = tmp_path / "bridge.yaml"
    config_path.write_text(yaml.safe_dump(config))
    # a 25 ms loop with room for a 20 ms read; overruns are not what this test is about. The board is a thread of
    # this ordinary test process: a bridge at a real-time priority would outrun its own device here (a real board
    # answers in hardware), so the bridge runs without the real-time means
    with running_node("swim_hw_bridge", "bridge_node", tmp_path / "log.txt", "-r", "__ns:=/error_test",
                      "-p", "realtime_policy:=other", "-p", "lock_memory:=false",
                      "-p", "backend:=serial", "-p", f"config_path:={config_path}", "-p", "sample_period_s:=0.025",
                      "-p", "overrun_limit:=1000", "-p", "watchdog_periods:=80", "-p", "diagnostics_rate_hz:=20.0"):
        client = BridgeClient(rclpy_context, "/error_test", tmp_path / "log.txt")
        try:
            assert client.transition(Transition.TRANSITION_CONFIGURE)
            firmware = rig.firmware
            assert not firmware.enable_requested and firmware.commanded_currents_ua == (0, 0)
            assert client.transition(Transition.TRANSITION_ACTIVATE)
            assert client.wait_for(lambda: firmware.outputs_enabled and client.states)
            client.send([0.05, 0.0])
            sent = time.monotonic()
            assert client.wait_for(lambda: (0.05, 0.0) in [pytest.approx(e) for e in efforts(client, sent)])
            # the state goes out right after the write; the firmware's thread applies it when it next runs
            assert client.wait_for(lambda: firmware.applied_currents_ua[0] > 0)
            assert firmware.applied_currents_ua[1] == 0

            firmware.disconnect()   # the cable is pulled
            lost = time.monotonic()
            assert client.wait_for(lambda: efforts(client, lost) and efforts(client, lost)[-1] == (0.0, 0.0))
            status, values = client.latest_diagnostic()
            assert status.level == status.ERROR and "DEVICE_FAILED" in values["faults"]

            assert not client.transition(Transition.TRANSITION_DEACTIVATE)   # ERROR: not a success
            assert client.state_label() == "unconfigured"
            _, values = client.latest_diagnostic()
            assert values["lifecycle_state"] == "unconfigured" and "loop_running" not in values   # device released
            client.spin(IN_FLIGHT_S)
            client.states.clear()
            client.spin(SILENCE_WINDOW_S)
            assert not client.states   # nothing published once unconfigured
            # the lost board switched its amplifiers off by itself: its enable line stopped toggling
            assert client.wait_for(lambda: not firmware.outputs_enabled)
            assert firmware.applied_currents_ua == (0, 0)

            firmware = rig.plug_in()   # the board is back under the same name: configure reconnects
            assert client.transition(Transition.TRANSITION_CONFIGURE)
            assert client.state_label() == "inactive"
            # zero current, not enabled (read by the firmware's thread when it next runs)
            assert client.wait_for(lambda: firmware.commands and firmware.commands[-1][1:] == (0, 0, 0))
            assert not firmware.outputs_enabled
            assert client.transition(Transition.TRANSITION_ACTIVATE)
            assert client.wait_for(lambda: firmware.outputs_enabled)
            assert client.transition(Transition.TRANSITION_DEACTIVATE)   # a device that answers: a plain deactivate
            assert client.state_label() == "inactive"
            # the board's firmware (a thread of this process) reads the bridge's last frames when it next runs
            assert client.wait_for(lambda: not firmware.enable_requested and firmware.commanded_currents_ua == (0, 0))
        finally:
            client.close()
            rig.close()


#: a process of IDLE_JOINERS participants (an rclpy context each) that idle, then subscribe to joint_states one after
#: another; it prints how many of them received a state
IDLE_JOINERS_SCRIPT = textwrap.dedent("""
    import sys, time
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from sensor_msgs.msg import JointState
    count, idle_s, spacing_s = int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3])
    joiners = []
    for i in range(count):
        context = rclpy.Context()
        rclpy.init(context=context)
        node = rclpy.create_node(f"idle_joiner_{i}", context=context)
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        joiners.append((context, node, executor, []))
    time.sleep(idle_s)
    for index, (_, node, _, received) in enumerate(joiners):
        node.create_subscription(JointState, "joint_states", received.append, 10)
        end = time.monotonic() + spacing_s
        while time.monotonic() < end:
            for _, _, executor, _ in joiners[:index + 1]:
                executor.spin_once(timeout_sec=0.0)
            time.sleep(0.005)
    end = time.monotonic() + 5.0
    while time.monotonic() < end and not all(received for *_, received in joiners):
        for _, _, executor, _ in joiners:
            executor.spin_once(timeout_sec=0.0)
        time.sleep(0.005)
    print(sum(bool(received) for *_, received in joiners), flush=True)
    for context, node, executor, _ in joiners:
        executor.shutdown()
        node.destroy_node()
        rclpy.shutdown(context=context)
""")


def test_the_bridge_keeps_off_shared_memory(bridge_process, bridge):
    """The bridge's participant talks UDP only (swim_ros.transport): it maps none of Fast DDS's shared memory, which
    the test's own participant, on Fast DDS's default transports and matched with it, does."""
    process, log = bridge_process
    assert fast_dds_shared_memory(os.getpid())
    assert not fast_dds_shared_memory(process.pid)
    assert "UDP only" in log.read_text()


def test_readers_joining_a_running_bridge_never_hold_its_publish(bridge, tmp_path):
    """Readers that join the running bridge from idle processes: every one gets states, and no state's publish
    waits on them (the bridge's state_publish maximum, over its whole run)."""
    output, errors = tmp_path / "joiners.out", tmp_path / "joiners.err"
    with open(output, "w") as out, open(errors, "w") as err:
        joiners = start_child([sys.executable, "-c", IDLE_JOINERS_SCRIPT, str(IDLE_JOINERS), str(JOINERS_IDLE_S),
                               str(JOINERS_SPACING_S)], stdout=out, stderr=err)
    deadline = time.monotonic() + JOINERS_TIMEOUT_S
    try:
        while joiners.poll() is None and time.monotonic() < deadline:
            bridge.hold(HOLD_S)
    finally:
        if joiners.poll() is None:
            joiners.kill()
        joiners.wait()
    assert joiners.returncode == 0, errors.read_text()[-3000:]
    assert int(output.read_text().strip()) == IDLE_JOINERS
    bridge.hold(HOLD_S)
    _, values = bridge.latest_diagnostic()
    assert float(values["state_publish_max_ms"]) < HELD_PUBLISH_MS, (
        f"a state's publish took {values['state_publish_max_ms']} ms")
