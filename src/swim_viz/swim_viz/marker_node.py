"""marker_node: the planned and the travelled path as visualization_msgs/MarkerArray, in the tank frame.

Topics, namespaces and parameters: see src/swim_viz/README.md, section "Nodes and parameters (read at start)".
"""
from __future__ import annotations

import dataclasses
from typing import Any

from geometry_msgs.msg import Point
from rclpy.node import Node
from swim_interfaces.msg import PlannedTrajectory
from visualization_msgs.msg import Marker, MarkerArray

from swim_model import SwimModelError
from swim_ros.entry import run_node
from swim_ros.parameters import NodeSettings, ParameterSpec
from swim_ros.qos import LATCHED_QOS
from swim_viz.markers import PathLine, TravelledPath, planned_paths
from swim_viz.rig_inputs import PARAMETERS, LatestJointState, RigInputSettings, load_rig_and_lane, rate_parameter

#: the paths change slowly on screen: ten redraws a second
DEFAULT_RATE_HZ = 10.0
#: 2 mm between kept points: finer than a drawn line's width, and a 30 s maneuver's travel (about 0.5 m for the
#: platform, a few metres of foil oscillation) stays within a few thousand points
DEFAULT_SPACING_M = 0.002
DEFAULT_MAX_POINTS = 20000

NODE_PARAMETERS = PARAMETERS + (
    rate_parameter(DEFAULT_RATE_HZ),
    ParameterSpec("travelled_spacing_m", DEFAULT_SPACING_M, "least motion between kept points of the travelled "
                  "path, m", range=(0.0, 1.0), read_only=True),
    ParameterSpec("travelled_max_points", DEFAULT_MAX_POINTS, "most points kept per travelled path",
                  range=(2, 1_000_000), read_only=True),
)


@dataclasses.dataclass(frozen=True)
class MarkerSettings(RigInputSettings):
    """NODE_PARAMETERS' values (swim_ros.parameters.NodeSettings)."""

    travelled_spacing_m: float
    travelled_max_points: int


def line_marker(line: PathLine, marker_id: int, stamp: Any) -> Marker:
    """A LINE_STRIP marker of the polyline."""
    marker = Marker(type=Marker.LINE_STRIP, action=Marker.ADD, ns=line.namespace, id=marker_id)
    marker.header.frame_id, marker.header.stamp = line.frame_id, stamp
    marker.pose.orientation.w = 1.0
    marker.scale.x = line.width_m
    marker.color.r, marker.color.g, marker.color.b, marker.color.a = line.rgba
    marker.points = [Point(x=float(x), y=float(y), z=float(z)) for x, y, z in line.points_m]
    return marker


class MarkerNode(Node):
    """The path markers' node (module docstring)."""

    def __init__(self) -> None:
        super().__init__("marker_node")
        self.settings = NodeSettings(self, NODE_PARAMETERS, MarkerSettings).current   # all read-only
        self.rig, self.lane_radius_m = load_rig_and_lane(self.settings)
        self.travelled = TravelledPath(self.rig, self.settings.travelled_spacing_m, self.settings.travelled_max_points)
        self.planned: list[PathLine] = []
        self.changed = False
        self.rejected_plans = 0
        self.publisher = self.create_publisher(MarkerArray, "markers", 10)
        self.create_subscription(PlannedTrajectory, "plan", self._on_plan, LATCHED_QOS)
        self.joint_states = LatestJointState(self, self.lane_radius_m, self._on_positions)
        self.create_timer(1.0 / self.settings.publish_rate_hz, self._publish)

    def _on_plan(self, plan: Any) -> None:
        lane_radius_m = plan.lane_radius_m if plan.constrained else self.lane_radius_m
        try:
            self.planned = planned_paths(self.rig, plan.joint_names, plan.positions, lane_radius_m)
        except ValueError as err:
            self.rejected_plans += 1
            self.get_logger().warning(f"plan not drawn ({self.rejected_plans} so far): {err}")
            return
        self.travelled.clear()
        self.changed = True

    def _on_positions(self, positions: Any) -> None:
        self.changed |= self.travelled.add(positions)

    def wake_markers(self) -> list[Marker]:
        """The wake's vortices: none until a message carries their positions and circulations (module docstring)."""
        return []

    def _publish(self) -> None:
        if not self.changed:
            return
        self.changed = False
        stamp = self.get_clock().now().to_msg()
        lines = self.planned + self.travelled.lines()
        markers = [line_marker(line, 0, stamp) for line in lines if len(line.points_m) >= 2]
        self.publisher.publish(MarkerArray(markers=markers + self.wake_markers()))


def main(args: list[str] | None = None) -> None:
    """Run marker_node until shut down; args are ROS's command-line arguments."""
    run_node(MarkerNode, args, name="marker_node", fatal_errors=(ValueError, SwimModelError))
