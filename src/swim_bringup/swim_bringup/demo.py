"""swim-demo: the paper's constrained maneuver in closed loop in simulation, recorded and analysed.

Brings up sim_node (lock-step, default disturbances), planner_node and tracker_node as separate processes over
DDS, asks the planner for the maneuver, has the tracker execute it while every topic of the run is recorded to an
MCAP bag, stops the nodes, and writes report.json, figures and the bag into the run folder; prints a summary.
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import random
import sys
import time
from pathlib import Path

from swim_bringup.analysis import analyze, summary_table, write_figures
from swim_bringup.bag import RUN_TOPICS, BagWriter
from swim_bringup.system import System, closed_loop_specs, config_dir

#: the paper's constrained maneuver (Sec. 7.1): accelerate to E1, cruise x2, cruise-to-cruise, cruise x2, stop
PAPER_CONSTRAINED = (["constrained/accelerate/E0.05", "constrained/cruise/E0.05",
                      "constrained/cruise_to_cruise/E0.05-E0.10", "constrained/cruise/E0.10",
                      "constrained/decelerate/E0.10"], [1, 2, 1, 2, 1])
STARTUP_TIMEOUT_S = 60.0
DRAIN_TIMEOUT_S = 60.0
RECORD_DEPTH = 10000   # the recorder may fall behind a lock-step loop; it must not drop periods


class DemoError(RuntimeError):
    """The run could not be done (a node did not start or died, the planner refused, ...)."""


def run_maneuver(bag_path: Path, primitive_ids: list[str], repeat_counts: list[int], time_scale: float,
                 timeout_s: float, progress=None) -> dict:
    """Request the maneuver, execute it, record the run; returns the action's result as a dict."""
    import rclpy
    from rclpy.action import ActionClient
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import QoSDurabilityPolicy, QoSProfile
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import JointState
    from swim_interfaces.action import ExecutePlan
    from swim_interfaces.msg import PlannedTrajectory, TrackingState
    from swim_interfaces.srv import RequestManeuver

    context = rclpy.Context()
    rclpy.init(context=context)
    bag = BagWriter(bag_path)
    try:
        node = rclpy.create_node("swim_demo_client", context=context)
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        types = {"joint_states": JointState, "joint_commands": JointState, "tracking_state": TrackingState,
                 "plan": PlannedTrajectory}
        latched = QoSProfile(depth=1, durability=QoSDurabilityPolicy.TRANSIENT_LOCAL)
        last_plan_time_s = [-1.0]
        for topic in RUN_TOPICS:
            def record(cdr: bytes, topic: str = topic) -> None:
                bag.write(topic, time.time_ns(), cdr)
                if topic == "tracking_state":
                    last_plan_time_s[0] = deserialize_message(cdr, TrackingState).plan_time_s
            node.create_subscription(types[topic], topic, record, latched if topic == "plan" else RECORD_DEPTH,
                                     raw=True)
        planner = node.create_client(RequestManeuver, "request_maneuver")
        tracker = ActionClient(node, ExecutePlan, "execute_plan")
        if not planner.wait_for_service(timeout_sec=STARTUP_TIMEOUT_S):
            raise DemoError("planner_node did not come up")
        if not tracker.wait_for_server(timeout_sec=STARTUP_TIMEOUT_S):
            raise DemoError("tracker_node did not come up")
        reply = _spin_until(executor, planner.call_async(RequestManeuver.Request(
            primitive_ids=primitive_ids, repeat_counts=repeat_counts, time_scale=time_scale)), 60.0)
        if not reply.success:
            raise DemoError(f"the planner refused the maneuver: {reply.message}")
        def on_feedback(message) -> None:
            if progress is not None:
                progress(message.feedback.progress)
        handle = _spin_until(executor, tracker.send_goal_async(ExecutePlan.Goal(plan=reply.plan),
                                                               feedback_callback=on_feedback), 30.0)
        if not handle.accepted:
            raise DemoError("the tracker refused the goal")
        result = _spin_until(executor, handle.get_result_async(), timeout_s).result
        # the recorder may lag a faster-than-real-time loop: drain until the plan's last period is in the bag
        drain_until = time.monotonic() + DRAIN_TIMEOUT_S
        while last_plan_time_s[0] < result.duration_s - 1e-6 and time.monotonic() < drain_until:
            executor.spin_once(timeout_sec=0.05)
        for _ in range(20):   # and a few periods of the hold after it
            executor.spin_once(timeout_sec=0.01)
        return {"error_code": result.error_code, "error_string": result.error_string,
                "final_alpha_error_rad": result.final_alpha_error_rad, "duration_s": result.duration_s}
    finally:
        bag.close()
        rclpy.try_shutdown(context=context)


def _spin_until(executor, future, timeout_s: float):
    deadline = time.monotonic() + timeout_s
    while not future.done():
        if time.monotonic() > deadline:
            raise DemoError(f"no answer within {timeout_s:.0f} s")
        executor.spin_once(timeout_sec=0.05)
    return future.result()


def parse_arguments(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="swim-demo", description=__doc__.splitlines()[0])
    parser.add_argument("--run-dir", type=Path, default=None, help="output folder (default runs/demo-<time>)")
    parser.add_argument("--primitives", nargs="+", default=PAPER_CONSTRAINED[0])
    parser.add_argument("--repeats", nargs="+", type=int, default=PAPER_CONSTRAINED[1])
    parser.add_argument("--time-scale", type=float, default=1.0)
    parser.add_argument("--sliding-mode", choices=("on", "off"), default="on")
    parser.add_argument("--config", type=Path, default=None, help="folder of sim/planner/tracker YAML files")
    parser.add_argument("--timeout", type=float, default=600.0, help="wall-time limit of the maneuver, s")
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_arguments(argv)
    run_dir = args.run_dir or Path("runs") / datetime.datetime.now().strftime("demo-%Y%m%d-%H%M%S")
    run_dir.mkdir(parents=True, exist_ok=True)
    # a domain of our own unless the user chose one: a demo never talks to another session's nodes
    os.environ.setdefault("ROS_DOMAIN_ID", str(random.randint(101, 200)))
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    bag_path = run_dir / "bag"
    if bag_path.exists():
        print(f"swim-demo: {bag_path} exists; choose another --run-dir", file=sys.stderr)
        return 2
    from tqdm import tqdm
    specs = closed_loop_specs(args.config or config_dir(),
                              tracker_overrides=(f"sliding_mode_enabled:={args.sliding_mode == 'on'}".lower(),))
    print(f"swim-demo: bringing up {', '.join(s.executable for s in specs)} (logs in {run_dir / 'logs'})")
    started = time.monotonic()
    try:
        with System(specs, run_dir / "logs") as system, \
                tqdm(total=100, unit="%", desc="maneuver", file=sys.stderr) as bar:
            def progress(fraction: float) -> None:
                bar.update(round(100 * fraction) - bar.n)
                if system.dead():
                    raise DemoError(f"{', '.join(system.dead())} died (see {run_dir / 'logs'})")
            result = run_maneuver(bag_path, args.primitives, args.repeats, args.time_scale, args.timeout,
                                  progress)
    except DemoError as err:
        print(f"swim-demo: {err}", file=sys.stderr)
        return 1
    report = analyze(bag_path)
    report["result"] = result
    report["wall_time_s"] = time.monotonic() - started
    (run_dir / "report.json").write_text(json.dumps(report, indent=2))
    write_figures(bag_path, run_dir)
    print(summary_table({run_dir.name: report}))
    print(f"swim-demo: report, figures and bag in {run_dir}")
    return 0 if result["error_code"] == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
