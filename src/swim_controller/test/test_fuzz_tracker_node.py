"""tracker_node's joint_states input fuzzed over DDS (swim_ros.testing.fuzz).

One idle node for the module (no goal). A well-formed state is answered by a command stamped like it, within its
deadline; a malformed one never is (the well-formed state sent after it is answered, and no command carries the
malformed one's stamp); every command is finite and within the motor limits; the node stays alive.
The execute_plan goals (plans) are not fuzzed here.
"""
import math
import time

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from swim_ros.testing.fixtures import STARTUP_TIMEOUT_S, running_node
from swim_ros.testing.fuzz import EDGE_FLOATS, any_float, fuzz_settings, joint_states, to_joint_state

JOINTS = ("alpha", "phi", "theta")
#: a state's command: within a period here; 5 s for a loaded 2-core host (and for discovery on the first one)
DEADLINE_S = 5.0


@pytest.fixture(scope="module")
def tracker(ros_domain, tmp_path_factory):
    # a stale limit far past the test's pace: its zero commands would otherwise come between the test's states
    with running_node("swim_controller", "tracker_node", tmp_path_factory.mktemp("fuzz_tracker") / "log.txt",
                      "-p", "stale_after_periods:=1000") as process:
        yield process


class StateSource:
    """The test's side: publishes joint_states with stamps of its own, collects joint_commands."""

    def __init__(self, context):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from sensor_msgs.msg import JointState
        self.node = rclpy.create_node("tracker_fuzz_source", context=context)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.publisher = self.node.create_publisher(JointState, "joint_states", 10)
        self.commands = []
        self.node.create_subscription(JointState, "joint_commands", self.commands.append, 50)
        self.next_second = 100

    def stamp(self):
        from builtin_interfaces.msg import Time
        self.next_second += 1   # never zero: a zero stamp means "not stamped"
        return Time(sec=self.next_second)

    def answered(self, stamp):
        from swim_ros.calls import spin_until
        return spin_until(self.executor, lambda: any(c.header.stamp == stamp for c in self.commands), DEADLINE_S)


def valid_state(stamp):
    from sensor_msgs.msg import JointState
    message = JointState(name=list(JOINTS), position=[0.0, 0.1, -0.1], velocity=[0.0, 0.0, 0.0])
    message.header.stamp = stamp
    return message


@pytest.fixture(scope="module")
def source(tracker, ros_domain):
    import rclpy
    context = rclpy.Context()
    rclpy.init(context=context)
    source = StateSource(context)
    deadline = time.monotonic() + STARTUP_TIMEOUT_S
    while True:   # discovery: states sent before the node's reader matched are lost; send until one is answered
        stamp = source.stamp()
        source.publisher.publish(valid_state(stamp))
        if source.answered(stamp) or time.monotonic() > deadline:
            break
    assert any(c.header.stamp == stamp for c in source.commands), "tracker_node never answered a state"
    yield source
    source.executor.shutdown()
    source.node.destroy_node()
    rclpy.shutdown(context=context)


@pytest.fixture(scope="module")
def torque_limits():
    from swim_model import load_rig
    return np.array(load_rig().torque_limits_n_m)


def values():
    """Positions and velocities: ordinary, at float64's edges (finite: well formed, the node must cope), and any."""
    return st.one_of(st.floats(-3.0, 3.0), st.sampled_from(EDGE_FLOATS), any_float())


@fuzz_settings(80)
@given(state=joint_states(JOINTS, values()))
def test_fuzzed_states_are_answered_only_when_well_formed_with_finite_torque(tracker, source, torque_limits, state):
    stamp = source.stamp()
    source.commands.clear()
    source.publisher.publish(to_joint_state(state, stamp))
    if state.defect is None:
        start = time.monotonic()
        assert source.answered(stamp), state
        assert time.monotonic() - start < DEADLINE_S
    else:   # refused: the good state after it is answered, and nothing was for the bad one
        good = source.stamp()
        source.publisher.publish(valid_state(good))
        assert source.answered(good)
        assert not any(c.header.stamp == stamp for c in source.commands), state
    for command in source.commands:
        assert all(math.isfinite(v) for v in command.effort), command
        assert np.all(np.abs(command.effort) <= torque_limits), command
    assert tracker.poll() is None
