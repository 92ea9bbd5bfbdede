"""Fixtures of swim_ros's tests: the DDS fixtures every package's tests share (swim_ros.testing.fixtures), and the
one-segment trajectories the PlannedTrajectory codec's tests encode (swim_control.testing.strokes)."""
from swim_control.testing.strokes import make_trajectory  # noqa: F401
from swim_ros.testing.fixtures import rclpy_context, ros_domain  # noqa: F401
