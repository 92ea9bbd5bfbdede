"""The client side of a run over DDS: ask the planner for a maneuver, have the tracker execute it, record the run.

RunClient owns an rclpy context of its own (so a process can hold several, one after another), a node with
the planner's service client and the tracker's action client, and a rosbag2 MCAP bag (bag.BagWriter) with one raw
subscription per recorded topic: messages go into the bag as the CDR bytes received, stamped with the wall time
of receipt, under the topic's fully qualified name (bag.RUN_TOPICS: /joint_states, as rosbag2 records it).
swim-demo uses it for a whole maneuver; the kill-a-node tests use it to stop a node mid-run.
"""
from __future__ import annotations

import struct
import time
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Optional, Sequence

from swim_bringup.bag import LATCHED_TOPICS, RUN_TOPICS, BagWriter
from swim_bringup.recorder import RECORD_DEPTH, TopicRecorder
from swim_controller.supervisor import Tolerances
from swim_ros.calls import (
    CallFailed,
    GoalStatusWatch,
    RetryPolicy,
    call_service,
    goal_result,
    new_request_id,
    send_goal,
    spin_until,
    wait_for_server,
)

if TYPE_CHECKING:
    from rclpy.subscription import Subscription

STARTUP_TIMEOUT_S = 60.0
#: a maneuver request: a plan of primitives whose gains are new takes 0.1-0.3 s each, so 20 s a try is generous;
#: a repeat carries the same request id, so the planner never plans twice
PLANNER_POLICY = RetryPolicy(attempt_timeout_s=20.0, attempts=3, discovery_timeout_s=STARTUP_TIMEOUT_S)
DRAIN_TIMEOUT_S = 60.0
#: a bridge reports its I/O loop on /diagnostics at diagnostics_rate_hz (2 Hz in config/bridge.yaml): the recording
#: waits this long past the plan's last period for the report that follows it, so that a run's bridge figures
#: (overruns, worst lateness) cover its whole length, its last half second included
BRIDGE_REPORT_WAIT_S = 2.0
#: published every period by the nodes of a run (keys of RUN_TOPICS)
LOOP_TOPICS = ("/joint_states", "/joint_commands", "/tracking_state")
#: ... these also before a plan (plant and idle tracker)
IDLE_LOOP_TOPICS = ("/joint_states", "/joint_commands")


class RunError(RuntimeError):
    """The run could not be done (a node did not start or died, the planner refused, ...)."""


class NodeDied(RunError):
    """Nodes of the run died.

    Parameters
    ----------
    nodes : sequence of str
        The dead nodes' executables.
    logs : Path
        Where their logs are.
    cause : str, optional
        What the run met first, when that was not the death itself.

    Attributes
    ----------
    nodes : tuple of str
        The dead nodes' executables.
    """

    def __init__(self, nodes: Sequence[str], logs: Path, cause: str = "") -> None:
        died = f"{', '.join(nodes)} died (see {logs})"
        super().__init__(f"{cause}; {died}" if cause else died)
        self.nodes = tuple(nodes)


class RunClient:
    """Planner and tracker clients plus a recorder of topics into a bag.

    Planner and tracker clients plus a recorder of topics (fully qualified name -> type name) into the bag at
    bag_path. ValueError for a relative name: the client's waits look the loop's topics up by LOOP_TOPICS' names.
    """

    def __init__(self, bag_path: Path, topics: dict[str, str] = RUN_TOPICS) -> None:
        relative = [topic for topic in topics if not topic.startswith("/")]
        if relative:
            raise ValueError(f"RunClient records topics under their full names (/joint_states), not: "
                             f"{', '.join(relative)}")
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from swim_interfaces.action import ExecutePlan
        from swim_interfaces.srv import RequestManeuver

        from swim_ros.calls import ActionClient
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self._closed = False
        self.bag: Optional[BagWriter] = None
        try:
            self.node = rclpy.create_node("swim_run_client", context=self.context)
            self.executor = SingleThreadedExecutor(context=self.context)
            self.executor.add_node(self.node)
            self.bag = BagWriter(bag_path, topics)
            self.recorder = TopicRecorder(self.node, self.bag)
            self.latest_cdr: dict[str, bytes] = self.recorder.latest_cdr   # topic -> the latest message recorded
            self.recordings: dict[str, Subscription] = self.recorder.subscriptions   # topic -> its subscription
            # the idle loop's topics last: a publisher learns of a process's readers in the order they were made,
            # so a first message on them (wait_for_nodes) shows the others were matched too
            for topic in sorted(topics, key=lambda t: t in IDLE_LOOP_TOPICS):
                self._record(topic, topics[topic])
            self.planner = self.node.create_client(RequestManeuver, "request_maneuver")
            self.tracker = ActionClient(self.node, ExecutePlan, "execute_plan")
            self.goal_status = GoalStatusWatch(self.node, "execute_plan")
        except BaseException:
            self.close()
            raise

    def _record(self, topic: str, type_name: str) -> None:
        from rclpy.qos import QoSDurabilityPolicy, QoSProfile
        # a latched topic (transient local) reaches a late subscriber too
        qos = QoSProfile(depth=1, durability=QoSDurabilityPolicy.TRANSIENT_LOCAL) if topic in LATCHED_TOPICS \
            else RECORD_DEPTH
        self.recorder.record(topic, type_name, qos)

    @property
    def last_plan_time_s(self) -> float:
        """Plan time of the latest tracking_state recorded (-1 before the first)."""
        from rclpy.serialization import deserialize_message
        from swim_interfaces.msg import TrackingState
        cdr = self.latest_cdr.get("/tracking_state")
        return -1.0 if cdr is None else deserialize_message(cdr, TrackingState).plan_time_s

    def __enter__(self) -> "RunClient":
        """The client, closed on leaving the block."""
        return self

    def __exit__(self, *exc) -> None:
        """Close the client."""
        self.close()

    def close(self) -> None:
        """Finish the bag and leave DDS; safe to call twice.

        The node and its subscriptions are destroyed here, not left to the garbage collector: a closed client's readers
        would stay matched, and every publisher of the next run on the domain would keep sending them each period
        (docs/benchmarks.md, bench_record).
        """
        import rclpy
        if self.bag is not None:
            self.bag.close()
        if self._closed:
            return
        self._closed = True
        if hasattr(self, "executor"):
            self.executor.shutdown()
        if hasattr(self, "node"):
            self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)
        self.context.destroy()

    # --- waiting -------------------------------------------------------------------------------------------
    def spin_until(self, done: Callable[[], bool], timeout_s: float, what: str = "an answer") -> None:
        """Serve callbacks (recording included) until done() holds; RunError after timeout_s."""
        if not spin_until(self.executor, done, timeout_s):
            raise RunError(f"no {what} within {timeout_s:.0f} s")

    def wait_for(self, future, timeout_s: float, what: str = "an answer"):
        """The future's result, serving callbacks meanwhile."""
        self.spin_until(future.done, timeout_s, what)
        return future.result()

    def spin_for(self, seconds: float) -> None:
        """Serve callbacks (keep recording) for seconds of wall time."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.executor.spin_once(timeout_sec=min(0.01, max(end - time.monotonic(), 0.0)))

    # --- the run -------------------------------------------------------------------------------------------
    def wait_for_nodes(self, timeout_s: float = STARTUP_TIMEOUT_S, first_messages: Sequence[str] = ()) -> None:
        """Wait for the planner, the tracker and the loop's topics to be matched; RunError after timeout_s.

        first_messages: recorded topics whose first message must have come too (a node that publishes them while
        the loop idles is among the run's nodes: rig_state_publisher's /tf).
        """
        try:
            wait_for_server(self.executor, self.planner.service_is_ready, "planner_node", timeout_s)
            wait_for_server(self.executor, self.tracker.server_is_ready, "tracker_node", timeout_s)
        except CallFailed as err:
            raise RunError(f"{err.service} did not come up within {timeout_s:.0f} s") from err
        # discovery matches each topic on its own, and each side of it on its own: a recorder that has seen a
        # publisher may not yet be seen by it, and a volatile writer sends nothing to a reader it has not matched
        # (a bridge run's bag once lacked the first 56 ms of joint_states). A first message received proves the
        # writer's side; tracking_state has none before the plan, but the tracker that sent joint_commands to
        # this recorder already knew its tracking_state reader (made before, see __init__).
        awaited = tuple(topic for topic in (*IDLE_LOOP_TOPICS, *first_messages) if topic in self.recordings)

        def unmatched() -> list[str]:
            return [topic for topic in LOOP_TOPICS if topic in self.recordings
                    and self.recordings[topic].get_publisher_count() == 0] \
                + [topic for topic in awaited if topic not in self.latest_cdr]
        self.spin_until(lambda: not unmatched(), timeout_s,
                        f"publisher on each of {', '.join(LOOP_TOPICS)} and a first message on {', '.join(awaited)}")

    def request(self, primitive_ids: list[str], repeat_counts: list[int], time_scale: float):
        """The planner's plan (swim_interfaces/PlannedTrajectory) for the sequence; RunError if refused."""
        from swim_interfaces.srv import RequestManeuver
        request = RequestManeuver.Request(primitive_ids=primitive_ids, repeat_counts=repeat_counts,
                                          time_scale=time_scale, request_id=new_request_id())
        try:
            reply = call_service(self.executor, self.planner, request, PLANNER_POLICY)
        except CallFailed as err:
            raise RunError(str(err)) from err
        if not reply.success:
            raise RunError(f"the planner refused the maneuver: {reply.message}")
        return reply.plan

    def execute(self, plan, progress: Optional[Callable[[float], None]] = None,
                tolerances: Optional[Tolerances] = None):
        """Send the plan to the tracker; the accepted goal's handle.

        Send the plan to the tracker with tolerances (default: none checked); returns the accepted goal's
        handle (RunError if refused).
        """
        from swim_interfaces.action import ExecutePlan
        goal = ExecutePlan.Goal(plan=plan)
        if tolerances is not None:
            goal.path_tolerance_alpha_rad, goal.path_tolerance_r_m = tolerances.path_alpha_rad, tolerances.path_r_m
            goal.goal_tolerance_alpha_rad, goal.goal_tolerance_r_m = tolerances.goal_alpha_rad, tolerances.goal_r_m

        def on_feedback(message) -> None:
            if progress is not None:
                progress(message.feedback.progress)
        try:
            handle = send_goal(self.executor, self.tracker, goal, self.goal_status, on_feedback)
        except CallFailed as err:
            raise RunError(str(err)) from err
        if not handle.accepted:
            raise RunError("the tracker refused the goal")
        return handle

    def result(self, handle, timeout_s: float):
        """The accepted goal's result (ExecutePlan.Result) within timeout_s, or RunError."""
        try:
            return goal_result(self.executor, handle, timeout_s).result
        except CallFailed as err:
            raise RunError(f"no end of the maneuver within {timeout_s:.0f} s") from err

    def drain(self, duration_s: float) -> None:
        """Record until the plan's last period and the plan are in the bag.

        Record until the plan's last period (plan time duration_s) is in the bag on every loop topic, and the
        plan itself, then a few more periods. The recorder may lag a faster-than-real-time loop, and by more on
        joint_states and joint_commands, which flowed (and queued) before the plan while tracking_state did not.
        RunError if that does not happen within DRAIN_TIMEOUT_S. Where a bridge reports on /diagnostics, then
        until its first report stamped after that period, for at most BRIDGE_REPORT_WAIT_S (a bridge that stopped
        reporting leaves its last report the run's).
        """
        deadline = time.monotonic() + DRAIN_TIMEOUT_S
        final_stamp_ns, checked = None, None
        while not self._recorded_up_to(final_stamp_ns):
            if time.monotonic() > deadline:
                raise RunError(f"the recorder did not get the plan's last period within {DRAIN_TIMEOUT_S:.0f} s "
                               f"({self._recording_status(final_stamp_ns)})")
            self.executor.spin_once(timeout_sec=0.05)
            latest = self.latest_cdr.get("/tracking_state")
            # deserialize each tracking_state once
            if final_stamp_ns is None and latest is not None and latest is not checked:
                checked = latest
                if self.last_plan_time_s >= duration_s - 1e-6:
                    final_stamp_ns = header_stamp_ns(latest)
        for _ in range(20):   # a few periods of the hold after it
            self.executor.spin_once(timeout_sec=0.01)
        if "/diagnostics" in self.latest_cdr:
            assert final_stamp_ns is not None   # the loop above ends only with it
            deadline = time.monotonic() + BRIDGE_REPORT_WAIT_S
            while header_stamp_ns(self.latest_cdr["/diagnostics"]) < final_stamp_ns and time.monotonic() < deadline:
                self.executor.spin_once(timeout_sec=0.05)

    def _recorded_up_to(self, stamp_ns: Optional[int]) -> bool:
        """Whether every loop topic is recorded up to stamp_ns and the plan is recorded.

        Every loop topic recorded up to stamp_ns, and the plan recorded: a plan of thousands of samples goes out
        in fragments, and one lost beside a fast loop is repaired only at the writer's next heartbeat.
        """
        return stamp_ns is not None and ("/plan" not in self.recordings or "/plan" in self.latest_cdr) and all(
            topic in self.latest_cdr and header_stamp_ns(self.latest_cdr[topic]) >= stamp_ns
            for topic in LOOP_TOPICS if topic in self.recordings)

    def _recording_status(self, final_stamp_ns: Optional[int]) -> str:
        latest = {topic: header_stamp_ns(cdr) * 1e-9 for topic, cdr in self.latest_cdr.items() if topic in LOOP_TOPICS}
        return (f"last period {'not seen' if final_stamp_ns is None else f'{final_stamp_ns * 1e-9:.3f} s'}, "
                f"latest stamps {', '.join(f'{t} {v:.3f} s' for t, v in latest.items())}, "
                f"plan {'recorded' if '/plan' in self.latest_cdr else 'missing'}")


def header_stamp_ns(cdr: bytes) -> int:
    """The header stamp, ns, of a serialized message that starts with a std_msgs/Header.

    In CDR: a 4-byte encapsulation header, its second byte 1 for little-endian, then the stamp's int32 sec and uint32
    nanosec.
    """
    sec, nanosec = struct.unpack_from("<iI" if cdr[1] == 1 else ">iI", cdr, 4)
    return sec * 1_000_000_000 + nanosec
