"""Fixtures: the rig, its vehicle models and smooth strokes to linearize about (swim_control.testing.strokes), and
the DDS fixtures every package's tests share (swim_ros.testing.fixtures)."""
from swim_control.testing.strokes import make_trajectory, model_for, rig, strokes  # noqa: F401
from swim_ros.testing.fixtures import rclpy_context, ros_domain  # noqa: F401
