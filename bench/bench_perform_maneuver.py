"""Benchmark: a perform_maneuver goal from its acceptance to the first tracked period (target <= 100 ms median).

Brings up the realistic pipeline's simulator set in real time (so that the loop leaves the other nodes their share
of the 2 cores, as a rig does) with maneuver_node (swim_bringup.system, each node in its own process, a ROS domain of
its own), flies one goal to have the tracker build its vehicle model, then sends RUNS goals of the 20-primitive
maneuver {accelerate, cruise x18, decelerate} (constrained, E = 0.05), each canceled once tracked and the simulator
reset (sim_node's reset); the next is sent once the vehicle is at rest again (the tracker's hold brings the foil
back). For each: from the goal's acceptance (its answer at this client) to the first tracking_state of its plan
received here. That span holds maneuver_node's checks, the primitive list, the plan requested of planner_node and
sent on to tracker_node, and its first period. Prints one JSON line.
"""
import json
import os
import statistics
import tempfile
import time
from pathlib import Path

TARGET_MS = 100.0
RUNS = 10
#: the 20-primitive maneuver of bench_planner_latency, at the stored time scale
GOAL = {"mode": 0, "primitive_ids": ["constrained/accelerate/E0.05", "constrained/cruise/E0.05",
                                     "constrained/decelerate/E0.05"], "repeat_counts": [1, 18, 1]}
#: how long the nodes may take to start and answer, s (a loaded 2-core host)
STARTUP_TIMEOUT_S = 60.0
#: the vehicle is at rest for the next goal when every joint speed has stayed under this for REST_STATES states
#: (maneuver_node's rest bounds are 0.1 rad/s and 0.02 m/s: a goal then waits for nothing)
REST_SPEED = 0.05
REST_STATES = 25
#: a tracked period's plan time at most, for it to count as the new plan's first (a few periods of 8 ms)
FIRST_PERIOD_PLAN_TIME_S = 0.05


def main() -> None:
    from swim_ros.domains import run_domain
    from swim_ros.processes import interrupt_on_sigterm
    run_domain()   # a domain of our own unless the user chose one: never another session's nodes
    interrupt_on_sigterm()   # SIGTERM stops the nodes as Ctrl-C does
    from swim_bringup.system import System, closed_loop_specs, config_dir
    specs = closed_loop_specs(config_dir("realistic"), ("mode:=realtime",), plant="sim", visualization=False,
                              maneuver=True)
    with tempfile.TemporaryDirectory() as logs, System(specs, Path(logs)) as system:
        latencies_ms, segments = measure()
        if system.dead():
            raise SystemExit(f"{', '.join(system.dead())} died (logs in {logs})")
    median = statistics.median(latencies_ms)
    print(json.dumps({"benchmark": "perform_maneuver", "segments": segments, "runs": len(latencies_ms),
                      "median_ms": round(median, 1), "max_ms": round(max(latencies_ms), 1),
                      "min_ms": round(min(latencies_ms), 1), "target_ms": TARGET_MS,
                      "meets_target": median <= TARGET_MS, "load_average": round(os.getloadavg()[0], 2)}))


def measure() -> tuple[list[float], int]:
    """The acceptance-to-first-period spans of RUNS goals (after one that builds the model), and their segments."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from sensor_msgs.msg import JointState
    from std_srvs.srv import Trigger
    from swim_interfaces.action import PerformManeuver
    from swim_interfaces.msg import TrackingState

    from swim_ros.calls import (
        ActionClient,
        GoalStatusWatch,
        RetryPolicy,
        call_service,
        cancel_goal,
        goal_result,
        send_goal,
        spin_until,
    )
    policy = RetryPolicy(attempt_timeout_s=10.0, attempts=3, discovery_timeout_s=STARTUP_TIMEOUT_S)
    rclpy.init()
    node = rclpy.create_node("perform_maneuver_bench")
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    first_period: list[float] = []
    tracking = node.create_subscription(
        TrackingState, "tracking_state", lambda m: first_period.append(time.perf_counter())
        if m.plan_time_s <= FIRST_PERIOD_PLAN_TIME_S and not first_period else None, 100)
    still = [0]   # consecutive states at rest
    node.create_subscription(JointState, "joint_states", lambda m: still.__setitem__(
        0, still[0] + 1 if max(map(abs, m.velocity), default=1.0) < REST_SPEED else 0), 100)
    client = ActionClient(node, PerformManeuver, "perform_maneuver")
    status = GoalStatusWatch(node, "perform_maneuver")
    reset = node.create_client(Trigger, "reset")
    latencies_ms, segments = [], 0
    try:
        # matched before the first goal, or its first periods would go unseen (a new reader misses them)
        if not spin_until(executor, lambda: tracking.get_publisher_count() > 0, STARTUP_TIMEOUT_S):
            raise SystemExit("tracking_state has no publisher: is tracker_node up?")
        for run in range(RUNS + 1):
            feedback: list = []
            if not spin_until(executor, lambda: still[0] >= REST_STATES, STARTUP_TIMEOUT_S):
                raise SystemExit("the vehicle did not come to rest")
            first_period.clear()
            handle = send_goal(executor, client, PerformManeuver.Goal(**GOAL), status,
                               lambda m: feedback.append(m.feedback), policy)
            accepted = time.perf_counter()
            if not spin_until(executor, lambda: bool(first_period), STARTUP_TIMEOUT_S):
                result = goal_result(executor, handle, STARTUP_TIMEOUT_S).result
                raise SystemExit(f"no tracked period: {result.error_code} {result.error_string}")
            if run > 0:   # the first goal waited for the tracker's model
                latencies_ms.append(1000.0 * (first_period[0] - accepted))
            cancel_goal(executor, handle, policy)
            result = goal_result(executor, handle, STARTUP_TIMEOUT_S).result
            if result.error_code != PerformManeuver.Result.CANCELED:
                raise SystemExit(f"the goal was not canceled: {result.error_code} {result.error_string}")
            segments = max((f.segment_count for f in feedback), default=0)
            if not call_service(executor, reset, Trigger.Request(), policy).success:
                raise SystemExit("sim_node did not reset")
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.shutdown()
    return latencies_ms, segments


if __name__ == "__main__":
    main()
