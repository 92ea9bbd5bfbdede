"""Requests that survive a lost answer: services, parameters, lifecycle transitions and action goals.

Fast DDS drops a service response sent before the server has matched the client's response reader
(ros2/rmw_fastrtps#706, ros2/ros2#1017), and ``wait_for_service`` proves only the request side. So a request
whose answer does not come within its attempt's deadline is sent again, a bounded number of times, and the
first answer of any attempt is taken. A request is repeated as it is only when acting on it twice is harmless:

- idempotent services (sim_node's reset and set_state, parameter gets and sets, an action's result and cancel
  requests) are repeated as they are;
- a maneuver request carries a request id, and planner_node answers a repeated id with the plan it made;
- an action goal is repeated with the same goal id; rclpy's action server refuses a goal id it already has
  without starting it again, and the action's status topic (transient local) tells whether that id was accepted;
- a lifecycle transition is repeated only after reading the node's current state (it may have happened).

Actions go through ``ActionClient``, rclpy's with a lock that keeps an executor thread from taking an answer
before its request is filed.

A call that finally fails raises ``CallFailed``, which says which service, how many tries and how long.
All functions spin the given executor while they wait, so the caller's other callbacks keep running. A caller that
runs inside a callback of a multi-threaded executor, whose other threads serve the answers, passes a
``ServedElsewhere`` instead: it only waits.
"""
from __future__ import annotations

import dataclasses
import threading
import time
import uuid
import weakref
from typing import Any, Callable, Optional, Protocol, Sequence

from rclpy.action import ActionClient as RclpyActionClient
from rclpy.client import Client
from rclpy.node import Node
from rclpy.task import Future

#: how long one spin of the caller's executor may block while waiting (s): short, so deadlines are kept
SPIN_SLICE_S = 0.05


class Spinner(Protocol):
    """What these functions need of an executor: serve callbacks for at most timeout_sec."""

    def spin_once(self, timeout_sec: Optional[float] = None) -> None:
        """Serve callbacks for at most timeout_sec (s; None: until one is served)."""


class ServedElsewhere:
    """A Spinner for a caller inside a callback of a multi-threaded executor.

    The executor's other threads serve the answers, so waiting is sleeping, poll_s at a time (the answer is seen at most
    poll_s late).
    """

    def __init__(self, poll_s: float = 0.001) -> None:
        if not poll_s > 0.0:
            raise ValueError(f"poll_s must be > 0, got {poll_s!r}")
        self.poll_s = poll_s

    def spin_once(self, timeout_sec: Optional[float] = None) -> None:
        """Sleep poll_s, or timeout_sec if shorter (s): the other threads serve the answers."""
        time.sleep(self.poll_s if timeout_sec is None else min(self.poll_s, max(timeout_sec, 0.0)))


class CallFailed(RuntimeError):
    """No answer: names the service, the tries made and the time spent."""

    def __init__(self, service: str, tries: int, elapsed_s: float, detail: str = "") -> None:
        self.service, self.tries, self.elapsed_s = service, tries, elapsed_s
        super().__init__(f"no answer from {service} to {tries} tr{'y' if tries == 1 else 'ies'} in "
                         f"{elapsed_s:.1f} s{': ' + detail if detail else ''}")


@dataclasses.dataclass(frozen=True)
class RetryPolicy:
    """How long to wait and how often to ask again.

    The defaults are assumed: a lost answer is a start-up event (discovery), so three tries of 10 s cover a
    loaded 2-core host; a server that is merely slow (a new primitive's gains, 0.1-0.3 s) answers well within
    one try.
    """

    attempt_timeout_s: float = 10.0    # one try's wait for an answer, s
    attempts: int = 3                  # tries before CallFailed
    discovery_timeout_s: float = 30.0  # wait for the service to appear at all, s

    def __post_init__(self) -> None:
        """ValueError unless the try timeout is positive, attempts at least 1 and the discovery timeout not negative."""
        if not (self.attempt_timeout_s > 0.0 and self.attempts >= 1 and self.discovery_timeout_s >= 0.0):
            raise ValueError(f"not a valid retry policy: {self}")


DEFAULT_POLICY = RetryPolicy()


def spin_until(executor: Spinner, done: Callable[[], bool], timeout_s: float) -> bool:
    """Spin executor until done() holds (True) or timeout_s has passed (False)."""
    deadline = time.monotonic() + timeout_s
    while not done():
        remaining = deadline - time.monotonic()
        if remaining <= 0.0:
            return False
        executor.spin_once(timeout_sec=min(SPIN_SLICE_S, remaining))
    return True


def wait_for_server(executor: Spinner, ready: Callable[[], bool], name: str, timeout_s: float) -> None:
    """Spin until ready() (a service or action server is discovered); CallFailed after timeout_s."""
    start = time.monotonic()
    if not spin_until(executor, ready, timeout_s):
        raise CallFailed(name, 0, time.monotonic() - start, "the server never appeared")


def repeat_until_answered(executor: Spinner, send: Callable[[], Future], name: str,
                          policy: RetryPolicy = DEFAULT_POLICY,
                          cancel: Optional[Callable[[Future], None]] = None) -> Any:
    """send() up to policy.attempts times, each time the answers so far are overdue; the first answer of any try.

    send must be safe to repeat (see the module docstring). cancel(future) forgets a try that did not answer.
    """
    start = time.monotonic()
    futures: list[Future] = []
    try:
        for _ in range(policy.attempts):
            futures.append(send())
            if spin_until(executor, lambda: any(f.done() for f in futures), policy.attempt_timeout_s):
                return next(f for f in futures if f.done()).result()
        raise CallFailed(name, len(futures), time.monotonic() - start)
    finally:
        for future in futures:
            if not future.done() and cancel is not None:
                cancel(future)


def call_service(executor: Spinner, client: Client, request: Any, policy: RetryPolicy = DEFAULT_POLICY) -> Any:
    """The service's response to an idempotent request (or one made so by a request id)."""
    wait_for_server(executor, client.service_is_ready, client.srv_name, policy.discovery_timeout_s)
    return repeat_until_answered(executor, lambda: client.call_async(request), client.srv_name, policy,
                                 client.remove_pending_request)


def new_request_id() -> str:
    """A request id for a request a server must not act on twice (a maneuver request)."""
    return uuid.uuid4().hex


# ----- parameters ---------------------------------------------------------------------------------------------
class ParameterCalls:
    """get, set and describe another node's parameters (all idempotent), as rcl_interfaces' services."""

    def __init__(self, node: Node, executor: Spinner, target_node: str,
                 policy: RetryPolicy = DEFAULT_POLICY) -> None:
        from rcl_interfaces.srv import DescribeParameters, GetParameters, SetParameters
        prefix = target_node if target_node.startswith("/") else f"/{target_node}"
        self.executor, self.policy = executor, policy
        self._get = node.create_client(GetParameters, f"{prefix}/get_parameters")
        self._set = node.create_client(SetParameters, f"{prefix}/set_parameters")
        self._describe = node.create_client(DescribeParameters, f"{prefix}/describe_parameters")

    def set(self, parameters: Sequence[Any]) -> list[Any]:
        """Set the rclpy Parameters given: one rcl_interfaces/SetParametersResult per parameter, in order."""
        from rcl_interfaces.srv import SetParameters
        request = SetParameters.Request(parameters=[p.to_parameter_msg() for p in parameters])
        return list(call_service(self.executor, self._set, request, self.policy).results)

    def get(self, names: Sequence[str]) -> list[Any]:
        """Parameter names -> their values as Python values (rclpy's parameter_value_to_python)."""
        from rcl_interfaces.srv import GetParameters
        from rclpy.parameter import parameter_value_to_python
        response = call_service(self.executor, self._get, GetParameters.Request(names=list(names)), self.policy)
        return [parameter_value_to_python(value) for value in response.values]

    def describe(self, names: Sequence[str]) -> list[Any]:
        """Parameter names -> their rcl_interfaces/ParameterDescriptor (description, ranges, read_only)."""
        from rcl_interfaces.srv import DescribeParameters
        request = DescribeParameters.Request(names=list(names))
        return list(call_service(self.executor, self._describe, request, self.policy).descriptors)


# ----- lifecycle ----------------------------------------------------------------------------------------------
def transition_goal_state(transition_id: int) -> int:
    """The primary state a successful lifecycle transition (lifecycle_msgs/Transition id) ends in."""
    from lifecycle_msgs.msg import State, Transition
    goals = {Transition.TRANSITION_CONFIGURE: State.PRIMARY_STATE_INACTIVE,
             Transition.TRANSITION_CLEANUP: State.PRIMARY_STATE_UNCONFIGURED,
             Transition.TRANSITION_ACTIVATE: State.PRIMARY_STATE_ACTIVE,
             Transition.TRANSITION_DEACTIVATE: State.PRIMARY_STATE_INACTIVE,
             Transition.TRANSITION_UNCONFIGURED_SHUTDOWN: State.PRIMARY_STATE_FINALIZED,
             Transition.TRANSITION_INACTIVE_SHUTDOWN: State.PRIMARY_STATE_FINALIZED,
             Transition.TRANSITION_ACTIVE_SHUTDOWN: State.PRIMARY_STATE_FINALIZED}
    if transition_id not in goals:
        raise ValueError(f"{transition_id} is not a transition a client can ask for")
    return goals[transition_id]


def change_lifecycle_state(node: Node, executor: Spinner, target_node: str, transition_id: int,
                           policy: RetryPolicy = DEFAULT_POLICY) -> bool:
    """Ask target_node for a lifecycle transition.

    True when it succeeded, False if the node refused it or it failed.

    A transition is not idempotent (configure twice fails the second time), so it is sent again only after
    get_state shows it did not happen: a node found in the transition's goal state has made it.
    """
    from lifecycle_msgs.msg import Transition
    from lifecycle_msgs.srv import ChangeState, GetState
    goal_state_id = transition_goal_state(transition_id)
    prefix = target_node if target_node.startswith("/") else f"/{target_node}"
    get_state = node.create_client(GetState, f"{prefix}/get_state")
    change_state = node.create_client(ChangeState, f"{prefix}/change_state")
    start, tries = time.monotonic(), 0
    try:
        wait_for_server(executor, change_state.service_is_ready, change_state.srv_name, policy.discovery_timeout_s)
        for attempt in range(policy.attempts):
            if attempt > 0 and \
                    call_service(executor, get_state, GetState.Request(), policy).current_state.id == goal_state_id:
                return True     # the transition was made; its answer was lost
            tries += 1
            future = change_state.call_async(ChangeState.Request(transition=Transition(id=transition_id)))
            if spin_until(executor, future.done, policy.attempt_timeout_s):
                return bool(future.result().success)
            change_state.remove_pending_request(future)
        raise CallFailed(change_state.srv_name, tries, time.monotonic() - start)
    finally:
        node.destroy_client(get_state)
        node.destroy_client(change_state)


# ----- actions ------------------------------------------------------------------------------------------------
class ActionClient(RclpyActionClient):
    """rclpy's ActionClient whose requests are filed before their answers can be taken.

    rclpy 7.1.6 sends a goal, cancel or result request first and files the request's future after. An executor
    thread that takes the answer in between either drops it as unexpected (the future never completes) or
    completes the future before its done callback is set; that callback then runs in the caller and raises
    ``ValueError: list.remove(x): x not in list``. One lock over sending and filing, and over taking answers, closes
    both (ros2/rclpy#1123; upstream rclpy takes the same lock, ros2/rclpy#1519).
    Constructed and used as rclpy's.
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        # before rclpy's constructor, which hands the client to the executors that call take_data
        self._request_lock = threading.Lock()
        super().__init__(*args, **kwargs)

    def take_data(self) -> Any:
        """The answers, feedback and statuses ready, taken only while no request is being sent and filed."""
        with self._request_lock:
            return super().take_data()

    def send_goal_async(self, goal: Any, feedback_callback: Optional[Callable[[Any], None]] = None,
                        goal_uuid: Any = None) -> Future:
        """The goal's acceptance future (as rclpy's send_goal_async), its request sent and filed under the lock."""
        with self._request_lock:
            return super().send_goal_async(goal, feedback_callback=feedback_callback, goal_uuid=goal_uuid)

    def _cancel_goal_async(self, goal_handle: Any) -> Future:
        """The cancel's answer future (as rclpy's), its request sent and filed under the lock."""
        with self._request_lock:
            return super()._cancel_goal_async(goal_handle)

    def _get_result_async(self, goal_handle: Any) -> Future:
        """The result's future (as rclpy's), its request sent and filed under the lock."""
        with self._request_lock:
            return super()._get_result_async(goal_handle)


class GoalStatusWatch:
    """The latest goal statuses an action server published (its status topic is transient local)."""

    def __init__(self, node: Node, action_name: str) -> None:
        from action_msgs.msg import GoalStatusArray
        from rclpy.action.client import qos_profile_action_status_default
        self.statuses: dict[bytes, int] = {}
        self._subscription = node.create_subscription(
            GoalStatusArray, f"{action_name}/_action/status", self._on_status, qos_profile_action_status_default)

    def _on_status(self, message: Any) -> None:
        self.statuses = {bytes(s.goal_info.goal_id.uuid): s.status for s in message.status_list}


def send_goal(executor: Spinner, action_client: Any, goal: Any, status: GoalStatusWatch,
              feedback_callback: Optional[Callable[[Any], None]] = None,
              policy: RetryPolicy = DEFAULT_POLICY) -> Any:
    """Send an action goal; the accepted goal's ClientGoalHandle, or the refusal's (handle.accepted False).

    A goal whose answer is overdue is sent again with the same goal id. The server refuses an id it already
    has without starting it again; if the status topic then lists the id, the first try was accepted and its
    handle is made here, so the caller can follow it as any other.
    """
    from action_msgs.msg import GoalStatus
    from rclpy.action.client import ClientGoalHandle
    from unique_identifier_msgs.msg import UUID
    wait_for_server(executor, action_client.server_is_ready, action_client._action_name,
                    policy.discovery_timeout_s)
    goal_id = UUID(uuid=list(uuid.uuid4().bytes))
    tries = 0

    def send() -> Future:
        nonlocal tries
        tries += 1
        return action_client.send_goal_async(goal, feedback_callback=feedback_callback, goal_uuid=goal_id)
    handle = repeat_until_answered(executor, send, f"{action_client._action_name} (send goal)", policy)
    if handle.accepted or tries == 1:
        return handle
    # a repeat refused: was the goal id accepted by an earlier try whose answer was lost?
    known = bytes(goal_id.uuid)
    spin_until(executor, lambda: known in status.statuses, policy.attempt_timeout_s)
    if status.statuses.get(known, GoalStatus.STATUS_UNKNOWN) == GoalStatus.STATUS_UNKNOWN:
        return handle
    response = action_client._action_type.Impl.SendGoalService.Response(accepted=True)
    recovered = ClientGoalHandle(action_client, goal_id, response)
    # rclpy follows a goal's status and result through weak references to its handles, by goal id
    action_client._goal_handles[known] = weakref.ref(recovered)
    return recovered


def goal_result(executor: Spinner, handle: Any, timeout_s: float, resend_after_s: float = 10.0) -> Any:
    """The goal's result (the action's GetResult response); CallFailed after timeout_s.

    While none came, it asks again every resend_after_s (a result request is idempotent).
    """
    tries = max(1, int(timeout_s // resend_after_s))
    policy = RetryPolicy(attempt_timeout_s=timeout_s / tries, attempts=tries, discovery_timeout_s=0.0)
    return repeat_until_answered(executor, handle.get_result_async, "goal result", policy)


def cancel_goal(executor: Spinner, handle: Any, policy: RetryPolicy = DEFAULT_POLICY) -> Any:
    """Cancel an accepted goal (idempotent: a goal already canceling or ended is answered so)."""
    return repeat_until_answered(executor, handle.cancel_goal_async, "cancel goal", policy)
