"""maneuver_node: the perform_maneuver action, a maneuver flown from where the vehicle is.

The goal, where it starts, the planner and tracker calls, the result, cancel and the parameters: see
src/swim_bringup/README.md, section "maneuver_node".
"""
from __future__ import annotations

import dataclasses
import functools
import threading
import time
from typing import Any, Optional

from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from sensor_msgs.msg import JointState
from swim_interfaces.action import ExecutePlan, PerformManeuver
from swim_interfaces.srv import ListPrimitives, RequestManeuver

from swim_bringup.maneuver import ManeuverGoal, ManeuverGoalError, NotAtRest, RestBounds, VehicleState, start_state
from swim_control.errors import StateMessageError
from swim_controller.supervisor import Tolerances
from swim_model.vehicle import JOINT_NAMES_CONSTRAINED, JOINT_NAMES_UNCONSTRAINED
from swim_model.velocity_filter import VelocityEstimator
from swim_ros.calls import (
    ActionClient,
    CallFailed,
    GoalStatusWatch,
    RetryPolicy,
    ServedElsewhere,
    call_service,
    cancel_goal,
    new_request_id,
    send_goal,
)
from swim_ros.entry import run_node
from swim_ros.parameters import NodeSettings, ParameterSpec, positive
from swim_ros.qos import per_period_subscription
from swim_ros.trajectory_messages import state_from_message
from swim_ros.transport import use_large_message_transport

Result = PerformManeuver.Result
Feedback = PerformManeuver.Feedback

#: threads of the node's executor: a goal's work holds one while it waits; another goal (preemption), the answers,
#: the feedback and joint_states need the others
EXECUTOR_THREADS = 4
#: a goal waits for the tracker's result this long at a time (it is asked again after), and checks for a cancel this
#: often: a cancel reaches the tracker at most this late (assumed: 20 ms is 2.5 control periods)
RESULT_POLL_S = 0.02
#: how often an unanswered result request is sent again (idempotent; the answer of a lost one never comes)
RESULT_RESEND_S = 10.0

#: the rest bounds' defaults, from the speeds measured after the realistic pipeline's decelerates: the hub coasts
#: on at 0.03 rad/s (emulated rig) to 0.065 rad/s (simulator, tilted tank), and the emulated rig's vortex wake turns
#: it back at up to 0.1 rad/s in the next minute; the platform drifts at 0.01 m/s; the foil settles under 0.1 rad/s
#: within 0.5 s of the plan's end. A cruise swings the foil at over 1 rad/s
REST_ANGULAR_SPEED_RAD_S = 0.15
REST_LINEAR_SPEED_M_S = 0.03
#: how long a goal waits for a vehicle moving faster than that to come to rest before it refuses (the foil's 0.5 s,
#: doubled)
REST_WAIT_S = 1.0

PARAMETERS = (
    ParameterSpec("rest_angular_speed_rad_s", REST_ANGULAR_SPEED_RAD_S,
                  "at rest: |alpha_dot|, |phi_dot| and |theta_dot| under this, rad/s", range=(1e-6, 10.0),
                  check=positive),
    ParameterSpec("rest_linear_speed_m_s", REST_LINEAR_SPEED_M_S, "at rest: |R_dot| under this, m/s",
                  range=(1e-6, 1.0), check=positive),
    ParameterSpec("rest_wait_s", REST_WAIT_S,
                  "a goal waits this long for a moving vehicle to come to rest before it refuses, s",
                  range=(0.0, 60.0)),
    ParameterSpec("lane_tolerance_m", 0.025,
                  "the free vehicle is on the lane nearest its R if within this, m (half the lanes' spacing)",
                  range=(1e-6, 1.0), check=positive),
    ParameterSpec("state_max_age_s", 0.5,
                  "a goal starts from joint_states no older than this (it waits node_timeout_s for one), s",
                  range=(0.01, 60.0), check=positive),
    ParameterSpec("node_timeout_s", 10.0,
                  "how long a goal waits for joint_states, for planner_node or tracker_node to appear and for each "
                  "answer, s",
                  range=(0.1, 600.0), check=positive),
)


@dataclasses.dataclass(frozen=True)
class ManeuverSettings:
    """PARAMETERS' values (swim_ros.parameters.NodeSettings)."""

    rest_angular_speed_rad_s: float
    rest_linear_speed_m_s: float
    rest_wait_s: float
    lane_tolerance_m: float
    state_max_age_s: float
    node_timeout_s: float


class ManeuverNode(Node):
    """The operator's maneuver server: the perform_maneuver action, planned and tracked from where the vehicle is."""

    def __init__(self) -> None:
        super().__init__("maneuver_node")
        self.parameters = NodeSettings(self, PARAMETERS, ManeuverSettings)
        group = ReentrantCallbackGroup()
        self._state_lock = threading.Lock()
        self._latest_state: Optional[tuple[JointState, float]] = None   # message, monotonic time of receipt
        self._state_arrived = threading.Event()
        per_period_subscription(self, JointState, "joint_states", self._on_state)
        self._planner = self.create_client(RequestManeuver, "request_maneuver", callback_group=group)
        self._lister = self.create_client(ListPrimitives, "list_primitives", callback_group=group)
        self._tracker = ActionClient(self, ExecutePlan, "execute_plan", callback_group=group)
        self._tracker_status = GoalStatusWatch(self, "execute_plan")
        self._catalog: Optional[Any] = None   # planner_node's latest ListPrimitives reply (_primitive_list)
        self._server = ActionServer(self, PerformManeuver, "perform_maneuver", execute_callback=self._execute,
                                    goal_callback=lambda goal: GoalResponse.ACCEPT,
                                    cancel_callback=lambda handle: CancelResponse.ACCEPT, callback_group=group)
        self.get_logger().info("maneuver server ready: perform_maneuver plans through request_maneuver and tracks "
                               "through execute_plan")

    def _on_state(self, message: JointState) -> None:
        with self._state_lock:
            self._latest_state = (message, time.monotonic())
        self._state_arrived.set()

    def _policy(self) -> RetryPolicy:
        timeout_s = self.parameters.current.node_timeout_s
        return RetryPolicy(attempt_timeout_s=timeout_s, attempts=3, discovery_timeout_s=timeout_s)

    # ----- the goal's steps --------------------------------------------------------------------------------------
    def _vehicle(self) -> VehicleState:
        """The vehicle from the latest joint_states; ManeuverGoalError if there is none recent or it is malformed."""
        settings = self.parameters.current
        max_age_s, timeout_s = settings.state_max_age_s, settings.node_timeout_s
        deadline_s = time.monotonic() + timeout_s
        while True:
            with self._state_lock:
                latest = self._latest_state
            if latest is not None and time.monotonic() - latest[1] <= max_age_s:
                break
            if time.monotonic() > deadline_s:
                raise ManeuverGoalError(f"no joint_states for {timeout_s:g} s: is a plant (sim_node or bridge_node) "
                                        f"running?")
            self._state_arrived.wait(RESULT_POLL_S)
            self._state_arrived.clear()
        message = latest[0]
        if len(message.velocity) == 0:   # one message's: a velocity estimate needs a series
            raise ManeuverGoalError("the latest joint_states carries no velocities: whether the vehicle is at rest "
                                    "is unknown")
        try:
            return vehicle_of(message)
        except StateMessageError as err:
            raise ManeuverGoalError(f"the latest joint_states is not the vehicle's: {err}") from err

    def _primitive_list(self):
        """planner_node's list_primitives reply, kept for the next goals."""
        self._catalog = call_service(ServedElsewhere(), self._lister, ListPrimitives.Request(), self._policy())
        return self._catalog

    def _flight_plan(self, goal: ManeuverGoal):
        """The planner's reply and its request id for the goal from where the vehicle is.

        (the planner's reply, its request id) for the goal from where the vehicle is. The primitive list kept
        from an earlier goal serves only while it passes the checks and names the library the plan came from;
        otherwise the planner is asked for its list again (it may serve another library now) and the goal checked
        and planned on that. ManeuverGoalError, NotAtRest or CallFailed when it cannot be.
        """
        lists = (False, True) if self._catalog is not None else (True,)
        for fresh in lists:
            catalog = self._catalog if not fresh and self._catalog is not None else self._primitive_list()
            try:
                vehicle, start = self._start(goal, catalog)
            except NotAtRest:
                raise
            except ManeuverGoalError:
                if fresh:
                    raise
                continue
            request_id = new_request_id()
            self.get_logger().info(
                f"maneuver {request_id}: from {start} at alpha {vehicle.alpha_rad:.4f} rad"
                + ("" if vehicle.lane_radius_m is None else f", R {vehicle.lane_radius_m:.4f} m")
                + f", joint speeds {', '.join(f'{n} {v:+.3g}' for n, v in zip(vehicle.joint_names, vehicle.qdot))}")
            reply = self._plan(goal, start, vehicle, request_id)
            if fresh or reply.success and reply.plan.library_digest == catalog.library_digest:
                return reply, request_id
        raise AssertionError("the last try is made with a fresh list and returns")

    def _start(self, goal: ManeuverGoal, catalog) -> tuple[VehicleState, str]:
        """The vehicle and the graph state the maneuver starts in.

        They are as maneuver.start_state gives them, waiting up to rest_wait_s for a vehicle that is coming to rest.
        """
        settings = self.parameters.current
        deadline_s = time.monotonic() + settings.rest_wait_s
        start_states = {p.primitive_id: p.start_state for p in catalog.primitives}
        bounds = RestBounds(settings.rest_angular_speed_rad_s, settings.rest_linear_speed_m_s)
        while True:
            vehicle = self._vehicle()
            try:
                return vehicle, start_state(goal, vehicle, catalog.states, start_states, bounds,
                                            settings.lane_tolerance_m)
            except NotAtRest:
                if time.monotonic() > deadline_s:
                    raise
            self._state_arrived.wait(RESULT_POLL_S)
            self._state_arrived.clear()

    def _plan(self, goal: ManeuverGoal, start: str, vehicle: VehicleState, request_id: str):
        """The planner's reply to the goal from the vehicle's start."""
        request = RequestManeuver.Request(mode=goal.mode, primitive_ids=list(goal.primitive_ids),
                                          repeat_counts=list(goal.repeats), goal_state=goal.goal_state,
                                          goal_alpha_rad=goal.goal_alpha_rad, time_scale=goal.time_scale,
                                          start_alpha_rad=vehicle.alpha_rad, request_id=request_id)
        if goal.mode == PerformManeuver.Goal.MODE_GOAL:
            request.start_state = start
        return call_service(ServedElsewhere(), self._planner, request, self._policy())

    def _execute(self, handle) -> PerformManeuver.Result:
        """The goal's whole flight, ended with an error on an unexpected one.

        The goal's whole flight; an unexpected error ends it with the error, never with rclpy's default result
        (whose error code would read as SUCCESSFUL).
        """
        try:
            return self._fly(handle)
        except Exception as err:  # noqa: BLE001 - reported to the client, the node serves the next goal
            self.get_logger().error(f"maneuver failed: {err!r}")
            if handle.is_active:
                return self._ended(handle, Result.NODE_UNAVAILABLE, f"maneuver_node failed: {err!r}")
            return Result(error_code=Result.NODE_UNAVAILABLE, error_string=f"maneuver_node failed: {err!r}")

    def _fly(self, handle) -> PerformManeuver.Result:
        handle.publish_feedback(Feedback(phase=Feedback.PHASE_PLANNING))
        request_id = ""
        try:
            goal = goal_of(handle.request)
            goal.validate()
            reply, request_id = self._flight_plan(goal)
        except ManeuverGoalError as err:
            return self._ended(handle, Result.INVALID_GOAL, f"refused: {err}")
        except CallFailed as err:
            return self._ended(handle, Result.NODE_UNAVAILABLE, f"planner_node: {err}", request_id)
        if not reply.success:
            return self._ended(handle, Result.PLANNING_FAILED, f"the planner refused: {reply.message}", request_id)
        if handle.is_cancel_requested:
            return self._ended(handle, Result.CANCELED, "canceled before tracking: nothing moved", request_id)
        return self._track(handle, reply.plan, goal.tolerances, request_id)

    def _track(self, handle, plan, tolerances: Tolerances, request_id: str) -> PerformManeuver.Result:
        """Send the plan to the tracker, relay its feedback, pass a cancel on, and return its result as ours."""
        segments = [segment.primitive_id for segment in plan.segments]

        def relay(message) -> None:
            tracked = message.feedback
            out = Feedback(phase=tracked.phase, segment_count=len(segments), progress=tracked.progress,
                           state=tracked.state)
            state = tracked.state
            if tracked.phase == ExecutePlan.Feedback.PHASE_TRACKING and state.joint_names:
                out.segment_index = min(state.segment_index, len(segments) - 1)
                out.primitive_id = segments[out.segment_index]
                errors = dict(zip(state.joint_names, state.error.positions))
                out.alpha_error_rad, out.r_error_m = errors.get("alpha", 0.0), errors.get("R", 0.0)
            handle.publish_feedback(out)

        goal = ExecutePlan.Goal(plan=plan, path_tolerance_alpha_rad=tolerances.path_alpha_rad,
                                path_tolerance_r_m=tolerances.path_r_m,
                                goal_tolerance_alpha_rad=tolerances.goal_alpha_rad,
                                goal_tolerance_r_m=tolerances.goal_r_m)
        policy = self._policy()
        try:
            tracked = send_goal(ServedElsewhere(), self._tracker, goal, self._tracker_status, relay, policy)
        except CallFailed as err:
            return self._ended(handle, Result.NODE_UNAVAILABLE, f"tracker_node: {err}", request_id)
        if not tracked.accepted:
            return self._ended(handle, Result.NODE_UNAVAILABLE, "tracker_node refused the goal", request_id)
        result = self._tracker_result(handle, tracked, policy)
        if result is None:
            return self._ended(handle, Result.NODE_UNAVAILABLE,
                               f"tracker_node gave no result and left the graph (waited {policy.attempt_timeout_s:g} "
                               f"s for it)", request_id)
        ours = Result(error_code=result.error_code, error_string=result.error_string,
                      final_alpha_error_rad=result.final_alpha_error_rad, final_r_error_m=result.final_r_error_m,
                      duration_s=result.duration_s, request_id=request_id)
        if result.error_code == Result.SUCCESSFUL:
            handle.succeed()
        elif result.error_code == Result.CANCELED and handle.is_cancel_requested:
            handle.canceled()
        else:
            handle.abort()
        self.get_logger().info(f"maneuver {request_id} ended: {result.error_code} {result.error_string}")
        return ours

    def _tracker_result(self, handle, tracked, policy: RetryPolicy):
        """The tracker's result for the goal tracked, or None.

        The tracker's result for the goal tracked, passing a cancel of ours on once; None if the tracker left
        the graph for longer than the policy's attempt timeout without answering.
        """
        event = threading.Event()
        futures = []

        def ask() -> None:
            future = tracked.get_result_async()
            future.add_done_callback(lambda _: event.set())
            futures.append(future)
        ask()
        asked_s = gone_since_s = time.monotonic()
        cancel_sent = False
        while not any(f.done() for f in futures):
            event.wait(RESULT_POLL_S)
            now_s = time.monotonic()
            if handle.is_cancel_requested and not cancel_sent:
                cancel_sent = True
                try:
                    cancel_goal(ServedElsewhere(), tracked, policy)
                except CallFailed as err:
                    self.get_logger().error(f"the tracker did not answer the cancel: {err}")
            if now_s - asked_s > RESULT_RESEND_S:
                ask()
                asked_s = now_s
            if self._tracker.server_is_ready():
                gone_since_s = now_s
            elif now_s - gone_since_s > policy.attempt_timeout_s:
                return None
        return next(f for f in futures if f.done()).result().result

    def _ended(self, handle, code: int, reason: str, request_id: str = "") -> PerformManeuver.Result:
        """End a goal that never reached the tracker's result: aborted (or canceled), with the reason."""
        if code == Result.CANCELED:
            handle.canceled()
        else:
            handle.abort()
        self.get_logger().warning(f"maneuver not flown: {reason}")
        return Result(error_code=code, error_string=reason, request_id=request_id)


def vehicle_of(message) -> VehicleState:
    """The vehicle a sensor_msgs/JointState gives.

    It passes swim_ros.trajectory_messages.state_from_message's checks (the vehicle's joints in any order, finite
    values, lengths that agree); its speeds are zero when the message carries none. StateMessageError otherwise.
    """
    _, q, qdot = state_from_message(message, None, VelocityEstimator(), 0.0)
    return VehicleState(JOINT_NAMES_UNCONSTRAINED if len(q) == len(JOINT_NAMES_UNCONSTRAINED)
                        else JOINT_NAMES_CONSTRAINED, q, qdot)


def goal_of(request) -> ManeuverGoal:
    """A PerformManeuver goal message as a ManeuverGoal."""
    return ManeuverGoal(
        mode=request.mode, primitive_ids=tuple(request.primitive_ids), repeat_counts=tuple(request.repeat_counts),
        goal_state=request.goal_state, goal_alpha_rad=request.goal_alpha_rad, time_scale=request.time_scale,
        tolerances=Tolerances(request.path_tolerance_alpha_rad, request.path_tolerance_r_m,
                              request.goal_tolerance_alpha_rad, request.goal_tolerance_r_m))


def main(args: list[str] | None = None) -> None:
    """Run maneuver_node."""
    run_node(ManeuverNode, args, name="maneuver_node",
             executor=functools.partial(MultiThreadedExecutor, num_threads=EXECUTOR_THREADS),
             transport=use_large_message_transport)


if __name__ == "__main__":
    main()
