"""Fixtures of swim_ros's tests: the DDS fixtures every package's tests share (swim_ros.testing.fixtures)."""
from swim_ros.testing.fixtures import rclpy_context, ros_domain  # noqa: F401
