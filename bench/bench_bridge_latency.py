"""Benchmark: bridge_node command-to-device latency with the emulated backend at the 8 ms period.

bridge_node runs in this process (its executor in one thread, its I/O loop in another, as in its own process);
a second node publishes joint_commands at about 125 Hz over DDS (localhost, own ROS_DOMAIN_ID). Each command
carries a distinct heave torque, so the emulated device's write log (time.monotonic() of every write_currents)
tells which write first used it. Latency = that write's time - the command's publish time. The loop only
picks up a command at its next period, so about half a period (4 ms) of the median is the sampling itself.

The same run also gives the I/O loop's wake-up lateness (each period's start past its place on the grid, the
loop's own histogram) in the node, whose executor and the commanding node share its interpreter, and in a bare
process of its own that runs only the same loop on the same device for the same time, one after the other: what
a process of its own would give the loop. bridge_node runs as its own process's node (owns_process), so with
its real-time means unless --ordinary (realtime_policy other, nothing locked, automatic collection); the bare
loop likewise. Prints one JSON line.
"""
import argparse
import json
import random
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path

import yaml

PERIOD_S = 0.008
COMMANDS = 600
WITHOUT_REALTIME = ("realtime_policy:=other", "lock_memory:=false", "collect_garbage_between_periods:=false")
#: the bare loop: the emulated device behind an IoLoop, run for a given time with the node's real-time means or
#: none; prints its wake-up lateness (p50, p99, max, ms)
BARE_LOOP = """
import json, sys, time
from swim_hw_bridge.backends import make_device
from swim_hw_bridge.conversions import Conversions, load_bridge_config
from swim_hw_bridge.io_loop import IoLoop
from swim_hw_bridge.safety import SafetyLayer, SafetyLimits
from swim_ros.realtime import NO_REALTIME_MEANS, RealtimeSettings, make_process_realtime
realtime = RealtimeSettings(priority=70) if sys.argv[1] == "on" else NO_REALTIME_MEANS
config = load_bridge_config()
device = make_device("emulated", config.device_config("emulated"))
device.open()
limits = SafetyLimits.from_config(config, PERIOD_S, 5, 3, 3)
make_process_realtime(realtime)
loop = IoLoop(device, Conversions(config), SafetyLayer(limits), PERIOD_S, 10_000, realtime, 80)
loop.start()
time.sleep(float(sys.argv[2]))
loop.stop()
h = loop.wake_lateness
print(json.dumps([round(1e3 * v, 3) for v in (h.percentile_s(50), h.percentile_s(99), h.largest_s)]))
""".replace("PERIOD_S", repr(PERIOD_S))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ordinary", action="store_true", help="without the real-time means")
    args = parser.parse_args()
    from swim_ros.domains import run_domain
    from swim_ros.processes import interrupt_on_sigterm
    interrupt_on_sigterm()   # SIGTERM ends the run as Ctrl-C does: the bridge releases its device
    run_domain()   # a domain of our own unless the user chose one: never another session's nodes
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from sensor_msgs.msg import JointState

    from swim_hw_bridge.bridge_node import BridgeNode
    from swim_hw_bridge.conversions import Conversions, default_config_path, load_bridge_config
    document = yaml.safe_load(default_config_path().read_text())
    document["backend_options"]["emulated"]["write_log_size"] = 4 * COMMANDS + 1000   # every write of the run
    config_path = Path(tempfile.mkdtemp()) / "bridge.yaml"
    config_path.write_text(yaml.safe_dump(document))
    overrides = [a for o in (WITHOUT_REALTIME if args.ordinary else ()) for a in ("-p", o)]
    rclpy.init(args=["--ros-args", "-p", f"config_path:={config_path}", *overrides, "--log-level", "warn"])
    bridge = BridgeNode(owns_process=True)
    bridge.trigger_configure()
    device = bridge.loop.device
    bridge.trigger_activate()
    bridge_executor = SingleThreadedExecutor()
    bridge_executor.add_node(bridge)
    spinner = threading.Thread(target=bridge_executor.spin, daemon=True)
    spinner.start()

    sender = rclpy.create_node("bridge_latency_bench")
    publisher = sender.create_publisher(JointState, "joint_commands", 10)
    deadline = time.monotonic() + 10.0
    while publisher.get_subscription_count() == 0 and time.monotonic() < deadline:
        time.sleep(0.01)
    time.sleep(0.5)   # discovery settled both ways
    conversions = Conversions(load_bridge_config())
    jitter = random.Random(0)
    started_s = time.monotonic()
    published = {}   # heave current the command makes -> publish time
    for k in range(COMMANDS):
        torque = (1 if k % 2 else -1) * 1e-4 * (k + 1)   # distinct, small, alternating: the foil stays near 0
        message = JointState(name=["phi", "theta"], effort=[torque, 0.0])
        published[conversions.torques_to_currents(torque, 0.0)[0]] = time.monotonic()
        publisher.publish(message)
        time.sleep(PERIOD_S + jitter.uniform(-0.001, 0.001))   # no fixed phase against the loop
    time.sleep(0.1)
    run_s = time.monotonic() - started_s
    snapshot = bridge.loop.snapshot()
    wake = bridge.loop.wake_lateness
    in_node_ms = [round(1e3 * v, 3) for v in (wake.percentile_s(50), wake.percentile_s(99), wake.largest_s)]
    rows = device.write_log[:device.write_count]
    first_write = {}
    for write_s, heave_a, _ in rows:
        first_write.setdefault(heave_a, write_s)
    latencies_ms = sorted(1e3 * (first_write[current] - sent_s) for current, sent_s in published.items()
                          if current in first_write)
    bridge_executor.shutdown()
    bridge.release()
    sender.destroy_node()
    bridge.destroy_node()
    rclpy.try_shutdown()
    from swim_ros.processes import run_child
    bare = run_child([sys.executable, "-c", BARE_LOOP, "off" if args.ordinary else "on", str(run_s)],
                     capture_output=True, text=True)
    if bare.returncode != 0:
        raise SystemExit(f"the bare loop failed: {bare.stderr[-2000:]}")
    bare_ms = json.loads(bare.stdout.strip().splitlines()[-1])
    p99 = latencies_ms[min(len(latencies_ms) - 1, int(0.99 * len(latencies_ms)))]
    print(json.dumps({"benchmark": "bridge_latency", "backend": "emulated", "sample_period_ms": 1e3 * PERIOD_S,
                      "commands": COMMANDS, "reached_device": len(latencies_ms),
                      "superseded": COMMANDS - len(latencies_ms),   # a newer command arrived in the same period
                      "median_ms": round(statistics.median(latencies_ms), 2), "p99_ms": round(p99, 2),
                      "max_ms": round(latencies_ms[-1], 2), "loop_overruns": snapshot.overruns,
                      "loop_rate_hz": round(snapshot.loop_rate_hz, 1), "realtime": not args.ordinary,
                      "wake_lateness_in_node_ms": dict(zip(("p50", "p99", "max"), in_node_ms)),
                      "wake_lateness_bare_process_ms": dict(zip(("p50", "p99", "max"), bare_ms))}))


if __name__ == "__main__":
    main()
