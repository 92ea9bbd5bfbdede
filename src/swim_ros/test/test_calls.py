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
    ServedElsewhere,
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
    from rclpy.action import ActionServer
    from swim_interfaces.action import ExecutePlan

    from swim_ros.calls import ActionClient
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


class _SlowFiling(dict):
    """A table of pending action requests that pauses the caller's thread at one point of filing a request.

    rclpy's ActionClient tests the table for the new sequence number right after sending the request
    ("sent"), then stores the future ("filed") and only then sets its done callback: in either pause an
    executor thread can take the request's answer.
    """

    def __init__(self, caller, where, pause_s):
        super().__init__()
        self.caller, self.where, self.pause_s = caller, where, pause_s

    def _pause(self, where):
        if self.where == where and threading.current_thread() is self.caller:
            time.sleep(self.pause_s)

    def __contains__(self, key):
        self._pause("sent")
        return super().__contains__(key)

    def __setitem__(self, key, value):
        super().__setitem__(key, value)
        self._pause("filed")


#: how long a request's filing is paused (s): long beside the server's answer on this host (milliseconds)
FILING_PAUSE_S = 0.3


@pytest.mark.parametrize("where", ["sent", "filed"])
@pytest.mark.parametrize("request_table", ["_pending_goal_requests", "_pending_result_requests"])
def test_an_answer_taken_while_its_request_is_filed_completes_the_request(rclpy_context, request_table, where):
    """A goal's acceptance or its result, answered while the caller is between sending and filing the request,
    completes the caller's future (rclpy's own client drops the answer, or raises ValueError from the result's
    filing)."""
    import rclpy
    from rclpy.action import ActionServer
    from rclpy.executors import MultiThreadedExecutor
    from swim_interfaces.action import ExecutePlan

    from swim_ros.calls import ActionClient, spin_until
    server = rclpy.create_node("filing_test_server", context=rclpy_context)
    client = rclpy.create_node("filing_test_client", context=rclpy_context)

    def execute(goal_handle):
        goal_handle.succeed()
        return ExecutePlan.Result(duration_s=goal_handle.request.goal_tolerance_alpha_rad)
    action_server = ActionServer(server, ExecutePlan, "execute_plan", execute)
    action_client = ActionClient(client, ExecutePlan, "execute_plan")
    executors = [SingleThreadedExecutor(context=rclpy_context), MultiThreadedExecutor(context=rclpy_context)]
    executors[0].add_node(server)
    executors[1].add_node(client)
    threads = [threading.Thread(target=e.spin, daemon=True) for e in executors]
    for thread in threads:
        thread.start()
    try:
        assert action_client.wait_for_server(timeout_sec=20.0)
        caller = threading.current_thread()
        setattr(action_client, request_table, _SlowFiling(caller, where, FILING_PAUSE_S))
        waiting = ServedElsewhere()
        accepted = action_client.send_goal_async(ExecutePlan.Goal(goal_tolerance_alpha_rad=0.25))
        assert spin_until(waiting, accepted.done, 10.0), "the goal's acceptance never completed its future"
        handle = accepted.result()
        assert handle.accepted
        result = handle.get_result_async()
        assert spin_until(waiting, result.done, 10.0), "the goal's result never completed its future"
        assert result.result().result.duration_s == 0.25
        # the requests' done callbacks (run by the executor after the futures complete) forget both
        assert spin_until(waiting, lambda: action_client._futures == [], 5.0)
        assert dict(action_client._pending_goal_requests) == dict(action_client._pending_result_requests) == {}
    finally:
        for executor in executors:
            executor.shutdown()
        for thread in threads:
            thread.join(timeout=5.0)
        action_server.destroy()
        action_client.destroy()
        server.destroy_node()
        client.destroy_node()
