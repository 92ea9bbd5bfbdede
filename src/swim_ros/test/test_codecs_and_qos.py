"""Codecs against rclpy's own serialization; the per-period factories' QoS and event handlers."""
import math

import numpy as np
import pytest

from swim_ros.codecs import MessageError, float_array, joint_state_arrays, seconds_of, stamp_of, torque_from_command


def test_float_array_fills_a_message_field_with_the_same_values():
    from rclpy.serialization import deserialize_message, serialize_message
    from sensor_msgs.msg import JointState
    values = np.array([[0.1, -2.5e-300, 1e300], [np.pi, -0.0, 7.0]])
    message = JointState(position=float_array(values))
    decoded = deserialize_message(serialize_message(message), JointState)
    np.testing.assert_array_equal(np.asarray(decoded.position), values.ravel())
    assert np.signbit(np.asarray(decoded.position)[4])          # -0.0 kept bit for bit
    assert list(float_array(np.arange(3, dtype=np.int64))) == [0.0, 1.0, 2.0]


@pytest.mark.parametrize("time_s", [0.0, 1.0, 1.008, 123456.789012345, 2.0 ** 31 - 1.5])
def test_stamps_round_trip_to_the_nanosecond(time_s):
    stamp = stamp_of(time_s)
    assert 0 <= stamp.nanosec < 1_000_000_000
    assert stamp.sec * 1_000_000_000 + stamp.nanosec == int(round(time_s * 1e9))
    assert seconds_of(stamp) == pytest.approx(time_s, abs=1e-9)


def test_per_period_factories_have_no_event_handlers_and_recordable_qos(rclpy_context):
    import rclpy
    from sensor_msgs.msg import JointState

    from swim_ros.qos import RECORDABLE_QOS, per_period_publisher, per_period_subscription
    node = rclpy.create_node("swim_ros_qos_test", context=rclpy_context)
    try:
        publisher = per_period_publisher(node, JointState, "joint_states")
        subscription = per_period_subscription(node, JointState, "joint_commands", lambda message: None)
        default = node.create_publisher(JointState, "other", 10)
        assert publisher.qos_profile == RECORDABLE_QOS and publisher.qos_profile.depth == 1000
        assert publisher.event_handlers == [] and subscription.event_handlers == []
        assert len(default.event_handlers) > 0        # what the factories leave out
    finally:
        node.destroy_node()


@pytest.mark.parametrize("names, efforts", [
    (["phi"], [0.1]),
    (["phi", "theta", "alpha"], [0.1, 0.1, 0.1]),
    (["phi", "phi"], [0.1, 0.1]),
    (["heave", "theta"], [0.1, 0.1]),
    (["phi", "theta"], [0.1]),
    (["phi", "theta"], [0.1, 0.2, 0.3]),
    (["phi", "theta"], [math.nan, 0.1]),
    (["phi", "theta"], [0.1, -math.inf]),
])
def test_malformed_commands_are_refused(names, efforts):
    with pytest.raises(MessageError):
        torque_from_command(names, efforts)


def test_names_in_any_order():
    assert torque_from_command(["theta", "phi"], [0.2, 0.1]) == (0.1, 0.2)


@pytest.mark.parametrize("names, positions, velocities, message", [
    (["alpha", "phi"], [0.0, 0.0], [], "joint names"),
    (["alpha", "phi", "phi"], [0.0, 0.0, 0.0], [], "joint names"),
    (["theta", "alpha", "phi"], [0.0, 0.0], [], "2 positions for 3 joints"),
    (["theta", "alpha", "phi"], [0.0, 0.0, 0.0], [1.0], "1 velocities for 3 joints"),
    (["theta", "alpha", "phi"], [0.0, math.nan, 0.0], [], "non-finite position"),
    (["theta", "alpha", "phi"], [0.0, 0.0, 0.0], [0.0, math.inf, 0.0], "non-finite velocity"),
])
def test_bad_joint_states_are_refused(names, positions, velocities, message):
    with pytest.raises(MessageError, match=message):
        joint_state_arrays(names, positions, velocities, ("alpha", "phi", "theta"))


def test_joint_states_in_any_order_come_back_in_the_models():
    q, qdot = joint_state_arrays(["theta", "alpha", "R", "phi"], [4.0, 1.0, 2.0, 3.0], [40.0, 10.0, 20.0, 30.0],
                                 ("alpha", "R", "phi", "theta"))
    np.testing.assert_array_equal(q, [1.0, 2.0, 3.0, 4.0])
    np.testing.assert_array_equal(qdot, [10.0, 20.0, 30.0, 40.0])
    assert joint_state_arrays(["phi", "alpha", "theta"], [2.0, 1.0, 3.0], [], ("alpha", "phi", "theta"))[1] is None
