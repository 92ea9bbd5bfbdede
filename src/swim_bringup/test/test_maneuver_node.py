"""maneuver_node over DDS on the simulator in lock-step (the realistic pipeline, each node in its own process): the
perform_maneuver goal as an operator types it (fields from a YAML string, as ros2cli fills them), refusals with their
reasons and nothing moved, the phases of the feedback, a refused goal that leaves the maneuver under way alone, a
cancel passed on to the tracker, and a plan sent to the tracker directly preempting the maneuver."""
import math

import numpy as np
import pytest

from swim_ros.testing.fixtures import new_rclpy_context, ros_domain  # noqa: F401

#: a try's wait for an answer, and the wait for the nodes: several nodes start at once on a loaded 2-core host
POLICY_S = 60.0
#: a maneuver's wall time in lock-step: the 30 s plan runs in 7-15 s on a 2-core host, a loaded one slower
RESULT_TIMEOUT_S = 300.0
#: the paper's constrained maneuver (recorded_run.PAPER_CONSTRAINED) as an operator types it, with the demo's
#: tolerances (recorded_run.RUN_TOLERANCES, checked against them below)
PAPER_GOAL_YAML = ("{mode: 0, primitive_ids: [constrained/accelerate/E0.05, constrained/cruise/E0.05, "
                   "constrained/cruise_to_cruise/E0.05-E0.10, constrained/cruise/E0.10, constrained/decelerate/E0.10],"
                   " repeat_counts: [1, 2, 1, 2, 1], path_tolerance_alpha_rad: 1.0, goal_tolerance_alpha_rad: 0.25,"
                   " goal_tolerance_r_m: 0.025}")

#: the paper's maneuver with ten cruises at each level (110 s of plan, 25 s and more of wall time in lock-step): it
#: is still under way however slow a loaded host makes the steps a test takes while it flies
LONG_GOAL_YAML = PAPER_GOAL_YAML.replace("repeat_counts: [1, 2, 1, 2, 1]", "repeat_counts: [1, 10, 1, 10, 1]")

#: at rest for the next goal: every joint speed under REST_SPEED (rad/s or m/s) for REST_STATES states in a row,
#: well under maneuver_node's bounds (config/maneuver.yaml: 0.15 rad/s, 0.03 m/s)
REST_SPEED = 0.05
REST_STATES = 25


class Operator:
    """A client of the running set: the perform_maneuver action, and what the tracker commands."""

    def __init__(self, context) -> None:
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from sensor_msgs.msg import JointState
        from swim_interfaces.action import PerformManeuver

        from swim_ros.calls import ActionClient, GoalStatusWatch
        self.node = rclpy.create_node("maneuver_test_operator", context=context)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.client = ActionClient(self.node, PerformManeuver, "perform_maneuver")
        self.status = GoalStatusWatch(self.node, "perform_maneuver")
        self.tracker_status = GoalStatusWatch(self.node, "execute_plan")
        self.efforts: list[tuple[float, ...]] = []
        self.node.create_subscription(JointState, "joint_commands",
                                      lambda m: self.efforts.append(tuple(m.effort)), 100)
        self.still_states = 0   # consecutive joint_states with every speed under REST_SPEED
        self.node.create_subscription(JointState, "joint_states", self._on_state, 100)

    def _on_state(self, message) -> None:
        moving = not message.velocity or max(map(abs, message.velocity)) >= REST_SPEED
        self.still_states = 0 if moving else self.still_states + 1

    def reset_to_rest(self) -> None:
        """sim_node back at its start (its reset service), and at rest again: the tracker's hold brings the foil
        back to where the reset put it."""
        from std_srvs.srv import Trigger

        from swim_ros.calls import RetryPolicy, call_service
        policy = RetryPolicy(attempt_timeout_s=10.0, attempts=3, discovery_timeout_s=POLICY_S)
        assert call_service(self.executor, self.node.create_client(Trigger, "reset"), Trigger.Request(),
                            policy).success
        self.still_states = 0
        self.spin_until(lambda: self.still_states >= REST_STATES)

    def send(self, goal_yaml: str, feedback: list):
        from swim_interfaces.action import PerformManeuver

        from swim_ros.calls import RetryPolicy, send_goal
        from swim_ros.testing.message_fields import message_from_yaml
        goal = message_from_yaml(PerformManeuver.Goal, goal_yaml)
        policy = RetryPolicy(attempt_timeout_s=10.0, attempts=3, discovery_timeout_s=POLICY_S)
        handle = send_goal(self.executor, self.client, goal, self.status, lambda m: feedback.append(m.feedback),
                           policy)
        assert handle.accepted
        return handle

    def result(self, handle):
        from swim_ros.calls import goal_result
        return goal_result(self.executor, handle, RESULT_TIMEOUT_S).result

    def spin_until(self, done, timeout_s: float = RESULT_TIMEOUT_S) -> None:
        from swim_ros.calls import spin_until
        assert spin_until(self.executor, done, timeout_s)

    def until_tracking(self, handle, feedback: list, segment_index: int = 0) -> None:
        """Spin until the goal tracks its segment_index-th primitive or later; fails at once if the goal ended."""
        from action_msgs.msg import GoalStatus
        from swim_interfaces.action import PerformManeuver
        tracking = PerformManeuver.Feedback.PHASE_TRACKING
        key = bytes(handle.goal_id.uuid)
        self.spin_until(lambda: any(f.phase == tracking and f.segment_index >= segment_index for f in feedback)
                        or self.status.statuses.get(key, GoalStatus.STATUS_UNKNOWN) >= GoalStatus.STATUS_SUCCEEDED)
        assert self.status.statuses.get(key) == GoalStatus.STATUS_EXECUTING, self.result(handle)

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()


@pytest.fixture(scope="module")
def operator(ros_domain, tmp_path_factory):  # noqa: F811 - the fixture imported above
    from swim_bringup.system import System, closed_loop_specs, config_dir
    specs = closed_loop_specs(config_dir("realistic"), plant="sim", visualization=False, maneuver=True)
    with System(specs, tmp_path_factory.mktemp("maneuver_node") / "logs") as system:
        with new_rclpy_context() as context:
            operator = Operator(context)
            try:
                # the loop is up once the idle tracker answers the simulator's states
                operator.spin_until(lambda: len(operator.efforts) > 10, POLICY_S)
                yield operator
            finally:
                operator.close()
        assert not system.dead(), f"{system.dead()} died during the tests"


@pytest.mark.parametrize("goal_yaml, code, reason", [
    ("{mode: 0, primitive_ids: [no/such]}", "PLANNING_FAILED", "the planner refused: unknown primitives"),
    ("{mode: 1, goal_state: free/rest/R0.48}", "PLANNING_FAILED", "no sequence of primitives leads from"),
    ("{mode: 0, primitive_ids: [constrained/accelerate/E0.05], time_scale: .nan}", "PLANNING_FAILED",
     "the planner refused: .*time scale"),
    ("{mode: 0}", "INVALID_GOAL", "neither a sequence"),
    ("{mode: 1, goal_state: constrained/rest, goal_tolerance_r_m: -1.0}", "INVALID_GOAL", "goal_r_m must be"),
    ("{mode: 0, primitive_ids: [free/accelerate/R0.43/E0.05]}", "INVALID_GOAL",
     "starts in 'free/rest/R0.43', and the vehicle is in 'constrained/rest'"),
])
def test_a_goal_that_cannot_be_flown_ends_with_the_reason_and_nothing_moves(operator, goal_yaml, code, reason):
    import re

    from swim_interfaces.action import PerformManeuver
    feedback: list = []
    operator.efforts.clear()
    handle = operator.send(goal_yaml, feedback)
    result = operator.result(handle)
    assert result.error_code == getattr(PerformManeuver.Result, code), result.error_string
    assert re.search(reason, result.error_string), result.error_string
    assert [f.phase for f in feedback] == [PerformManeuver.Feedback.PHASE_PLANNING]
    operator.spin_until(lambda: len(operator.efforts) > 5)   # the tracker's answers after the refusal too
    assert set(operator.efforts) == {(0.0, 0.0)}, "a refused goal commanded torque"


def test_the_papers_maneuver_typed_as_yaml_flies_from_where_the_vehicle_is(operator):
    from swim_interfaces.action import PerformManeuver

    from swim_bringup.experiments import PAPER_CONSTRAINED
    from swim_bringup.recorded_run import RUN_TOLERANCES
    Feedback = PerformManeuver.Feedback
    assert (RUN_TOLERANCES.path_alpha_rad, RUN_TOLERANCES.goal_alpha_rad, RUN_TOLERANCES.goal_r_m) == (1.0, 0.25, 0.025)
    feedback: list = []
    handle = operator.send(PAPER_GOAL_YAML, feedback)
    result = operator.result(handle)
    assert result.error_code == PerformManeuver.Result.SUCCESSFUL, result.error_string
    assert abs(result.final_alpha_error_rad) <= RUN_TOLERANCES.goal_alpha_rad and len(result.request_id) == 32
    assert result.duration_s == pytest.approx(30.0)
    # each phase in order: the circulatory constrained model is not one the tracker builds at start
    phases = [f.phase for f in feedback]
    firsts = sorted({phase: phases.index(phase) for phase in set(phases)}.items(), key=lambda item: item[1])
    assert [phase for phase, _ in firsts] == [Feedback.PHASE_PLANNING, Feedback.PHASE_WAITING_FOR_MODEL,
                                              Feedback.PHASE_TRACKING]
    tracked = [f for f in feedback if f.phase == Feedback.PHASE_TRACKING]
    expected = [pid for pid, count in zip(*PAPER_CONSTRAINED) for _ in range(count)]
    assert all(f.segment_count == len(expected) and f.primitive_id == expected[f.segment_index] for f in tracked)
    assert [f.segment_index for f in tracked] == sorted(f.segment_index for f in tracked)
    assert np.all(np.diff([f.progress for f in tracked]) >= 0.0)
    for f in tracked:   # the errors are the tracking state's own
        assert f.alpha_error_rad == f.state.error.positions[0] and f.r_error_m == 0.0
    assert max(abs(f.alpha_error_rad) for f in tracked) <= RUN_TOLERANCES.path_alpha_rad


def test_a_maneuver_starts_at_the_vehicles_alpha(operator):
    """After the paper's maneuver the vehicle rests near alpha 15 rad: a goal-state request plans from there."""
    from swim_interfaces.action import PerformManeuver
    Feedback = PerformManeuver.Feedback
    feedback: list = []
    handle = operator.send("{mode: 1, goal_state: constrained/rest, goal_alpha_rad: 3.0, goal_tolerance_alpha_rad: "
                           "0.25}", feedback)
    operator.spin_until(lambda: any(f.phase == Feedback.PHASE_TRACKING for f in feedback))
    first = next(f for f in feedback if f.phase == Feedback.PHASE_TRACKING).state
    assert first.reference.positions[0] > 10.0   # the paper's maneuver advanced some 15 rad
    assert first.reference.positions[0] == pytest.approx(first.feedback.positions[0], abs=0.05)
    result = operator.result(handle)
    assert result.error_code == PerformManeuver.Result.SUCCESSFUL, result.error_string


def test_a_goal_for_a_moving_vehicle_is_refused_and_a_cancel_reaches_the_tracker(operator):
    from action_msgs.msg import GoalStatus
    from swim_interfaces.action import PerformManeuver

    from swim_ros.calls import cancel_goal
    operator.reset_to_rest()
    feedback: list = []
    handle = operator.send(LONG_GOAL_YAML, feedback)
    operator.until_tracking(handle, feedback, segment_index=1)   # cruising: the foil swings
    refused: list = []
    second = operator.send("{mode: 1, goal_state: constrained/rest, goal_alpha_rad: 3.0}", refused)
    result = operator.result(second)
    assert result.error_code == PerformManeuver.Result.INVALID_GOAL
    assert "not at rest" in result.error_string and "rad/s" in result.error_string
    assert operator.status.statuses[bytes(handle.goal_id.uuid)] == GoalStatus.STATUS_EXECUTING   # not preempted
    progress = feedback[-1].progress
    assert 0.0 < progress < 1.0
    cancel_goal(operator.executor, handle)
    result = operator.result(handle)
    assert result.error_code == PerformManeuver.Result.CANCELED, result.error_string
    assert 0.0 < result.duration_s < 110.0 and math.isfinite(result.final_alpha_error_rad)
    operator.spin_until(lambda: operator.status.statuses.get(bytes(handle.goal_id.uuid)) == GoalStatus.STATUS_CANCELED)
    # the tracker's own goal was canceled too (its status topic is transient local, the latest goal last)
    operator.spin_until(lambda: GoalStatus.STATUS_CANCELED in operator.tracker_status.statuses.values())


def test_a_plan_sent_to_the_tracker_preempts_the_maneuver_under_way(operator):
    """Preemption keeps execute_plan's meaning: a goal the tracker starts ends the maneuver under way, PREEMPTED."""
    from swim_interfaces.action import ExecutePlan, PerformManeuver
    from swim_interfaces.srv import RequestManeuver

    from swim_ros.calls import (
        ActionClient,
        GoalStatusWatch,
        RetryPolicy,
        call_service,
        cancel_goal,
        goal_result,
        new_request_id,
        send_goal,
    )
    policy = RetryPolicy(attempt_timeout_s=10.0, attempts=3, discovery_timeout_s=POLICY_S)
    operator.reset_to_rest()
    feedback: list = []
    handle = operator.send(LONG_GOAL_YAML, feedback)
    operator.until_tracking(handle, feedback)
    planner = operator.node.create_client(RequestManeuver, "request_maneuver")
    reply = call_service(operator.executor, planner, RequestManeuver.Request(
        # long enough (4 s and 30 cruises) to be still under way when the test cancels it
        primitive_ids=["constrained/accelerate/E0.05", "constrained/cruise/E0.05"], repeat_counts=[1, 30],
        request_id=new_request_id(),
        start_alpha_rad=feedback[-1].state.feedback.positions[0]), policy)
    assert reply.success, reply.message
    tracker = ActionClient(operator.node, ExecutePlan, "execute_plan")
    direct = send_goal(operator.executor, tracker, ExecutePlan.Goal(plan=reply.plan), GoalStatusWatch(
        operator.node, "execute_plan"), policy=policy)
    result = operator.result(handle)
    assert result.error_code == PerformManeuver.Result.PREEMPTED, result.error_string
    cancel_goal(operator.executor, direct, policy)
    assert goal_result(operator.executor, direct, RESULT_TIMEOUT_S).result.error_code == \
        ExecutePlan.Result.CANCELED
