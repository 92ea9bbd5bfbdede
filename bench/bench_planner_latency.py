"""Benchmark: planner service latency over DDS for a 20-primitive maneuver at lambda = 1.2 (target <= 50 ms).

Starts planner_node in its own process (own ROS_DOMAIN_ID, discovery on localhost), sends 30 requests
of {accelerate, cruise x18, decelerate} (constrained, E = 0.05) through swim_ros.calls, each with its own
request id, and prints one JSON line with the median
and worst round-trip time.
"""
import json
import os
import signal
import statistics
import subprocess
import time
from pathlib import Path

WORKSPACE = Path(__file__).resolve().parents[1]
TARGET_MS = 50.0
#: how long planner_node may take to load its library and serve, s (a loaded 2-core host)
STARTUP_TIMEOUT_S = 60.0


def main() -> None:
    from swim_ros.domains import run_domain
    from swim_ros.processes import interrupt_on_sigterm, start_child
    run_domain()   # a domain of our own unless the user chose one: never another session's nodes
    interrupt_on_sigterm()   # SIGTERM stops the nodes as Ctrl-C does
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from swim_interfaces.srv import RequestManeuver

    from swim_ros.calls import call_service, new_request_id, wait_for_server
    node_process = start_child(["bash", "-c", "source scripts/env.sh && exec ros2 run swim_planner planner_node"],
                               cwd=WORKSPACE, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                               start_new_session=True)
    try:
        rclpy.init()
        node = rclpy.create_node("planner_latency_bench")
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        client = node.create_client(RequestManeuver, "request_maneuver")
        wait_for_server(executor, client.service_is_ready, client.srv_name, STARTUP_TIMEOUT_S)
        latencies = []
        for _ in range(30):
            request = RequestManeuver.Request(
                primitive_ids=["constrained/accelerate/E0.05", "constrained/cruise/E0.05",
                               "constrained/decelerate/E0.05"],
                repeat_counts=[1, 18, 1], time_scale=1.2, request_id=new_request_id())
            start = time.perf_counter()
            reply = call_service(executor, client, request)
            if not reply.success:
                raise SystemExit(f"request refused: {reply.message}")
            latencies.append(1000.0 * (time.perf_counter() - start))
        segments = len(reply.plan.segments)
        executor.shutdown()
        node.destroy_node()
        rclpy.shutdown()
    finally:
        os.killpg(node_process.pid, signal.SIGINT)
        node_process.wait(timeout=10)
    median = statistics.median(latencies[1:])
    print(json.dumps({"benchmark": "planner_latency", "segments": segments, "time_scale": 1.2,
                      "median_ms": round(median, 1), "max_ms": round(max(latencies[1:]), 1),
                      "first_ms": round(latencies[0], 1), "target_ms": TARGET_MS, "meets_target": median <= TARGET_MS}))


if __name__ == "__main__":
    main()
