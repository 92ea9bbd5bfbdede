"""planner_node over DDS: a real node in its own process, requests through rclpy, the latched plan topic."""

import numpy as np
import pytest

from swim_ros.calls import ParameterCalls, RetryPolicy, call_service, spin_until
from swim_ros.testing.fixtures import running_node

#: a try's wait: planning takes milliseconds, new gains 0.1-0.3 s a primitive; a lost answer is asked again
POLICY = RetryPolicy(attempt_timeout_s=10.0, attempts=3, discovery_timeout_s=30.0)
#: a late subscriber's wait for the latched plan: discovery of a new reader on a loaded host takes seconds
LATCHED_DELIVERY_S = 10.0

PAPER = (["constrained/accelerate/E0.05", "constrained/cruise/E0.05", "constrained/cruise_to_cruise/E0.05-E0.10",
          "constrained/cruise/E0.10", "constrained/decelerate/E0.10"], [1, 2, 1, 2, 1])


@pytest.fixture(scope="module")
def planner(ros_domain, tmp_path_factory):
    with running_node("swim_planner", "planner_node", tmp_path_factory.mktemp("planner_node") / "log.txt") as process:
        yield process


@pytest.fixture()
def client(planner, rclpy_context):
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from swim_interfaces.srv import RequestManeuver
    node = rclpy.create_node("planner_test_client", context=rclpy_context)
    service = node.create_client(RequestManeuver, "request_maneuver")
    executor = SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(node)
    yield executor, service
    executor.shutdown()
    node.destroy_node()


def call(executor, service, ids, counts, time_scale=1.0, mode=0):
    from swim_interfaces.srv import RequestManeuver

    from swim_ros.calls import new_request_id
    request = RequestManeuver.Request(mode=mode, primitive_ids=ids, repeat_counts=counts, time_scale=time_scale,
                                      request_id=new_request_id())
    return call_service(executor, service, request, POLICY)


def test_valid_request_returns_the_paper_maneuver(client):
    executor, service = client
    reply = call(executor, service, *PAPER, time_scale=1.2)
    assert reply.success, reply.message
    plan = reply.plan
    assert plan.time_from_start_s[-1] == pytest.approx(30.0 / 1.2)
    assert len(plan.positions) == 3 * len(plan.time_from_start_s)
    assert [s.primitive_id for s in plan.segments] == [PAPER[0][0]] + [PAPER[0][1]] * 2 + [PAPER[0][2]] + \
        [PAPER[0][3]] * 2 + [PAPER[0][4]]
    assert all(s.time_scale == 1.2 for s in plan.segments)
    np.testing.assert_allclose(np.asarray(plan.velocities).reshape(-1, 3)[-1], 0.0, atol=1e-6)


@pytest.mark.parametrize("ids, counts, scale, mode, message", [
    (["no/such"], [1], 1.0, 0, "unknown primitives"),
    (["constrained/accelerate/E0.05", "constrained/cruise/E0.10"], [1, 1], 1.0, 0, "does not end where"),
    (PAPER[0], PAPER[1], 3.0, 0, "largest feasible time scale"),
    (PAPER[0], [1], 1.0, 0, "repeat counts"),
    ([], [], 1.0, 0, "empty"),
    (PAPER[0], PAPER[1], float("nan"), 0, "positive finite"),
    (PAPER[0], PAPER[1], 1.0, 7, "unknown mode 7"),
])
def test_bad_requests_are_refused_and_the_node_lives_on(client, planner, ids, counts, scale, mode, message):
    executor, service = client
    reply = call(executor, service, ids, counts, scale, mode)
    assert not reply.success and message in reply.message
    assert len(reply.plan.time_from_start_s) == 0
    assert planner.poll() is None


def test_goal_request(client):
    from swim_interfaces.srv import RequestManeuver
    executor, service = client
    request = RequestManeuver.Request(mode=RequestManeuver.Request.MODE_GOAL, goal_state="constrained/rest",
                                      goal_alpha_rad=3.0, time_scale=1.0)
    reply = call_service(executor, service, request, POLICY)
    assert reply.success, reply.message
    positions = np.asarray(reply.plan.positions).reshape(-1, 3)
    assert positions[-1, 0] - positions[0, 0] >= 3.0
    assert reply.plan.segments[0].primitive_type == "accelerate"
    assert reply.plan.segments[-1].primitive_type == "decelerate"
    request.goal_state = "constrained/cruise/E9.99"
    reply = call_service(executor, service, request, POLICY)
    assert not reply.success and "unknown goal state" in reply.message


def test_the_primitive_list_is_the_librarys(planner, rclpy_context, library):
    """list_primitives: every primitive of the served library (the ideal one, the node's default) with its duration,
    its advance from the stored motion and its energy levels; the graph's states, rests and cruises."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from swim_interfaces.srv import ListPrimitives
    node = rclpy.create_node("planner_list_client", context=rclpy_context)
    executor = SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(node)
    try:
        reply = call_service(executor, node.create_client(ListPrimitives, "list_primitives"),
                             ListPrimitives.Request(), POLICY)
    finally:
        executor.shutdown()
        node.destroy_node()
    assert (reply.flow_model, reply.library_digest) == ("ideal", library.digest())
    assert [p.primitive_id for p in reply.primitives] == sorted(library.ids())
    for info in reply.primitives:
        primitive = library.get(info.primitive_id)
        assert info.duration_s == library.spec(info.primitive_id).duration_s
        assert info.advance_rad == pytest.approx(primitive.q[-1, 0] - primitive.q[0, 0], abs=1e-12)
        assert info.start_state in reply.states and info.end_state in reply.states and info.in_graph
    accelerate = next(p for p in reply.primitives if p.primitive_id == "constrained/accelerate/E0.10")
    assert (accelerate.start_state, accelerate.end_state) == ("constrained/rest", "constrained/cruise/E0.10")
    assert (accelerate.start_energy_j, accelerate.end_energy_j, accelerate.primitive_type) == \
        (0.0, 0.10, "accelerate")
    assert {"constrained/rest", "free/rest/R0.43", "free/rest/R0.48"} <= set(reply.states)


def test_concurrent_requests(client):
    executor, service = client
    from swim_interfaces.srv import RequestManeuver
    call(executor, service, *PAPER)          # discovery complete both ways before the concurrent requests
    futures = [service.call_async(RequestManeuver.Request(primitive_ids=PAPER[0], repeat_counts=PAPER[1],
                                                          time_scale=scale))
               for scale in (0.8, 1.0, 1.1, 1.2)]
    spin_until(executor, lambda: all(f.done() for f in futures), POLICY.attempt_timeout_s)
    durations = [f.result().plan.time_from_start_s[-1] for f in futures]
    np.testing.assert_allclose(durations, [30 / 0.8, 30.0, 30 / 1.1, 30 / 1.2])


def test_last_plan_is_latched(client, rclpy_context):
    import rclpy
    from rclpy.qos import QoSDurabilityPolicy, QoSProfile
    from swim_interfaces.msg import PlannedTrajectory
    executor, service = client
    assert call(executor, service, *PAPER, time_scale=1.0).success
    late = rclpy.create_node("late_subscriber", context=rclpy_context)
    received = []
    late.create_subscription(PlannedTrajectory, "plan", received.append,
                             QoSProfile(depth=1, durability=QoSDurabilityPolicy.TRANSIENT_LOCAL))
    executor.add_node(late)
    spin_until(executor, lambda: bool(received), LATCHED_DELIVERY_S)
    executor.remove_node(late)
    late.destroy_node()
    assert received and received[-1].time_from_start_s[-1] == pytest.approx(30.0)


def test_lqr_weights_switch_at_run_time(client, tmp_path):
    """Plans after a new lqr_weights_path carry gains for it; a bad file is refused and changes nothing."""
    from rclpy.parameter import Parameter
    executor, service = client
    parameters = ParameterCalls(executor.get_nodes()[0], executor, "planner_node", POLICY)

    def set_weights_path(path):
        return parameters.set([Parameter("lqr_weights_path", value=str(path))])[0]

    def heave_gains(reply):
        assert reply.success, reply.message
        plan = reply.plan
        return np.reshape(plan.lqr_gains, (len(plan.time_from_start_s), 2, -1))[:, 0], plan.library_digest

    sequence = (PAPER[0][:2], [1, 1])
    stored, stored_digest = heave_gains(call(executor, service, *sequence))
    heavier = tmp_path / "heavier_heave_input.yaml"
    heavier.write_text("heave_input_weight: 0.04\n")   # 4x the default: a costlier heave input
    assert set_weights_path(heavier).successful
    retuned, retuned_digest = heave_gains(call(executor, service, *sequence))
    assert np.abs(retuned).mean() < 0.8 * np.abs(stored).mean() and retuned_digest != stored_digest
    bad = tmp_path / "bad.yaml"
    bad.write_text("heave_input_weight: -1.0\n")
    refused = set_weights_path(bad)
    assert not refused.successful and "positive finite" in refused.reason
    unchanged, _ = heave_gains(call(executor, service, *sequence))
    np.testing.assert_array_equal(unchanged, retuned)
    assert set_weights_path("").successful
    back, back_digest = heave_gains(call(executor, service, *sequence))
    np.testing.assert_array_equal(back, stored)
    assert back_digest == stored_digest
