"""Calls against servers that lose answers the way Fast DDS does: the server acts, its answer never arrives.

Each server here drops its first answer(s) on purpose (its send is replaced), or starts only after the request
was sent; the helpers must still return exactly one answer, and a request that must not act twice (a goal, a
lifecycle transition) acts once.
"""
import contextlib
import threading
import time

import pytest
from rclpy.executors import SingleThreadedExecutor

from swim_ros.calls import (
    CallFailed,
    GoalStatusWatch,
    ParameterCalls,
    RetryPolicy,
    call_service,
    change_lifecycle_state,
    goal_result,
    send_goal,
)

#: short tries: these servers answer within milliseconds when they answer at all
QUICK = RetryPolicy(attempt_timeout_s=1.0, attempts=3, discovery_timeout_s=20.0)


def drop_first_answers(service, count):
    """Replace service.send_response so its first count answers are lost (the callback still ran)."""
    original, dropped = service.send_response, []

    def send_response(response, header):
        if len(dropped) < count:
            dropped.append(response)
            return
        original(response, header)
    service.send_response = send_response
    return dropped


@contextlib.contextmanager
def served(server, client, context):
    """The client's executor (the test spins it), with a thread of its own spinning the server; both nodes
    destroyed on leaving."""
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(client)
    spinner = SingleThreadedExecutor(context=context)
    spinner.add_node(server)
    thread = threading.Thread(target=spinner.spin, daemon=True)
    thread.start()
    try:
        yield executor
    finally:
        spinner.shutdown()
        thread.join(timeout=5.0)
        server.destroy_node()
        client.destroy_node()


@pytest.fixture()
def pair(rclpy_context):
    """(server node, client node, the client's executor), the server spun by a thread of its own."""
    import rclpy
    server = rclpy.create_node("calls_test_server", context=rclpy_context)
    client = rclpy.create_node("calls_test_client", context=rclpy_context)
    with served(server, client, rclpy_context) as executor:
        yield server, client, executor


def test_a_lost_answer_is_asked_again_and_one_answer_returned(pair):
    from std_srvs.srv import Trigger
    server, client, executor = pair
    served = []

    def on_trigger(request, response):
        served.append(len(served) + 1)
        response.success, response.message = True, f"answer {len(served)}"
        return response
    dropped = drop_first_answers(server.create_service(Trigger, "idempotent", on_trigger), 1)
    start = time.monotonic()
    response = call_service(executor, client.create_client(Trigger, "idempotent"), Trigger.Request(), QUICK)
    assert response.message == "answer 2" and served == [1, 2] and len(dropped) == 1
    assert time.monotonic() - start >= QUICK.attempt_timeout_s   # the second try went out after the first's wait


def test_a_call_that_finally_fails_names_service_tries_and_time(pair):
    from std_srvs.srv import Trigger
    server, client, executor = pair
    drop_first_answers(server.create_service(Trigger, "silent", lambda request, response: response), 100)
    with pytest.raises(CallFailed, match=r"no answer from silent to 3 tries in [3-9]\.\d s") as failure:
        call_service(executor, client.create_client(Trigger, "silent"), Trigger.Request(), QUICK)
    assert failure.value.tries == 3 and failure.value.service == "silent"


def test_a_server_started_after_the_request_answers_it(pair):
    from std_srvs.srv import Trigger
    server, client, executor = pair
    served = []

    def start_late():
        time.sleep(1.5)
        server.create_service(Trigger, "late", lambda request, response: served.append(1) or response)
    threading.Thread(target=start_late, daemon=True).start()
    call_service(executor, client.create_client(Trigger, "late"), Trigger.Request(), QUICK)
    assert served == [1]


def test_parameter_set_and_get_survive_a_lost_answer(pair):
    from rclpy.parameter import Parameter
    server, client, executor = pair
    server.declare_parameter("gain", 1.0)
    drop_first_answers(_service_named(server, "/set_parameters"), 1)
    calls = ParameterCalls(client, executor, "calls_test_server", QUICK)
    results = calls.set([Parameter("gain", value=2.5)])
    assert [r.successful for r in results] == [True]
    assert calls.get(["gain"]) == [2.5]


def _service_named(node, suffix):
    return next(s for s in node.services if s.srv_name.endswith(suffix))


def test_a_lifecycle_transition_whose_answer_was_lost_is_not_repeated(rclpy_context):
    """The configure went through but its answer was lost: the helper reads the state and does not configure
    again (a second configure of a configured node would fail)."""
    import rclpy
    from lifecycle_msgs.msg import State, Transition
    from rclpy.lifecycle import Node as LifecycleNode
    from rclpy.lifecycle import TransitionCallbackReturn

    class Counting(LifecycleNode):
        configured = 0

        def on_configure(self, state):
            Counting.configured += 1
            return TransitionCallbackReturn.SUCCESS
    server = Counting("calls_test_lifecycle", context=rclpy_context)
    client = rclpy.create_node("calls_test_lifecycle_client", context=rclpy_context)
    with served(server, client, rclpy_context) as executor:
        drop_first_answers(_service_named(server, "change_state"), 1)
        assert change_lifecycle_state(client, executor, "calls_test_lifecycle", Transition.TRANSITION_CONFIGURE,
                                      QUICK)
        assert Counting.configured == 1 and server._state_machine.current_state[0] == State.PRIMARY_STATE_INACTIVE
        # a transition whose answer arrives is sent once
        assert change_lifecycle_state(client, executor, "calls_test_lifecycle", Transition.TRANSITION_ACTIVATE,
                                      QUICK)
        assert server._state_machine.current_state[0] == State.PRIMARY_STATE_ACTIVE


class _DroppingHandle:
    """An action server's handle whose first goal answer is lost (the goal is accepted and started)."""

    def __init__(self, handle):
        self._handle, self.dropped = handle, 0

    def send_goal_response(self, header, response):
        if self.dropped == 0:
            self.dropped += 1
            return
        self._handle.send_goal_response(header, response)

    def __getattr__(self, name):
        return getattr(self._handle, name)

    def __enter__(self):
        return self._handle.__enter__()

    def __exit__(self, *exc):
        return self._handle.__exit__(*exc)


def test_a_goal_whose_acceptance_was_lost_is_started_once_and_followed(pair):
    from rclpy.action import ActionClient, ActionServer
    from swim_interfaces.action import ExecutePlan
    server, client, executor = pair
    started = []

    def execute(goal_handle):
        started.append(bytes(goal_handle.goal_id.uuid))
        goal_handle.succeed()
        return ExecutePlan.Result(duration_s=goal_handle.request.goal_tolerance_alpha_rad)
    action_server = ActionServer(server, ExecutePlan, "execute_plan", execute)
    action_server._handle = dropping = _DroppingHandle(action_server._handle)
    action_client = ActionClient(client, ExecutePlan, "execute_plan")
    status = GoalStatusWatch(client, "execute_plan")
    handle = send_goal(executor, action_client, ExecutePlan.Goal(goal_tolerance_alpha_rad=0.25), status,
                       policy=QUICK)
    assert dropping.dropped == 1 and handle.accepted
    result = goal_result(executor, handle, timeout_s=10.0, resend_after_s=2.0)
    assert result.result.duration_s == 0.25
    assert started == [bytes(handle.goal_id.uuid)]             # started once, by the first try
    action_server.destroy()
    action_client.destroy()


def test_served_elsewhere_waits_for_another_thread_within_its_poll():
    """A caller inside a multi-threaded executor's callback waits by sleeping: it sees an answer set by another
    thread at most a poll late, and gives up at its deadline."""
    import threading
    import time

    from swim_ros.calls import ServedElsewhere, spin_until
    done = threading.Event()
    threading.Timer(0.05, done.set).start()
    start = time.monotonic()
    assert spin_until(ServedElsewhere(poll_s=0.01), done.is_set, 5.0)
    assert 0.05 <= time.monotonic() - start < 0.5
    start = time.monotonic()
    assert not spin_until(ServedElsewhere(poll_s=0.01), lambda: False, 0.1)
    assert 0.1 <= time.monotonic() - start < 0.5
    with pytest.raises(ValueError, match="poll_s"):
        ServedElsewhere(poll_s=0.0)
