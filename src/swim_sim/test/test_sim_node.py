"""sim_node over DDS: lock-step determinism, /clock, set_state and its bounds, reset, malformed commands, blow-up
stop, the hold until the first torque, parameters (read-only seed, checked and applied values)."""
import time

import numpy as np
import pytest

from swim_ros.calls import RetryPolicy, spin_until
from swim_ros.testing.fixtures import MESSAGE_TIMEOUT_S, STARTUP_TIMEOUT_S, running_node

#: sim_node answers reset and set_state at once; a try waits 10 s for a loaded host
POLICY = RetryPolicy(attempt_timeout_s=10.0, attempts=3, discovery_timeout_s=STARTUP_TIMEOUT_S)
#: a state that must not come (no step taken): a step publishes its state within a period or two of the command;
#: 0.5 s is over 60 periods
NO_STEP_WINDOW_S = 0.5
#: sim_node's resend of an unanswered state: far longer than NO_STEP_WINDOW_S, so a resend is never taken for a step
RESEND_AFTER_S = 5.0

SEED = 11


def running_sim(log_path, *ros_args):
    """sim_node as these tests run it (swim_ros.testing.fixtures.running_node): lock-step on the constrained
    vehicle, an unanswered state resent after RESEND_AFTER_S; ros_args add more (``-p name:=value``, ``-r``)."""
    return running_node("swim_sim", "sim_node", log_path, "-p", "constrained:=true",
                        "-p", f"resend_after_s:={RESEND_AFTER_S}", *ros_args)


@pytest.fixture(scope="module")
def sim(ros_domain, tmp_path_factory):
    with running_sim(tmp_path_factory.mktemp("sim_node") / "log.txt", "-p", f"seed:={SEED}") as process:
        yield process


class Driver:
    """The test's side of the lock-step: answers each state with a command stamped like it. A context manager:
    its node is destroyed on leaving."""

    def __init__(self, context, namespace=""):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import JointState
        self.node = rclpy.create_node("sim_test_driver", namespace=namespace, context=context)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.states, self.clock = [], []
        self.publisher = self.node.create_publisher(JointState, "joint_commands", 10)
        self.node.create_subscription(JointState, "joint_states", self.states.append, 10)
        self.node.create_subscription(Clock, "/clock", lambda m: self.clock.append(m.clock), 10)

    def command(self, stamp, effort, names=("phi", "theta")):
        from sensor_msgs.msg import JointState
        message = JointState(name=list(names), effort=list(effort))
        message.header.stamp = stamp
        self.publisher.publish(message)

    def wait_for_states(self, count, timeout_s=MESSAGE_TIMEOUT_S):
        return spin_until(self.executor, lambda: len(self.states) >= count, timeout_s)

    def drive(self, torques):
        """One command per state, for the last state received; returns the states that followed."""
        start = len(self.states)
        for k, torque in enumerate(torques):
            assert self.wait_for_states(start + k + 1), f"no state after {k} commands"
            self.command(self.states[-1].header.stamp, torque)
        assert self.wait_for_states(start + len(torques) + 1)
        return self.states[start + 1:]

    def call(self, service_type, name, request):
        """reset and set_state are harmless to repeat: a lost answer is asked again (swim_ros.calls)."""
        from swim_ros.calls import call_service
        return call_service(self.executor, self.node.create_client(service_type, name), request, POLICY)

    def reset_and_wait(self):
        """Reset the simulator and wait for a state: the node publishes its state at start and on resend only,
        so a new driver asks for a fresh one by resetting."""
        from std_srvs.srv import Trigger
        assert self.call(Trigger, "reset", Trigger.Request()).success
        assert self.wait_for_states(1)

    def __enter__(self):
        return self

    def __exit__(self, *exc_info):
        self.executor.shutdown()
        self.node.destroy_node()


@pytest.fixture()
def driver(sim, rclpy_context):
    with Driver(rclpy_context) as driver:
        driver.reset_and_wait()
        yield driver


def positions(states):
    return np.array([s.position for s in states])


def test_lock_step_is_deterministic_after_reset_and_clock_follows(driver):
    from std_srvs.srv import Trigger
    torques = 0.3 * np.sin(np.arange(150)[:, None] * np.array([0.05, 0.08]))
    first = driver.drive(torques)
    stamps = [s.header.stamp.sec + 1e-9 * s.header.stamp.nanosec for s in first]
    np.testing.assert_allclose(np.diff(stamps), 0.008, atol=1e-9)    # one period per command, simulated time
    spin_until(driver.executor, lambda: bool(driver.clock) and driver.clock[-1] == first[-1].header.stamp,
               MESSAGE_TIMEOUT_S)
    assert driver.clock[-1] == first[-1].header.stamp
    assert driver.call(Trigger, "reset", Trigger.Request()).success
    assert driver.wait_for_states(len(driver.states) + 1)
    second = driver.drive(torques)
    assert np.array_equal(positions(first), positions(second))       # bit for bit: same seed, same commands
    assert np.array_equal([s.effort for s in first], [s.effort for s in second])
    assert np.abs(positions(first)[-1] - positions(first)[0]).max() > 0.01   # and the vehicle did move


def test_malformed_commands_do_not_step_and_a_valid_one_does(driver):
    stamp = driver.states[-1].header.stamp
    count = len(driver.states)
    for names, effort in [(("phi", "R"), (0.1, 0.1)), (("phi", "theta"), (float("nan"), 0.0)),
                          (("phi", "theta"), (0.1,))]:
        driver.command(stamp, effort, names)
    assert not driver.wait_for_states(count + 1, timeout_s=NO_STEP_WINDOW_S)
    driver.command(stamp, (0.1, 0.0))
    assert driver.wait_for_states(count + 1)
    assert list(driver.states[-1].effort) == [0.0, 0.1, 0.0]


def test_set_state_puts_the_vehicle_there(driver):
    from sensor_msgs.msg import JointState
    from swim_interfaces.srv import SetVehicleState
    target = {"theta": -0.2, "alpha": 0.5, "phi": 0.1}
    request = SetVehicleState.Request(state=JointState(name=list(target), position=list(target.values())))
    count = len(driver.states)
    assert driver.call(SetVehicleState, "set_state", request).success
    assert driver.wait_for_states(count + 1)
    measured = dict(zip(driver.states[-1].name, driver.states[-1].position))
    for joint, value in target.items():   # within a few encoder counts (quantization and noise)
        assert abs(measured[joint] - value) < 1e-3
    bad = SetVehicleState.Request(state=JointState(name=["alpha", "R", "phi"], position=[0.0, 0.4, 0.0]))
    reply = driver.call(SetVehicleState, "set_state", bad)
    assert not reply.success and "alpha" in reply.message


@pytest.mark.parametrize("position, velocity, said", [
    ((0.0, 0.0, 1.5), (), "theta = 1.5 is outside .* hard stops .*pitch_hard_stop"),   # past 80 degrees
    ((0.0, -1.1, 0.0), (), "phi = -1.1 is outside .* hard stops .*heave_hard_stop"),   # past -60 degrees
    ((2.0e6, 0.0, 0.0), (), "alpha = 2e\\+06 is outside .*MAX_ABS_START_ALPHA_RAD"),
    ((0.0, 0.0, float("nan")), (), "non-finite position"),
    ((0.0, 0.0, 0.0), (0.0, 0.0, 50.0), "theta velocity 50 is faster than 45, .*pitch_max_speed"),
    ((0.0, 0.0, 0.0), (float("inf"), 0.0, 0.0), "non-finite velocity"),
])
def test_set_state_out_of_bounds_is_refused_with_its_bound_and_changes_nothing(driver, position, velocity, said):
    import re

    from sensor_msgs.msg import JointState
    from swim_interfaces.srv import SetVehicleState
    count = len(driver.states)
    request = SetVehicleState.Request(state=JointState(name=["alpha", "phi", "theta"], position=list(position),
                                                       velocity=list(velocity)))
    reply = driver.call(SetVehicleState, "set_state", request)
    assert not reply.success and re.search(said, reply.message), reply.message
    assert not driver.wait_for_states(count + 1, timeout_s=NO_STEP_WINDOW_S)   # not restarted: nothing published
    before = driver.states[-1]
    after = driver.drive([(0.0, 0.0)])[0]   # and it steps on from where it was
    assert np.abs(np.array(after.position) - before.position).max() < 0.01


def test_seed_is_read_only_and_changeable_parameters_are_checked_and_applied(driver):
    from rclpy.parameter import Parameter

    from swim_ros.calls import ParameterCalls
    parameters = ParameterCalls(driver.node, driver.executor, "sim_node", POLICY)
    reply = parameters.set([Parameter("seed", value=12)])[0]
    assert not reply.successful and "read-only" in reply.reason
    assert parameters.get(["seed"]) == [SEED]
    descriptor = parameters.describe(["seed"])[0]
    assert descriptor.read_only and descriptor.description
    for name, value in [("sensors.position_noise_counts", float("nan")), ("sensors.quadrature_factor", 0.0),
                        ("velocity_source", "guessed"), ("resend_after_s", -1.0)]:
        reply = parameters.set([Parameter(name, value=value)])[0]
        assert not reply.successful and name.split(".")[-1] in reply.reason, reply.reason
    assert driver.states[-1].velocity   # velocities published ...
    assert parameters.set([Parameter("velocity_source", value="none")])[0].successful
    assert not driver.drive([(0.0, 0.0)])[0].velocity   # ... until velocity_source none takes effect
    assert parameters.set([Parameter("velocity_source", value="model")])[0].successful
    assert driver.drive([(0.0, 0.0)])[0].velocity


@pytest.fixture(scope="module")
def stiff_sim(ros_domain, tmp_path_factory):
    """A simulator set up to blow up (in a namespace of its own): a 50 ms period in one RK4 step under a drag 2000
    times the default makes the explicit integration unstable for a pitch rate of 40 rad/s (measured: the
    first period blows up)."""
    log = tmp_path_factory.mktemp("stiff_sim_node") / "log.txt"
    with running_sim(log, "-p", "sample_period_s:=0.05", "-p", "substeps:=1",
                     "-p", "disturbances.foil_normal_drag_coefficient:=100.0", "-r", "__ns:=/stiff") as process:
        yield process


def test_blow_up_stops_publishing_until_reset(stiff_sim, rclpy_context):
    from sensor_msgs.msg import JointState
    from std_srvs.srv import Trigger
    from swim_interfaces.srv import SetVehicleState
    with Driver(rclpy_context, namespace="/stiff") as driver:
        fast = JointState(name=["alpha", "phi", "theta"], position=[0.0, 0.0, 0.0], velocity=[0.0, 0.0, 40.0])
        assert driver.call(SetVehicleState, "set_state", SetVehicleState.Request(state=fast)).success
        assert driver.wait_for_states(1)
        count = len(driver.states)
        driver.command(driver.states[-1].header.stamp, (0.0, 0.0))
        assert not driver.wait_for_states(count + 1, timeout_s=NO_STEP_WINDOW_S)   # stopped: nothing published
        assert all(np.all(np.isfinite(s.position)) for s in driver.states)
        assert driver.call(Trigger, "reset", Trigger.Request()).success
        assert driver.wait_for_states(count + 1)


@pytest.fixture(scope="module")
def held_sim(ros_domain, tmp_path_factory):
    """A second simulator with hold_until_torque, in a namespace of its own (beside the module's other one)."""
    log = tmp_path_factory.mktemp("held_sim_node") / "log.txt"
    with running_sim(log, "-p", f"seed:={SEED}", "-p", "hold_until_torque:=true", "-r", "__ns:=/held") as process:
        yield process


def test_hold_until_torque_keeps_the_state_until_a_nonzero_command(held_sim, rclpy_context):
    from std_srvs.srv import Trigger
    with Driver(rclpy_context, namespace="/held") as driver:
        driver.reset_and_wait()
        held = driver.states[-1]
        started = time.monotonic()
        held_states = driver.drive(np.zeros((10, 2)))   # zero commands: the same state, published again
        elapsed_s = time.monotonic() - started
        for state in held_states:
            assert state.header.stamp == held.header.stamp and list(state.position) == list(held.position)
        # at most one republication per timer period (8 ms): not an idle loop as fast as the CPU
        assert elapsed_s >= 8 * 0.008 * 0.75
        moved = driver.drive([(0.3, 0.0)] + [(0.0, 0.0)] * 5)   # the first torque starts it; then zeros step too
        stamps = [s.header.stamp.sec + 1e-9 * s.header.stamp.nanosec for s in [held] + moved]
        np.testing.assert_allclose(np.diff(stamps), 0.008, atol=1e-9)
        assert list(moved[0].effort) == [0.0, 0.3, 0.0]
        assert driver.call(Trigger, "reset", Trigger.Request()).success   # a reset holds it again
        assert driver.wait_for_states(len(driver.states) + 1)
        reset_state = driver.states[-1]
        again = driver.drive(np.zeros((3, 2)))
        assert all(s.header.stamp == reset_state.header.stamp for s in again)
