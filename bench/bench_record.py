"""Benchmark: swim-record beside the closed loop, against the demo's in-process recorder (RunClient).

The closed loop in lock-step over DDS (sim_node, planner_node, tracker_node and swim_viz's nodes, the demo's
parameter files) executes the paper's constrained maneuver (30 s), each time in a bring-up of its own, REPEATS
times each way, alternating (the host's load changes with time):
1. in_process: recorded by the client that drives the run (RunClient, what swim-demo does);
2. swim_record: the same topics (the demo's RUN_TOPICS) recorded by a swim-record process started before the goal,
   the client recording nothing.
Speed: the plan's duration over the wall time from the goal's acceptance to its result (simulated s per wall s:
lock-step, so a recorder that takes CPU from the loop slows it). Loss: in swim-record's bag, the tracked periods
(tracking_state's stamps, one per 8 ms) must be contiguous over the whole plan, and joint_states and
joint_commands must hold each of them. The JSON line carries the load average before and after: the host is
shared, so speeds vary by run: the medians are compared.
Prints one JSON line.
"""
from __future__ import annotations

import json
import os
import re
import signal
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

from swim_bringup.bag import RUN_TOPICS, read_messages
from swim_bringup.recorded_run import PAPER_CONSTRAINED, RUN_TOLERANCES
from swim_bringup.run_client import LOOP_TOPICS, RunClient
from swim_bringup.system import System, closed_loop_specs, config_dir

PERIOD_NS = 8_000_000   # the demo's control period (rig.yaml sample_period: paper Sec. 2)
STARTUP_TIMEOUT_S, GOAL_TIMEOUT_S, RECORDER_TIMEOUT_S = 120.0, 600.0, 120.0
REPEATS = 2


def run_goal(client: RunClient) -> tuple[float, float]:
    """Execute the paper's maneuver; (the plan's duration s, simulated s per wall s from acceptance to result)."""
    client.wait_for_nodes(STARTUP_TIMEOUT_S)
    plan = client.request(*PAPER_CONSTRAINED, 1.0)
    started = time.monotonic()
    handle = client.execute(plan, tolerances=RUN_TOLERANCES)
    result = client.result(handle, GOAL_TIMEOUT_S)
    if result.error_code != 0:
        raise RuntimeError(f"the maneuver failed: {result.error_string}")
    return result.duration_s, result.duration_s / (time.monotonic() - started)


def in_process(work: Path) -> float:
    with System(closed_loop_specs(config_dir("paper")), work / "logs_in_process"), \
            RunClient(work / "bag_in_process") as client:
        duration_s, speed = run_goal(client)
        client.drain(duration_s)
    return speed


def wait_for(condition, timeout_s: float, what: str) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > deadline:
            raise RuntimeError(f"no {what} within {timeout_s:.0f} s")
        time.sleep(0.2)


def recorded_counts(log_path: Path) -> dict[str, int]:
    """The counts of swim-record's latest status line ('recording N topics: /a 12, /b 3')."""
    lines = [line for line in log_path.read_text().splitlines() if line.startswith("recording ")]
    return {topic: int(count) for topic, count in re.findall(r"(\S+) (\d+)", lines[-1].split(":", 1)[1])} \
        if lines else {}


def swim_record(work: Path) -> tuple[float, dict[str, int], int]:
    """(speed, messages per loop topic in the bag, tracked periods missing from any loop topic)."""
    bag, log_path = work / "bag_swim_record", work / "swim_record.log"
    with System(closed_loop_specs(config_dir("paper")), work / "logs_swim_record"), open(log_path, "w") as log:
        recorder = subprocess.Popen(["ros2", "run", "swim_bringup", "swim-record", "-o", str(bag), *RUN_TOPICS],
                                    stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        try:
            # joint_states and joint_commands flow before the goal: messages on them show the recorder matched
            wait_for(lambda: all(recorded_counts(log_path).get(t, 0) > 0 for t in LOOP_TOPICS[:2])
                     and LOOP_TOPICS[2] in recorded_counts(log_path), STARTUP_TIMEOUT_S, "recorder running")
            with RunClient(work / "bag_client_unused", topics={}) as client:
                duration_s, speed = run_goal(client)
            time.sleep(5.0)   # the recorder's queues drained
        finally:
            os.killpg(recorder.pid, signal.SIGINT)
            recorder.wait(RECORDER_TIMEOUT_S)
    stamps: dict[str, set[int]] = {topic: set() for topic in LOOP_TOPICS}
    counts = dict.fromkeys(LOOP_TOPICS, 0)
    for topic, _, message in read_messages(bag, LOOP_TOPICS):
        stamps[topic].add(message.header.stamp.sec * 1_000_000_000 + message.header.stamp.nanosec)
        counts[topic] += 1
    tracked = sorted(stamps["/tracking_state"])
    expected = set(range(tracked[0], tracked[0] + round(duration_s * 1e9) + 1, PERIOD_NS))
    missing = expected - stamps["/tracking_state"]
    for topic in LOOP_TOPICS[:2]:
        missing |= expected - stamps[topic]
    return speed, counts, len(missing)


def main() -> None:
    from swim_ros.domains import run_domain
    run_domain()   # a domain of our own unless the user chose one: never another session's nodes
    load_before = os.getloadavg()[0]
    in_process_speeds, swim_record_speeds, missing_periods, counts = [], [], 0, {}
    for _ in range(REPEATS):
        with tempfile.TemporaryDirectory() as directory:
            in_process_speeds.append(in_process(Path(directory)))
        with tempfile.TemporaryDirectory() as directory:
            speed, counts, missing = swim_record(Path(directory))
            swim_record_speeds.append(speed)
            missing_periods += missing
    print(json.dumps({
        "benchmark": "record_beside_closed_loop",
        "in_process_speed_sim_s_per_wall_s": [round(v, 2) for v in in_process_speeds],
        "swim_record_speed_sim_s_per_wall_s": [round(v, 2) for v in swim_record_speeds],
        "median_speed_ratio_swim_record_to_in_process":
            round(statistics.median(swim_record_speeds) / statistics.median(in_process_speeds), 2),
        "swim_record_messages_last_run": counts, "swim_record_missing_periods": missing_periods,
        "load_average_1min": [round(load_before, 2), round(os.getloadavg()[0], 2)]}))


if __name__ == "__main__":
    main()
