"""Benchmark: what a live Foxglove connection costs the closed loop. The paper's constrained maneuver (30 s of plan)
flown in lock-step (sim_node, planner, tracker, the visualization nodes; recorded_run.run_maneuver) with
foxglove_node and one client subscribed to joint_states, tracking_state, /tf and the scene, reading as the app
does, against the same run without them; the pairs interleaved, so that a slow hour of the host falls on both.

Speed: the plan's seconds per wall second of the maneuver (the tracker's duration over the maneuver's wall time,
from the goal sent to its result, recorded as swim-demo records it); slowdown = 1 - with/without, from the
medians. Latency from DDS to the client: for each joint_states message the client got, its receipt by the client
less its receipt by an rclpy subscriber in this process (the same bytes, the same clock), median and p99 over the
runs.

Target: the loop at most TARGET_SLOWDOWN slower with the client. Prints one JSON line last.

    python bench/bench_foxglove.py [--pairs 5]
"""
from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

from swim_ros.testing.foxglove_client import ClientThread, free_port

TARGET_SLOWDOWN = 0.10
#: the topics the client reads, as the layout's 3D panel and plots would
READ_TOPICS = ("/joint_states", "/tracking_state", "/tf", "/scene")
RUN_TIMEOUT_S = 600.0


class Observer(threading.Thread):
    """An rclpy subscriber to /joint_states in this process: the wall receipt time of each payload."""

    def __init__(self) -> None:
        super().__init__(daemon=True)
        self.stop = threading.Event()
        self.received: dict[bytes, float] = {}

    def run(self) -> None:
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from sensor_msgs.msg import JointState
        context = rclpy.Context()
        rclpy.init(context=context)
        try:
            node = rclpy.create_node("bench_foxglove_observer", context=context)
            node.create_subscription(JointState, "/joint_states",
                                     lambda raw: self.received.setdefault(raw, time.monotonic()), 1000, raw=True)
            executor = SingleThreadedExecutor(context=context)
            executor.add_node(node)
            while not self.stop.is_set():
                executor.spin_once(timeout_sec=0.01)
            executor.shutdown()
            node.destroy_node()
        finally:
            rclpy.shutdown(context=context)


def one_run(with_foxglove: bool, folder: Path) -> tuple[float, list[float]]:
    """(plan seconds per wall second of the maneuver, latencies in s) of one run."""
    from swim_bringup.experiments import PAPER_CONSTRAINED
    from swim_bringup.recorded_run import run_maneuver
    from swim_bringup.system import System, closed_loop_specs, config_dir
    from swim_ros.processes import NodeSpec
    specs = closed_loop_specs(config_dir("realistic"), plant="sim")
    observer = Observer()   # in both runs: its cost falls on both sides alike
    threads: list = [observer]
    if with_foxglove:
        port = free_port()
        specs = [*specs, NodeSpec("swim_viz", "foxglove_node", parameters=(f"port:={port}",))]
        threads.append(ClientThread(port, READ_TOPICS))
    for thread in threads:
        thread.start()
    try:
        with System(specs, folder / "logs"):
            started = time.monotonic()
            result = run_maneuver(folder / "bag", *PAPER_CONSTRAINED, 1.0, RUN_TIMEOUT_S, lambda fraction: None)
            wall_s = time.monotonic() - started
    finally:
        for thread in threads:
            thread.stop.set()
            thread.join(10.0)
    if result.error_code != 0:
        raise RuntimeError(f"the run failed: {result.error_string}")
    latencies = []
    if with_foxglove and threads[1].client is not None:
        received: dict[bytes, float] = {}
        for message in threads[1].client.messages("/joint_states"):
            received.setdefault(message.payload, message.received_s)
        latencies = [t - observer.received[payload] for payload, t in received.items() if payload in observer.received]
    return result.duration_s / wall_s, latencies


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=5)
    args = parser.parse_args()
    from swim_ros.domains import run_domain
    from swim_ros.processes import interrupt_on_sigterm
    interrupt_on_sigterm()
    run_domain()
    speeds: dict[bool, list[float]] = {False: [], True: []}
    latencies: list[float] = []
    started = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="bench_foxglove_") as work:
        for pair in range(args.pairs):
            for with_foxglove in (False, True):
                speed, run_latencies = one_run(with_foxglove, Path(work) / f"{pair}-{with_foxglove}")
                speeds[with_foxglove].append(speed)
                latencies += run_latencies
                print(f"pair {pair}, {'with' if with_foxglove else 'without'} foxglove_node: {speed:.2f}x real time"
                      f"{f', {len(run_latencies)} messages matched' if with_foxglove else ''}", flush=True)
    without, with_ = statistics.median(speeds[False]), statistics.median(speeds[True])
    slowdown = 1.0 - with_ / without
    print(json.dumps({
        "benchmark": "foxglove", "pairs": args.pairs,
        "speed_without_x_real_time": [round(s, 2) for s in speeds[False]],
        "speed_with_x_real_time": [round(s, 2) for s in speeds[True]],
        "slowdown": round(slowdown, 3), "target_slowdown": TARGET_SLOWDOWN, "meets_target": slowdown <= TARGET_SLOWDOWN,
        "messages_matched": len(latencies),
        "latency_p50_ms": round(float(np.percentile(latencies, 50)) * 1e3, 2) if latencies else None,
        "latency_p99_ms": round(float(np.percentile(latencies, 99)) * 1e3, 2) if latencies else None,
        "wall_time_s": round(time.monotonic() - started, 1)}))


if __name__ == "__main__":
    main()
