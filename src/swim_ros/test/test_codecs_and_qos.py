"""Codecs against rclpy's own serialization; the per-period factories' QoS and event handlers."""
import numpy as np
import pytest

from swim_ros.codecs import float_array, seconds_of, stamp_of


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
