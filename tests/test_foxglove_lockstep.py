"""A Foxglove client that subscribes to everything and never reads changes nothing of a run: the lock-step closed
loop (sim_node, planner, tracker, the visualization nodes) flown with foxglove_node and such a client gives the
report of the same run without them, key by key (the wall time aside). foxglove_node only subscribes, and drops
what its client does not take."""
from __future__ import annotations

import socket
import threading

from swim_bringup.recorded_run import run_recorded
from swim_bringup.system import closed_loop_specs, config_dir
from swim_ros.processes import NodeSpec
from swim_ros.testing.foxglove_client import FoxgloveClient

#: the paper's constrained start and stop: about 8 s of plan, a few seconds of wall time in lock-step
MANEUVER = (["constrained/accelerate/E0.05", "constrained/decelerate/E0.05"], [1, 1])
#: a lock-step run on a loaded host
RUN_TIMEOUT_S = 300.0


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


class StalledClient(threading.Thread):
    """Connects as soon as the server listens, subscribes to every channel, and then never reads."""

    def __init__(self, port: int) -> None:
        super().__init__(daemon=True)
        self.port, self.subscribed, self.stop = port, threading.Event(), threading.Event()
        self.topics: list[str] = []

    def run(self) -> None:
        while not self.stop.is_set():
            try:
                client = FoxgloveClient(f"ws://127.0.0.1:{self.port}")
                break
            except OSError:
                self.stop.wait(0.1)
        else:
            return
        with client:
            client.wait_for(lambda: len(client.channels) >= 13, 30.0)
            self.topics = sorted(channel["topic"] for channel in client.channels.values())
            for topic in self.topics:
                client.subscribe(topic)
            self.subscribed.set()
            self.stop.wait()


def test_a_client_that_never_reads_leaves_the_lockstep_run_as_it_was(ros_domain, tmp_path):  # noqa: F811
    specs = closed_loop_specs(config_dir("realistic"), plant="sim")
    alone = run_recorded(specs, tmp_path / "alone", *MANEUVER, time_scale=1.0, timeout_s=RUN_TIMEOUT_S)
    port = free_port()
    client = StalledClient(port)
    client.start()
    try:
        watched = run_recorded([*specs, NodeSpec("swim_viz", "foxglove_node", parameters=(f"port:={port}",))],
                               tmp_path / "watched", *MANEUVER, time_scale=1.0, timeout_s=RUN_TIMEOUT_S)
    finally:
        client.stop.set()
        client.join(10.0)
    assert client.subscribed.is_set() and "/joint_states" in client.topics and "/tf" in client.topics
    assert alone.result.error_code == 0
    without_time = lambda report: {k: v for k, v in report.to_json().items() if k != "wall_time_s"}  # noqa: E731
    assert without_time(watched) == without_time(alone)
