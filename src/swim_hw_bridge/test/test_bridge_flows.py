"""bridge_node's flow parameter over DDS: the emulated rig in the circulatory flow and in the vortex wake, started
with autostart, publishes joint_states with finite values while the test side sends torques (an unknown flow is
refused when set: test_bridge_node.py's parameter test)."""
import math

import pytest

from swim_ros.calls import spin_until
from swim_ros.testing.fixtures import MESSAGE_TIMEOUT_S, running_node

#: states watched: 50 periods of the 8 ms loop (0.4 s; the rate is test_bridge_node.py's)
WATCHED_STATES = 50
#: heave and pitch torques sent, N m: a fifth of the motors' limits, the foil swings without reaching its stops
TORQUES_N_M = (0.2, -0.08)


@pytest.mark.parametrize("flow", ["circulatory", "wake"])
def test_emulated_rig_swims_in_the_flow_and_publishes_finite_states(flow, ros_domain, rclpy_context, tmp_path):
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from sensor_msgs.msg import JointState
    log = tmp_path / "log.txt"
    with running_node("swim_hw_bridge", "bridge_node", log, "-r", f"__ns:=/{flow}_test", "-p", "autostart:=true",
                      "-p", f"flow:={flow}"):
        node = rclpy.create_node("bridge_flow_test", namespace=f"/{flow}_test", context=rclpy_context)
        executor = SingleThreadedExecutor(context=rclpy_context)
        executor.add_node(node)
        states = []
        commands = node.create_publisher(JointState, "joint_commands", 10)
        node.create_subscription(JointState, "joint_states",
                                 lambda m: (states.append(m), commands.publish(
                                     JointState(name=["phi", "theta"], effort=list(TORQUES_N_M)))), 10)
        assert spin_until(executor, lambda: bool(states), MESSAGE_TIMEOUT_S + 60.0), "no joint_states"
        first = len(states)
        watched_all = spin_until(executor, lambda: len(states) >= first + WATCHED_STATES, MESSAGE_TIMEOUT_S)
        executor.shutdown()
        node.destroy_node()
    watched = states[first:]
    assert watched_all, f"{len(watched)} states in {MESSAGE_TIMEOUT_S:g} s"
    assert all(math.isfinite(v) for s in watched for v in (*s.position, *s.velocity, *s.effort))
    assert any(abs(s.effort[2]) > 0.0 for s in watched)   # the torques reached the motors
    assert f"(flow {flow})" in log.read_text()

