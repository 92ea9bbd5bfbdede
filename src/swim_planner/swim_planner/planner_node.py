"""planner_node: serves maneuver requests from the primitive library.

Service ``request_maneuver`` (swim_interfaces/srv/RequestManeuver): an explicit primitive sequence with
repeat counts (MODE_SEQUENCE), or a goal state of the lane/energy graph with a distance to cover at least
(MODE_GOAL, answered by the quickest path), concatenated and time-scaled. A request that cannot be planned
gets success = false and a message saying why; nothing else changes. Topic ``plan`` (PlannedTrajectory,
transient local): the last plan made.

Parameters: ``library_path`` (default: the shipped library), ``rig_path`` (default: the shipped rig),
``default_time_scale`` (used when a request's time_scale is 0; default 1.0), ``lqr_weights_path`` (a YAML of
swim_controller LqrWeights fields; empty: the gains stored in the library). Setting ``lqr_weights_path`` at run
time retunes the plans made after it: each primitive's gains for the new weights are computed on its first use
(0.1-0.3 s each) and kept, while other requests are answered; a file that does not load is refused and changes
nothing.
"""
from __future__ import annotations

import rclpy
from rcl_interfaces.msg import SetParametersResult
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSDurabilityPolicy, QoSProfile
from swim_interfaces.msg import PlannedTrajectory, PrimitiveSegment
from swim_interfaces.srv import RequestManeuver

from swim_model import SwimModelError, load_rig
from swim_planner.errors import PlannerError
from swim_planner.gains import RetunedLibrary, load_lqr_weights
from swim_planner.graph import build_graph, plan_to_goal, rest_node
from swim_planner.library import PrimitiveLibrary
from swim_planner.maneuver import Plan, concatenate, expand_sequence
from swim_planner.paths import default_library_path


def plan_to_message(plan: Plan, stamp) -> PlannedTrajectory:
    message = PlannedTrajectory()
    message.header.stamp = stamp
    message.interface_version = PlannedTrajectory.INTERFACE_VERSION
    message.constrained = plan.constrained
    message.lane_radius_m = float(plan.lane_radius_m)
    message.joint_names = list(plan.joint_names)
    message.time_from_start_s = plan.time_s.tolist()
    message.positions = plan.q.ravel().tolist()
    message.velocities = plan.qdot.ravel().tolist()
    message.foil_accelerations = plan.foil_acceleration.ravel().tolist()
    message.feedforward_torques = plan.torque.ravel().tolist()
    message.lqr_gains = plan.lqr_gain.ravel().tolist()
    message.sliding_gains = plan.sliding_gain.ravel().tolist()
    message.segments = [PrimitiveSegment(
        primitive_id=s.primitive_id, primitive_type=s.primitive_type, repeat_index=s.repeat_index,
        start_time_s=s.start_time_s, duration_s=s.duration_s, time_scale=s.time_scale,
        alpha_offset_rad=s.alpha_offset_rad, first_sample=s.first_sample, sample_count=s.sample_count)
        for s in plan.segments]
    message.library_digest = plan.library_digest
    return message


class PlannerNode(Node):
    def __init__(self) -> None:
        super().__init__("planner_node")
        self.declare_parameter("library_path", "")
        self.declare_parameter("rig_path", "")
        self.declare_parameter("default_time_scale", 1.0)
        self.declare_parameter("lqr_weights_path", "")
        rig_path = self.get_parameter("rig_path").value or None
        library_path = self.get_parameter("library_path").value or default_library_path()
        self.rig = load_rig(rig_path)
        self.library = PrimitiveLibrary.load(library_path, self.rig)
        self.graph = build_graph(self.library)
        self._plan_library = self._retuned(self.get_parameter("lqr_weights_path").value)
        self.add_on_set_parameters_callback(self._on_set_parameters)
        for line in self.graph.mismatches:
            self.get_logger().warning(f"junction mismatch, primitive dropped from the graph: {line}")
        latched = QoSProfile(depth=1, durability=QoSDurabilityPolicy.TRANSIENT_LOCAL)
        self.plan_publisher = self.create_publisher(PlannedTrajectory, "plan", latched)
        self.create_service(RequestManeuver, "request_maneuver", self.on_request,
                            callback_group=ReentrantCallbackGroup())
        self.get_logger().info(f"serving {len(self.library)} primitives from {self.library.path}")

    def _retuned(self, lqr_weights_path: str) -> PrimitiveLibrary | RetunedLibrary:
        """The library plans are made from: its stored gains, or gains for the weights in lqr_weights_path."""
        if not lqr_weights_path:
            return self.library
        return RetunedLibrary(self.library, load_lqr_weights(lqr_weights_path))

    def _on_set_parameters(self, parameters) -> SetParametersResult:
        for parameter in parameters:
            if parameter.name == "lqr_weights_path":
                try:
                    retuned = self._retuned(parameter.value)
                except PlannerError as err:
                    return SetParametersResult(successful=False, reason=str(err))
                self._plan_library = retuned
                self.get_logger().info(f"LQ weights for new plans: {parameter.value or 'those stored'}")
        return SetParametersResult(successful=True)

    def on_request(self, request: RequestManeuver.Request,
                   response: RequestManeuver.Response) -> RequestManeuver.Response:
        try:
            plan = self.plan(request)
        except PlannerError as err:
            response.success, response.message = False, str(err)
            self.get_logger().warning(f"maneuver refused: {err}")
            return response
        response.success = True
        response.message = f"planned {len(plan.segments)} segments, {plan.duration_s:.3f} s"
        response.plan = plan_to_message(plan, self.get_clock().now().to_msg())
        self.plan_publisher.publish(response.plan)
        return response

    def plan(self, request: RequestManeuver.Request) -> Plan:
        time_scale = request.time_scale or self.get_parameter("default_time_scale").value
        if request.mode == RequestManeuver.Request.MODE_SEQUENCE:
            sequence = expand_sequence(list(request.primitive_ids), list(request.repeat_counts))
        elif request.mode == RequestManeuver.Request.MODE_GOAL:
            start = request.start_state or rest_node(request.goal_state.startswith("constrained"),
                                                     self.rig.lane_1_radius_m)
            sequence = plan_to_goal(self.graph, start, request.goal_state, request.goal_alpha_rad)
        else:
            modes = RequestManeuver.Request
            raise PlannerError(f"unknown mode {request.mode}: use MODE_SEQUENCE ({modes.MODE_SEQUENCE}) "
                               f"or MODE_GOAL ({modes.MODE_GOAL})")
        # the libraries are thread-safe; requests run concurrently (reentrant group), so one whose new gains are
        # being computed does not hold up the others
        return concatenate(self._plan_library, self.rig, sequence, time_scale, request.start_alpha_rad)


def main(args: list[str] | None = None) -> None:
    # this rclpy's init() is not a context manager, hence try/finally
    rclpy.init(args=args)
    try:
        try:
            node = PlannerNode()
        except (PlannerError, SwimModelError) as err:
            rclpy.logging.get_logger("planner_node").fatal(str(err))
            raise SystemExit(2) from err
        executor = MultiThreadedExecutor(num_threads=4)
        executor.add_node(node)
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()
