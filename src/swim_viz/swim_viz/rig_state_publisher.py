"""rig_state_publisher: the rig's URDF and its frames from joint_states.

It does what robot_state_publisher does for a robot whose joints are its URDF's (ours are not: the pitch joint
turns by theta - phi, swim_viz.frames).

Topics:
    joint_states (sub, sensor_msgs/JointState, best effort)  alpha, [R,] phi, theta
    robot_description (pub, std_msgs/String, latched)   the URDF from the rig file (swim_viz.urdf)
    /tf_static (pub, tf2_msgs/TFMessage, latched)       the fixed joints (pitch axis -> foil)
    /tf (pub, tf2_msgs/TFMessage)                       the moving joints at the latest joint_states, stamped with
                                                        its stamp, at most publish_rate_hz a second
Parameters (read at start): rig_path, lane_radius_m (swim_viz.rig_inputs), publish_rate_hz (30), mesh_dir (where
the foil's mesh is written; empty: $ROS_HOME/swim_viz, ~/.ros/swim_viz by default).
"""
from __future__ import annotations

import dataclasses
import os
from pathlib import Path
from typing import Any, Sequence

from geometry_msgs.msg import TransformStamped
from rclpy.node import Node
from rclpy.qos import QoSProfile
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage

from swim_model import SwimModelError
from swim_ros.entry import run_node
from swim_ros.parameters import NodeSettings, ParameterSpec
from swim_ros.qos import LATCHED_QOS
from swim_viz.frames import FrameTransform, fixed_transforms, moving_transforms
from swim_viz.rig_inputs import PARAMETERS, LatestJointState, RigInputSettings, load_rig_and_lane, rate_parameter
from swim_viz.urdf import rig_urdf, write_foil_mesh

#: tf2's own QoS for /tf (tf2_ros TransformBroadcaster): reliable, volatile, the last 100
TF_QOS = QoSProfile(depth=100)
#: a display of the rig needs no more than a screen's refresh: 30 frames a second
DEFAULT_RATE_HZ = 30.0

NODE_PARAMETERS = PARAMETERS + (
    rate_parameter(DEFAULT_RATE_HZ),
    ParameterSpec("mesh_dir", "", "folder the foil's STL mesh is written to (empty: $ROS_HOME/swim_viz)",
                  read_only=True),
)


@dataclasses.dataclass(frozen=True)
class RigStateSettings(RigInputSettings):
    """NODE_PARAMETERS' values (swim_ros.parameters.NodeSettings)."""

    mesh_dir: str


def mesh_directory(configured: str) -> Path:
    """The mesh folder: the parameter's, else $ROS_HOME/swim_viz, else ~/.ros/swim_viz (ROS' log and data home)."""
    if configured:
        return Path(configured).expanduser()
    return Path(os.environ.get("ROS_HOME") or Path.home() / ".ros") / "swim_viz"


def transform_messages(transforms: Sequence[FrameTransform], stamp: Any) -> list[TransformStamped]:
    """geometry_msgs/TransformStamped of each transform, stamped with stamp (builtin_interfaces/Time)."""
    messages = []
    for transform in transforms:
        message = TransformStamped()
        message.header.stamp = stamp
        message.header.frame_id = transform.parent
        message.child_frame_id = transform.child
        t = message.transform.translation
        t.x, t.y, t.z = transform.translation_m
        r = message.transform.rotation
        r.x, r.y, r.z, r.w = transform.quaternion_xyzw()
        messages.append(message)
    return messages


class RigStatePublisher(Node):
    """The URDF and transforms publisher's node (module docstring)."""

    def __init__(self) -> None:
        super().__init__("rig_state_publisher")
        self.settings = NodeSettings(self, NODE_PARAMETERS, RigStateSettings).current   # all read-only
        self.rig, lane_radius_m = load_rig_and_lane(self.settings)
        mesh_path = write_foil_mesh(self.rig, mesh_directory(self.settings.mesh_dir))
        self.description = rig_urdf(self.rig, mesh_path.resolve().as_uri())
        self.create_publisher(String, "robot_description", LATCHED_QOS).publish(String(data=self.description))
        static = TFMessage(transforms=transform_messages(fixed_transforms(self.rig), self.get_clock().now().to_msg()))
        self.create_publisher(TFMessage, "/tf_static", LATCHED_QOS).publish(static)
        self.tf_publisher = self.create_publisher(TFMessage, "/tf", TF_QOS)
        self.joint_states = LatestJointState(self, lane_radius_m)
        self.published = 0
        self.create_timer(1.0 / self.settings.publish_rate_hz, self._publish)
        self.get_logger().info(f"rig from {self.rig.source_path}, foil mesh {mesh_path}")

    def _publish(self) -> None:
        taken = self.joint_states.take()
        if taken is None:
            return
        message, positions = taken
        self.tf_publisher.publish(TFMessage(transforms=transform_messages(moving_transforms(self.rig, positions),
                                                                          message.header.stamp)))
        self.published += 1


def main(args: list[str] | None = None) -> None:
    """Run rig_state_publisher until shut down; args are ROS's command-line arguments."""
    run_node(RigStatePublisher, args, name="rig_state_publisher", fatal_errors=(ValueError, SwimModelError, OSError))
