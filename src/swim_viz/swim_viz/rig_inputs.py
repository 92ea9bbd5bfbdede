"""What both swim_viz nodes read: the rig, the lane radius of the constrained vehicle, and joint_states.

Parameters shared by rig_state_publisher and marker_node (read once at start):
    rig_path          the rig YAML file (empty: swim_model's shipped rig)
    lane_radius_m     R when joint_states has no R (the constrained vehicle); 0: the rig's constrained lane radius
    publish_rate_hz   the most messages a second the node publishes: its work per joint_states is storing it
"""
from __future__ import annotations

import dataclasses
from typing import Any, Callable, Optional

from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import JointState

from swim_model.rig import RigParameters, load_rig
from swim_ros.parameters import ParameterSpec, positive
from swim_ros.qos import per_period_subscription
from swim_viz.frames import JointPositions, positions_from_names

PARAMETERS = (
    ParameterSpec("rig_path", "", "rig YAML file (empty: the shipped rig)", read_only=True),
    ParameterSpec("lane_radius_m", 0.0, "R of the constrained vehicle, whose joint_states has no R, m (0: the rig's "
                  "constrained_lane_radius)", range=(0.0, 10.0), read_only=True),
)


def rate_parameter(default_hz: float) -> ParameterSpec:
    """The read-only publish_rate_hz parameter (Hz), default_hz by default."""
    return ParameterSpec("publish_rate_hz", default_hz, "most messages published a second, Hz", range=(0.0, 1000.0),
                         read_only=True, check=positive)


@dataclasses.dataclass(frozen=True)
class RigInputSettings:
    """The values of PARAMETERS and rate_parameter's, for a node's settings type to derive from.

    The settings type is swim_ros.parameters.NodeSettings'.
    """

    rig_path: str
    lane_radius_m: float
    publish_rate_hz: float


def load_rig_and_lane(settings: RigInputSettings) -> tuple[RigParameters, float]:
    """The rig and the lane radius (m) of a node's settings.

    Raises swim_model.SwimModelError for a rig file that does not load.
    """
    rig = load_rig(settings.rig_path or None)
    return rig, float(settings.lane_radius_m) or rig.constrained_lane_radius_m


class LatestJointState:
    """A best-effort subscription to joint_states that keeps only the latest message.

    It is what a node that publishes at its own rate needs, at the cost of one stored reference per message (a
    control loop is never held up: best effort, so a slow reader is simply passed by).
    """

    def __init__(self, node: Node, lane_radius_m: float,
                 each: Optional[Callable[[JointPositions], None]] = None) -> None:
        """each, if given, is called with the positions of every well-formed message as it comes."""
        self.node, self.lane_radius_m, self.each = node, lane_radius_m, each
        self.latest: Optional[Any] = None   # sensor_msgs/JointState
        self.rejected = 0
        per_period_subscription(node, JointState, "joint_states", self._on_state, qos_profile_sensor_data)

    def _on_state(self, message: Any) -> None:
        self.latest = message
        if self.each is not None:
            positions = self._positions(message)
            if positions is not None:
                self.each(positions)

    def _positions(self, message: Any) -> Optional[JointPositions]:
        try:
            return positions_from_names(message.name, message.position, self.lane_radius_m)
        except ValueError as err:
            self.rejected += 1
            self.node.get_logger().warning(f"joint_states rejected ({self.rejected} so far): {err}",
                                           throttle_duration_sec=1.0)
            return None

    def take(self) -> Optional[tuple[Any, JointPositions]]:
        """The latest message and its positions, once.

        None when none came since the last take, or it was malformed: then counted and logged.
        """
        message, self.latest = self.latest, None
        positions = None if message is None else self._positions(message)
        return None if positions is None else (message, positions)
