"""The recorder's stamp reader against rclpy's own serialization of the loop's message types."""
import pytest


@pytest.mark.parametrize("sec, nanosec", [(0, 0), (63, 184_000_000), (1_795_444_603, 86_991_424), (-5, 999_999_999)])
def test_header_stamp_read_from_cdr_equals_the_messages_stamp(sec, nanosec):
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import JointState
    from swim_bringup.run_client import LOOP_TOPICS, header_stamp_ns
    from swim_interfaces.msg import TrackingState
    assert set(LOOP_TOPICS) == {"joint_states", "joint_commands", "tracking_state"}   # the types below
    for message in (JointState(name=["phi", "theta"], effort=[0.1, -0.2]),
                    TrackingState(joint_names=["alpha", "phi", "theta"], plan_time_s=4.5, output_torques=[1.0, 2.0])):
        message.header.stamp.sec, message.header.stamp.nanosec = sec, nanosec
        message.header.frame_id = "a frame id of some length"   # after the stamp: must not matter
        assert header_stamp_ns(serialize_message(message)) == sec * 1_000_000_000 + nanosec
