"""swim_bringup.bag's type store (built from the installed .msg files) decodes what rclpy serializes."""
import numpy as np


def test_rosbags_reads_wake_statistics():
    """The bag's type store (swim_bringup.bag, from the installed .msg files) decodes what rclpy serializes."""
    from rclpy.serialization import serialize_message
    from swim_interfaces.msg import WakeStatistics

    from swim_bringup.bag import RUN_TOPICS
    from swim_ros.typestore import swim_typestore
    sent = WakeStatistics(vortex_count=300, total_circulation_m2_s=1e-17, thrust_n=-0.25,
                          joint_names=["alpha", "phi", "theta"], generalized_force=[0.1, -0.2, 0.003], clipped_count=2)
    decoded = swim_typestore().deserialize_cdr(serialize_message(sent), RUN_TOPICS["/wake_statistics"])
    assert decoded.vortex_count == 300 and decoded.thrust_n == -0.25 and decoded.clipped_count == 2
    assert list(decoded.joint_names) == ["alpha", "phi", "theta"]
    np.testing.assert_array_equal(decoded.generalized_force, [0.1, -0.2, 0.003])
