"""Benchmark: planner service latency over DDS for a 20-primitive maneuver at lambda = 1.2 (target <= 50 ms).

Starts planner_node in its own process (own ROS_DOMAIN_ID, discovery on localhost), sends 30 requests
of {accelerate, cruise x18, decelerate} (constrained, E = 0.05) and prints one JSON line with the median
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


def main() -> None:
    from swim_ros.domains import run_domain
    run_domain()   # a domain of our own unless the user chose one: never another session's nodes
    import rclpy
    from swim_interfaces.srv import RequestManeuver
    node_process = subprocess.Popen(["bash", "-c", "source scripts/env.sh && exec ros2 run swim_planner planner_node"],
                                    cwd=WORKSPACE, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                    start_new_session=True)
    try:
        rclpy.init()
        node = rclpy.create_node("planner_latency_bench")
        client = node.create_client(RequestManeuver, "request_maneuver")
        if not client.wait_for_service(timeout_sec=30.0):
            raise SystemExit("planner_node did not come up")
        request = RequestManeuver.Request(
            primitive_ids=["constrained/accelerate/E0.05", "constrained/cruise/E0.05", "constrained/decelerate/E0.05"],
            repeat_counts=[1, 18, 1], time_scale=1.2)
        latencies = []
        for _ in range(30):
            start = time.perf_counter()
            future = client.call_async(request)
            rclpy.spin_until_future_complete(node, future, timeout_sec=10.0)
            if not future.done() or not future.result().success:
                raise SystemExit(f"request failed: {future.result().message if future.done() else 'timeout'}")
            latencies.append(1000.0 * (time.perf_counter() - start))
        segments = len(future.result().plan.segments)
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
