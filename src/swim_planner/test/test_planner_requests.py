"""planner_node in this process, over DDS, with its answers lost the way Fast DDS loses them: a repeated request
id gets the first reply, and nothing is planned or published twice."""
import threading

import pytest

from swim_ros.calls import RetryPolicy, call_service, new_request_id

SEQUENCE = (["constrained/accelerate/E0.05", "constrained/cruise/E0.05", "constrained/decelerate/E0.05"], [1, 2, 1])
#: a plan of stored gains takes milliseconds: a 2 s try is ample, and short enough to keep the test quick
QUICK = RetryPolicy(attempt_timeout_s=2.0, attempts=3, discovery_timeout_s=30.0)


@pytest.fixture()
def planner():
    """(planner node spinning in a thread, a client node, the client's executor)."""
    import rclpy
    from rclpy.executors import MultiThreadedExecutor, SingleThreadedExecutor

    from swim_planner.planner_node import PlannerNode
    from swim_ros.domains import claim_ros_domain
    claim_ros_domain()
    rclpy.init()
    node = PlannerNode()
    spinner = MultiThreadedExecutor(num_threads=4)
    spinner.add_node(node)
    thread = threading.Thread(target=spinner.spin, daemon=True)
    thread.start()
    client = rclpy.create_node("planner_requests_test")
    executor = SingleThreadedExecutor()
    executor.add_node(client)
    yield node, client, executor
    spinner.shutdown()
    thread.join(timeout=10.0)
    client.destroy_node()
    node.destroy_node()
    rclpy.shutdown()


def counted(obj, name):
    """Wrap obj.name (a method) to count its calls; returns the list of calls."""
    calls, original = [], getattr(obj, name)

    def wrapper(*args, **kwargs):
        calls.append(args)
        return original(*args, **kwargs)
    setattr(obj, name, wrapper)
    return calls


def test_a_repeated_request_id_gets_the_first_reply_without_planning_again(planner):
    from swim_interfaces.srv import RequestManeuver
    node, client, executor = planner
    service = next(s for s in node.services if s.srv_name.endswith("request_maneuver"))
    original, lost = service.send_response, []
    service.send_response = lambda response, header: lost.append(response) if not lost else original(response, header)
    plans, published = counted(node, "plan"), counted(node.plan_publisher, "publish")
    request = RequestManeuver.Request(primitive_ids=SEQUENCE[0], repeat_counts=SEQUENCE[1], time_scale=1.2,
                                      request_id=new_request_id())
    reply = call_service(executor, client.create_client(RequestManeuver, "request_maneuver"), request, QUICK)
    assert reply.success and len(lost) == 1
    assert len(plans) == 1 and len(published) == 1
    assert list(reply.plan.time_from_start_s) == list(lost[0].plan.time_from_start_s)
    assert reply.plan.header.stamp == lost[0].plan.header.stamp          # the same reply, not a new plan
    # a new id plans again; no id plans every time
    call_service(executor, client.create_client(RequestManeuver, "request_maneuver"),
                 RequestManeuver.Request(primitive_ids=SEQUENCE[0], repeat_counts=SEQUENCE[1],
                                         request_id=new_request_id()), QUICK)
    assert len(plans) == 2


def test_answer_memory_keeps_the_latest_and_waits_for_a_reply_in_progress():
    from swim_planner.planner_node import AnswerMemory
    memory = AnswerMemory(size=2)
    first, done, box = memory.claim("a")
    assert first and not done.is_set()
    again = memory.claim("a")
    assert again[0] is False and again[1] is done
    threading.Timer(0.2, memory.answer, (done, box, "reply a")).start()
    assert again[1].wait(5.0) and again[2] == ["reply a"]
    memory.claim("b")
    memory.claim("c")                       # "a" is the oldest of three: forgotten
    assert memory.claim("a")[0] is True


@pytest.mark.parametrize("fields, message", [
    (dict(primitive_ids=SEQUENCE[0], repeat_counts=[1, 4_000_000_000, 1]), "longer than the longest plan"),
    (dict(primitive_ids=SEQUENCE[0], repeat_counts=[1, 100_000, 1]), "longer than the longest plan"),
    (dict(primitive_ids=SEQUENCE[0], repeat_counts=SEQUENCE[1], start_alpha_rad=float("nan")), "start alpha"),
    (dict(primitive_ids=SEQUENCE[0], repeat_counts=SEQUENCE[1], start_alpha_rad=1e300), "start alpha"),
    (dict(mode=1, goal_state="constrained/rest", goal_alpha_rad=float("nan")), "must be finite"),
    (dict(mode=1, goal_state="constrained/rest", goal_alpha_rad=1e12), "longer than the longest plan"),
    (dict(mode=1, goal_state="constrained/rest", goal_alpha_rad=3.0, time_scale=float("inf")), "time scale"),
])
def test_requests_past_a_bound_are_refused_at_once_and_the_node_serves_on(planner, fields, message):
    import time

    from swim_interfaces.srv import RequestManeuver
    node, client, executor = planner
    service = client.create_client(RequestManeuver, "request_maneuver")
    plans = counted(node, "_answer")
    start = time.monotonic()
    reply = call_service(executor, service, RequestManeuver.Request(request_id=new_request_id(), **fields), QUICK)
    assert not reply.success and message in reply.message, reply.message
    assert time.monotonic() - start < QUICK.attempt_timeout_s and len(plans) == 1   # answered on the first try
    good = call_service(executor, service, RequestManeuver.Request(primitive_ids=SEQUENCE[0],
                                                                   repeat_counts=SEQUENCE[1]), QUICK)
    assert good.success


def test_plan_bounds_are_parameters_checked_on_set(planner):
    from rclpy.parameter import Parameter

    from swim_ros.calls import ParameterCalls
    node, client, executor = planner
    parameters = ParameterCalls(client, executor, "planner_node", QUICK)
    assert not parameters.set([Parameter("max_plan_duration_s", value=-1.0)])[0].successful
    assert node.bounds.max_duration_s == 7200.0
    assert parameters.set([Parameter("max_plan_duration_s", value=10.0)])[0].successful
    assert node.bounds.max_duration_s == 10.0


@pytest.mark.parametrize("name, value, reason", [
    ("library_path", "/elsewhere", "read-only"), ("rig_path", "/elsewhere", "read-only"),
    ("max_plan_samples", 0, "out of range"), ("default_time_scale", float("nan"), "out of range"),
    ("max_plan_duration_s", 0.0, "above zero")])
def test_parameters_follow_their_table(planner, name, value, reason):
    from rclpy.parameter import Parameter

    from swim_planner.planner_node import PARAMETERS
    from swim_ros.calls import ParameterCalls
    node, client, executor = planner
    parameters = ParameterCalls(client, executor, "planner_node", QUICK)
    before = parameters.get([name])[0]
    result = parameters.set([Parameter(name, value=value)])[0]
    assert not result.successful and reason in result.reason.lower().replace("read only", "read-only")
    assert parameters.get([name])[0] == before
    described = {d.name: d for d in parameters.describe([spec.name for spec in PARAMETERS])}
    assert described["library_path"].read_only and described["max_plan_samples"].integer_range


def _planner_with(*overrides: str):
    """A PlannerNode started with ``name:=value`` parameter overrides, or the exception its start raised."""
    import rclpy

    from swim_planner.planner_node import PlannerNode
    from swim_ros.domains import claim_ros_domain
    claim_ros_domain()
    rclpy.init(args=["--ros-args", *[a for o in overrides for a in ("-p", o)]])
    try:
        return PlannerNode()
    except Exception as err:   # the tests assert on its type and message
        return err


@pytest.mark.parametrize("overrides, error, message", [
    (("flow_model:=circulatory", f"library_path:={__import__('swim_planner.paths').paths.default_library_path()}"),
     "LibraryError", "holds primitives of the ideal flow model, not the circulatory one"),
    (("flow_model:=viscous",), "ValueError", "flow_model must be one of 'ideal', 'circulatory'"),
])
def test_a_library_of_another_flow_model_stops_the_planner_at_start(overrides, error, message):
    import rclpy
    try:
        started = _planner_with(*overrides)
        assert type(started).__name__ == error and message in str(started)
    finally:
        rclpy.shutdown()


def test_the_circulatory_planner_serves_plans_of_its_flow_model():
    import rclpy
    from swim_interfaces.srv import RequestManeuver

    from swim_ros.trajectory_messages import trajectory_from_message
    try:
        node = _planner_with("flow_model:=circulatory")
        assert node.library.flow_model == "circulatory"
        response = node.on_request(RequestManeuver.Request(primitive_ids=SEQUENCE[0], repeat_counts=SEQUENCE[1]),
                                   RequestManeuver.Response())
        assert response.success, response.message
        plan = trajectory_from_message(response.plan)
        assert plan.flow_model == "circulatory" and plan.lag.shape == (len(plan.time_s), 2)
        node.destroy_node()
    finally:
        rclpy.shutdown()
