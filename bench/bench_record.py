"""Benchmark: swim-record beside the closed loop, against the demo's in-process recorder (RunClient).

The closed loop in lock-step over DDS (sim_node, planner_node, tracker_node and swim_viz's nodes, the demo's
parameter files) executes the paper's constrained maneuver (30 s), each time in a bring-up of its own, REPEATS
times each way, alternating, each way first in every other pair (the host's load changes with time):
1. in_process: recorded by the client that drives the run (RunClient, what swim-demo does);
2. swim_record: the same topics (the demo's RUN_TOPICS) recorded by a swim-record process started before the goal,
   the client recording nothing.
Speed: the plan's duration over the wall time from the goal's acceptance to its result (simulated s per wall s:
lock-step, so a recorder that takes CPU from the loop slows it). The runs go in pairs, one each way, and the ratio
of each pair's speeds is reported with their median: the pair shares the host's load of its minute. Recording cost:
the CPU seconds the recording side spent per simulated second over the same interval (the client's process, plus
swim-record's): the quantity that, on a shared host, is taken from the loop. Loss: in swim-record's bag, the
tracked periods (tracking_state's stamps, one per 8 ms) must be contiguous over the whole plan, and joint_states
and joint_commands must hold each of them. The JSON line carries the load average before and after: the host is
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
from swim_bringup.experiments import PAPER_CONSTRAINED
from swim_bringup.recorded_run import RUN_TOLERANCES
from swim_bringup.run_client import LOOP_TOPICS, RunClient
from swim_bringup.system import System, closed_loop_specs, config_dir
from swim_ros.processes import interrupt_on_sigterm, start_child

PERIOD_NS = 8_000_000   # the demo's control period (rig.yaml sample_period: paper Sec. 2)
STARTUP_TIMEOUT_S, GOAL_TIMEOUT_S, RECORDER_TIMEOUT_S = 120.0, 600.0, 120.0
REPEATS = 5   # pairs: with fewer, one pair's change of load decides the median
CLOCK_TICKS_PER_S = os.sysconf("SC_CLK_TCK")


def process_cpu_s(pid: int) -> float:
    """User plus system CPU seconds of process pid, all its threads (/proc/PID/stat fields 14 and 15)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLOCK_TICKS_PER_S


def run_goal(client: RunClient, recorder_pid: int | None = None) -> tuple[float, float, float]:
    """Execute the paper's maneuver; (the plan's duration s, simulated s per wall s from acceptance to result,
    CPU s per simulated s of this process and the recorder process over the same interval)."""
    client.wait_for_nodes(STARTUP_TIMEOUT_S)
    plan = client.request(*PAPER_CONSTRAINED, 1.0)
    pids = [os.getpid()] + ([recorder_pid] if recorder_pid is not None else [])
    cpu_before_s, started = sum(map(process_cpu_s, pids)), time.monotonic()
    handle = client.execute(plan, tolerances=RUN_TOLERANCES)
    result = client.result(handle, GOAL_TIMEOUT_S)
    wall_s, cpu_s = time.monotonic() - started, sum(map(process_cpu_s, pids)) - cpu_before_s
    if result.error_code != 0:
        raise RuntimeError(f"the maneuver failed: {result.error_string}")
    return result.duration_s, result.duration_s / wall_s, cpu_s / result.duration_s


def in_process(work: Path) -> tuple[float, float]:
    """(speed, recording side's CPU s per simulated s)."""
    with System(closed_loop_specs(config_dir("paper")), work / "logs_in_process"), \
            RunClient(work / "bag_in_process") as client:
        duration_s, speed, cpu_per_sim_s = run_goal(client)
        client.drain(duration_s)
    return speed, cpu_per_sim_s


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


def swim_record(work: Path) -> tuple[float, float, dict[str, int], int]:
    """(speed, recording side's CPU s per simulated s, messages per loop topic in the bag, tracked periods missing
    from any loop topic)."""
    bag, log_path = work / "bag_swim_record", work / "swim_record.log"
    with System(closed_loop_specs(config_dir("paper")), work / "logs_swim_record"), open(log_path, "w") as log:
        recorder = start_child(["ros2", "run", "swim_bringup", "swim-record", "-o", str(bag), *RUN_TOPICS],
                               stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        try:
            # joint_states and joint_commands flow before the goal: messages on them show the recorder matched
            wait_for(lambda: all(recorded_counts(log_path).get(t, 0) > 0 for t in LOOP_TOPICS[:2])
                     and LOOP_TOPICS[2] in recorded_counts(log_path), STARTUP_TIMEOUT_S, "recorder running")
            with RunClient(work / "bag_client_unused", topics={}) as client:
                duration_s, speed, cpu_per_sim_s = run_goal(client, recorder.pid)
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
    return speed, cpu_per_sim_s, counts, len(missing)


def main() -> None:
    from swim_ros.domains import run_domain
    run_domain()   # a domain of our own unless the user chose one: never another session's nodes
    interrupt_on_sigterm()   # SIGTERM stops the nodes as Ctrl-C does
    load_before = os.getloadavg()[0]
    in_process_speeds, swim_record_speeds, missing_periods, counts = [], [], 0, {}
    in_process_cpu, swim_record_cpu = [], []
    def run_in_process() -> None:
        with tempfile.TemporaryDirectory() as directory:
            speed, cpu_per_sim_s = in_process(Path(directory))
            in_process_speeds.append(speed)
            in_process_cpu.append(cpu_per_sim_s)

    def run_swim_record() -> None:
        nonlocal counts, missing_periods
        with tempfile.TemporaryDirectory() as directory:
            speed, cpu_per_sim_s, counts, missing = swim_record(Path(directory))
            swim_record_speeds.append(speed)
            swim_record_cpu.append(cpu_per_sim_s)
            missing_periods += missing
    for pair in range(REPEATS):
        # each way first in every other pair: a drift of the host's speed favours neither
        for run in (run_in_process, run_swim_record) if pair % 2 == 0 else (run_swim_record, run_in_process):
            run()
    pair_ratios = [mine / theirs for mine, theirs in zip(swim_record_speeds, in_process_speeds)]
    print(json.dumps({
        "benchmark": "record_beside_closed_loop",
        "in_process_speed_sim_s_per_wall_s": [round(v, 2) for v in in_process_speeds],
        "swim_record_speed_sim_s_per_wall_s": [round(v, 2) for v in swim_record_speeds],
        "speed_ratio_swim_record_to_in_process_per_pair": [round(v, 2) for v in pair_ratios],
        "median_pair_speed_ratio": round(statistics.median(pair_ratios), 2),
        "recording_cpu_s_per_sim_s_median": {"in_process": round(statistics.median(in_process_cpu), 3),
                                             "swim_record": round(statistics.median(swim_record_cpu), 3)},
        "swim_record_messages_last_run": counts, "swim_record_missing_periods": missing_periods,
        "load_average_1min": [round(load_before, 2), round(os.getloadavg()[0], 2)]}))


if __name__ == "__main__":
    main()
