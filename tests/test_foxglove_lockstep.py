"""foxglove_node during a lock-step closed loop (sim_node, planner, tracker, the visualization nodes):

- a client that subscribes to everything and never reads changes nothing of the run: the run flown with
  foxglove_node and such a client gives the report of the same run without them, key by key (the wall time
  aside); foxglove_node only subscribes, and drops what its client does not take;
- a client that reads gets what DDS carried: every joint_states message byte for byte (its stamp and values),
  every /tf transform as a FrameTransform with the same stamp, frames, translation and rotation.
"""
from __future__ import annotations

import threading
import time

from swim_bringup.recorded_run import run_recorded
from swim_bringup.run_client import header_stamp_ns
from swim_bringup.system import closed_loop_specs, config_dir
from swim_ros.processes import NodeSpec
from swim_ros.testing.foxglove_client import ClientThread, frame_transforms_keys, free_port, tf_message_keys

#: the paper's constrained start and stop: about 8 s of plan, a few seconds of wall time in lock-step
MANEUVER = (["constrained/accelerate/E0.05", "constrained/decelerate/E0.05"], [1, 1])
#: the reading client's run: 23 s of plan, so that a lock-step run on a fast host still lasts several wall seconds
#: of /tf at the rig state publisher's 30 Hz after the client's subscriptions are matched (8 s gave 4 transforms once)
READ_MANEUVER = (["constrained/accelerate/E0.05", "constrained/cruise/E0.05", "constrained/decelerate/E0.05"],
                 [1, 3, 1])
#: a lock-step run on a loaded host
RUN_TIMEOUT_S = 300.0
#: the depth of the observer's subscriptions: a reader's keep-last history drops its oldest unread message once
#: full, and a lock-step loop on a loaded host outruns the observer's thread for a while; the whole run fits
OBSERVER_DEPTH = 100_000


class Observer(threading.Thread):
    """The test's rclpy node on the run's domain: joint_states as DDS carried them, and /tf's transforms."""

    def __init__(self) -> None:
        super().__init__(daemon=True)
        self.stop = threading.Event()
        self.joint_states: set[bytes] = set()
        self.transforms: set[tuple] = set()
        self.last_read_s = time.monotonic()

    def drained(self, quiet_s: float = 1.0, timeout_s: float = 60.0) -> None:
        """Wait until nothing was read for quiet_s: the messages queued for it when the run ended are read."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() - self.last_read_s < quiet_s and time.monotonic() < deadline:
            time.sleep(0.1)

    def run(self) -> None:
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from sensor_msgs.msg import JointState
        from tf2_msgs.msg import TFMessage
        context = rclpy.Context()
        rclpy.init(context=context)
        try:
            node = rclpy.create_node("foxglove_lockstep_observer", context=context)
            node.create_subscription(JointState, "/joint_states", lambda raw: self.joint_states.add(raw),
                                     OBSERVER_DEPTH, raw=True)
            node.create_subscription(TFMessage, "/tf", lambda m: self.transforms.update(tf_message_keys(m)),
                                     OBSERVER_DEPTH)
            executor = SingleThreadedExecutor(context=context)
            executor.add_node(node)
            count = 0
            while not self.stop.is_set():
                executor.spin_once(timeout_sec=0.01)
                self.last_read_s = time.monotonic() if count != len(self.joint_states) else self.last_read_s
                count = len(self.joint_states)
            executor.shutdown()
            node.destroy_node()
        finally:
            rclpy.shutdown(context=context)


def test_a_reading_client_gets_what_dds_carried_during_a_lockstep_run(ros_domain, tmp_path):  # noqa: F811
    port = free_port()
    observer, reader = Observer(), ClientThread(port, ("/joint_states", "/tf"))
    observer.start()
    reader.start()
    try:
        specs = closed_loop_specs(config_dir("realistic"), plant="sim")
        report = run_recorded([*specs, NodeSpec("swim_viz", "foxglove_node", parameters=(f"port:={port}",))],
                              tmp_path / "run", *READ_MANEUVER, time_scale=1.0, timeout_s=RUN_TIMEOUT_S)
    finally:
        reader.stop.set()
        reader.join(10.0)
        observer.drained()
        observer.stop.set()
        observer.join(10.0)
    assert report.result.error_code == 0
    client = reader.client
    assert client is not None
    states, transforms = client.messages("/joint_states"), client.messages("/tf")
    assert len(states) >= 10 and len(transforms) >= 10, (len(states), len(transforms))
    # what the client received from the observer's first message on: on a loaded host the observer, a process of
    # its own, can match the run's publishers later than the foxglove node and miss the first periods
    first_state_ns = min(header_stamp_ns(payload) for payload in observer.joint_states)
    checked = [message for message in states if header_stamp_ns(message.payload) >= first_state_ns]
    assert len(checked) >= 10, (len(checked), len(states))
    missing = [message for message in checked if message.payload not in observer.joint_states]
    assert not missing, (f"{len(missing)} of {len(checked)} not among the {len(observer.joint_states)} DDS carried",
                         missing[:2], sorted(observer.joint_states)[:2])
    first_transform = min(key[:2] for key in observer.transforms)
    received = [key for key in frame_transforms_keys(client) if key[:2] >= first_transform]
    assert received and set(received) <= observer.transforms, set(received) - observer.transforms


def test_a_client_that_never_reads_leaves_the_lockstep_run_as_it_was(ros_domain, tmp_path):  # noqa: F811
    specs = closed_loop_specs(config_dir("realistic"), plant="sim")
    alone = run_recorded(specs, tmp_path / "alone", *MANEUVER, time_scale=1.0, timeout_s=RUN_TIMEOUT_S)
    port = free_port()
    client = ClientThread(port, read=False, min_channels=13)   # subscribes to every channel, never reads
    client.start()
    try:
        watched = run_recorded([*specs, NodeSpec("swim_viz", "foxglove_node", parameters=(f"port:={port}",))],
                               tmp_path / "watched", *MANEUVER, time_scale=1.0, timeout_s=RUN_TIMEOUT_S)
    finally:
        client.stop.set()
        client.join(10.0)
    assert client.subscribed.is_set() and "/joint_states" in client.topics and "/tf" in client.topics
    assert alone.result.error_code == 0
    # the same periods tracked, each to the same state: the same plan times and the same measures. The count of
    # tracking states may differ: in lock-step the simulator sends a state again when its command is late
    # (sim_node's resend_after_s), and the tracker answers it again at the same plan time, in either run
    assert tracked_plan_times(tmp_path / "watched") == tracked_plan_times(tmp_path / "alone")
    as_run = lambda report: {k: v for k, v in report.to_json().items() if k not in ("wall_time_s", "periods")}  # noqa: E731
    assert as_run(watched) == as_run(alone)


def tracked_plan_times(run_dir) -> list[float]:
    """The distinct plan times of the run's recorded tracking states, in order."""
    from swim_bringup.bag import read_messages
    times = [message.plan_time_s for _, _, message in read_messages(run_dir / "bag", ("/tracking_state",))]
    assert times, run_dir
    return sorted(set(times))
