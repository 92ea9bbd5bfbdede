"""Benchmark: closed-loop control period jitter over DDS at 8 ms and at 2 ms.

sim_node in real time (`mode: realtime`: a timer steps the plant every period with the latest command held),
planner_node and tracker_node as processes over DDS (swim_bringup's System, the parameter files of
swim_bringup/config with the period overridden), executing the paper's constrained accelerate primitive (4 s).
A RunClient records joint_states and joint_commands with the wall time of their receipt. Over the tracked part
of the run:
- period jitter: |interval between consecutive commands - the period| (what the motors see), and the same for
  the states (the simulator's timer, for comparison);
- latency: a command's receipt minus the receipt of the state it answers (same stamp): the tracker's step and
  two DDS hops;
- missed: the fraction of states no command answered.
Times are taken where the recorder receives the messages, so the recorder's own scheduling is in them.
Prints one JSON line.
"""
from __future__ import annotations

import json
import tempfile
from pathlib import Path

import numpy as np

from swim_bringup.bag import RUN_TOPICS, read_messages
from swim_bringup.run_client import LOOP_TOPICS, RunClient
from swim_bringup.system import System, closed_loop_specs, config_dir

PERIODS_S = (0.008, 0.002)
MANEUVER = (["constrained/accelerate/E0.05"], [1])
STALE_AFTER_S = 0.2   # the tracker's stale-state limit at either period (config/tracker.yaml: 25 x 8 ms)


def record_run(period_s: float, work: Path) -> Path:
    """The closed loop at period_s in real time, the maneuver executed and recorded; the bag's path."""
    specs = closed_loop_specs(
        config_dir(), ("mode:=realtime", f"sample_period_s:={period_s}"),
        (f"sample_period_s:={period_s}", f"stale_after_periods:={round(STALE_AFTER_S / period_s)}"))
    bag = work / f"bag_{period_s * 1e3:g}ms"
    topics = {topic: RUN_TOPICS[topic] for topic in LOOP_TOPICS}
    with System(specs, work / f"logs_{period_s * 1e3:g}ms"), RunClient(bag, topics) as client:
        client.wait_for_nodes()
        handle = client.execute(client.request(*MANEUVER, 1.0))
        result = client.result(handle, 120.0)
        client.drain(result.duration_s)
    return bag


def stamp_ns(message) -> int:
    return message.header.stamp.sec * 1_000_000_000 + message.header.stamp.nanosec


def period_jitter_ms(receipts_ns: list[int], period_s: float) -> np.ndarray:
    """|interval between consecutive receipts - period|, ms."""
    return np.abs(np.diff(np.array(receipts_ns) * 1e-9) - period_s) * 1e3


def loop_timing(bag: Path, period_s: float) -> dict:
    """Jitter, latency and missed periods over the tracked part of the recorded run."""
    rows = list(read_messages(bag, LOOP_TOPICS))
    tracked = [log_ns for topic, log_ns, _ in rows if topic == "/tracking_state"]
    first_ns, last_ns = tracked[0], tracked[-1]
    states = {stamp_ns(m): log_ns for topic, log_ns, m in rows
              if topic == "/joint_states" and first_ns <= log_ns <= last_ns}
    commands = [(stamp_ns(m), log_ns) for topic, log_ns, m in rows
                if topic == "/joint_commands" and first_ns <= log_ns <= last_ns]
    jitter_ms = period_jitter_ms([log_ns for _, log_ns in commands], period_s)
    state_jitter_ms = period_jitter_ms(sorted(states.values()), period_s)
    latency_ms = np.array([log_ns - states[stamp] for stamp, log_ns in commands if stamp in states]) * 1e-6
    answered = {stamp for stamp, _ in commands}
    return {"period_ms": period_s * 1e3, "commands": len(commands),
            "median_period_jitter_ms": round(float(np.median(jitter_ms)), 3),
            "p99_period_jitter_ms": round(float(np.percentile(jitter_ms, 99)), 3),
            "median_state_period_jitter_ms": round(float(np.median(state_jitter_ms)), 3),
            "p99_state_period_jitter_ms": round(float(np.percentile(state_jitter_ms, 99)), 3),
            "median_latency_ms": round(float(np.median(latency_ms)), 3),
            "p99_latency_ms": round(float(np.percentile(latency_ms, 99)), 3),
            "missed_fraction": round(1.0 - len(answered & set(states)) / len(states), 4)}


def main() -> None:
    from swim_ros.domains import run_domain
    from swim_ros.processes import interrupt_on_sigterm
    run_domain()   # a domain of our own unless the user chose one: never another session's nodes
    interrupt_on_sigterm()   # SIGTERM stops the nodes as Ctrl-C does
    results = {}
    with tempfile.TemporaryDirectory() as work:
        for period_s in PERIODS_S:
            results[f"period_{period_s * 1e3:g}ms"] = loop_timing(record_run(period_s, Path(work)), period_s)
    print(json.dumps({"benchmark": "closed_loop_jitter_over_dds", **results}))


if __name__ == "__main__":
    main()
