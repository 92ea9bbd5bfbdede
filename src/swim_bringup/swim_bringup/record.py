"""The swim-record command: record topics of a running system to a rosbag2 MCAP bag.

swim-record: record topics of a running system to a rosbag2 MCAP bag, like `ros2 bag record` (not installable
here).

    swim-record -a                         every topic (hidden ones, e.g. actions' _action/..., with --include-hidden)
    swim-record joint_states plan /tf     the topics named, each recorded once its publisher is discovered

Each topic is recorded with the QoS its publishers offer (recorder.recording_qos: the latched plan,
robot_description and /tf_static with transient local, so their last message arrives however late the recorder
starts), as the CDR bytes received, stamped with the wall time they are taken from the subscription's queue
(within POLL_PERIOD_S of their receipt: the queues are polled, no executor wakes per message), its publishers'
QoS profiles in the bag's metadata.yaml (rosbag2's format, version 9: `ros2 bag info` reads it). Any ROS 2 Jazzy
message type and ours can be recorded. A line on stderr counts the messages per topic. Ctrl-C (SIGINT) or SIGTERM
closes the bag (summary and metadata.yaml); the bag is flushed every --flush-period s, so a recorder killed outright
(SIGKILL, power loss) leaves a bag whose messages up to the last flush read back (swim_bringup.bag.read_messages,
Foxglove).
"""
from __future__ import annotations

import argparse
import datetime
import signal
import sys
import time
from pathlib import Path
from typing import Any, Optional, TextIO

from swim_bringup.bag import BagError, BagWriter
from swim_bringup.recorder import TopicRecorder, offered_qos, recording_qos

#: how often the graph is searched for the topics still to record: a new publisher is found within half a second
DISCOVERY_PERIOD_S = 0.5
#: the default time between flushes to disk: what a killed recorder can lose
FLUSH_PERIOD_S = 1.0
#: how often the line of counts is rewritten
STATUS_PERIOD_S = 1.0
#: how often the subscriptions' queues are emptied into the bag: messages are stamped this late at most, and queue
#: up to recorder.RECORD_DEPTH a topic meanwhile (a 125 Hz topic fills 3 slots)
POLL_PERIOD_S = 0.02


def hidden(topic: str) -> bool:
    """A hidden topic: a name component starting with '_' (ROS 2's convention, e.g. an action's _action/status)."""
    return any(part.startswith("_") for part in topic.split("/"))


class Recording:
    """The recorder's node, bag and subscriptions: topics are added as their publishers appear in the graph."""

    def __init__(self, bag_path: Path, topics: list[str], all_topics: bool, include_hidden: bool,
                 status: TextIO) -> None:
        import rclpy
        self.wanted, self.all_topics, self.include_hidden, self.status = topics, all_topics, include_hidden, status
        self.context = rclpy.Context()
        rclpy.init(context=self.context, signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
        # never spun (TopicRecorder.take_queued polls the subscriptions), so it offers no parameter services
        self.node = rclpy.create_node("swim_record", context=self.context, start_parameter_services=False)
        self.bag: Optional[BagWriter] = BagWriter(bag_path, {})
        self.recorder = TopicRecorder(self.node, self.bag)
        self.skipped: set[str] = set()

    def discover(self) -> None:
        """Subscribe to every wanted topic whose publishers are now known (its type and QoS come from them)."""
        assert self.bag is not None
        for topic, types in self.node.get_topic_names_and_types():
            if topic in self.recorder.subscriptions or topic in self.skipped:
                continue
            if not (topic in self.wanted or topic.lstrip("/") in self.wanted or "/" + topic in self.wanted
                    or self.all_topics and (self.include_hidden or not hidden(topic))):
                continue
            publishers = self.node.get_publishers_info_by_topic(topic)
            if not publishers:
                continue
            if len(types) != 1:
                self._skip(topic, f"published with {len(types)} types ({', '.join(types)})")
                continue
            try:
                self.bag.add_topic(topic, types[0], offered_qos(publishers))
            except BagError as err:
                self._skip(topic, str(err))
                continue
            self.recorder.record(topic, types[0], recording_qos(publishers))

    def _skip(self, topic: str, reason: str) -> None:
        self.skipped.add(topic)
        print(f"\nswim-record: not recording {topic}: {reason}", file=self.status)

    def status_line(self) -> str:
        """The topics recorded and their message counts, one line."""
        assert self.bag is not None
        counts = ", ".join(f"{topic} {count}" for topic, count in sorted(self.bag.counts.items()))
        return f"recording {len(self.bag.counts)} topics: {counts or 'none yet'}"

    def close(self) -> None:
        """Close the bag (summary and metadata.yaml) and leave DDS; safe to call twice."""
        import rclpy
        if self.bag is not None:
            self.bag.close()
            self.bag = None
        rclpy.try_shutdown(context=self.context)


def parse_arguments(argv: Optional[list[str]]) -> argparse.Namespace:
    """The command line of swim-record, parsed."""
    parser = argparse.ArgumentParser(prog="swim-record", description=__doc__.splitlines()[0])
    parser.add_argument("topics", nargs="*", help="topics to record (with or without the leading /)")
    parser.add_argument("-a", "--all", action="store_true", help="record every topic, as it appears")
    parser.add_argument("--include-hidden", action="store_true", help="with -a: hidden topics too")
    parser.add_argument("-o", "--output", type=Path, default=None, help="bag folder (default rosbag2_<time>)")
    parser.add_argument("--flush-period", type=float, default=FLUSH_PERIOD_S,
                        help="seconds between writes to disk (what a killed recorder can lose)")
    args = parser.parse_args(argv)
    if not args.topics and not args.all:
        parser.error("name topics to record, or -a for all")
    if not args.flush_period > 0.0:
        parser.error("--flush-period must be above zero")
    return args


class StopRequest:
    """A stop request set by SIGINT or SIGTERM.

    Set by SIGINT or SIGTERM; the recording loop ends at its next turn (within POLL_PERIOD_S), never in the
    middle of writing a message.
    """

    def __init__(self) -> None:
        self.requested = False
        for signum in (signal.SIGINT, signal.SIGTERM):
            signal.signal(signum, self._request)

    def _request(self, signum: int, frame: Any) -> None:
        self.requested = True


def main(argv: Optional[list[str]] = None) -> int:
    """The swim-record command; its exit status."""
    args = parse_arguments(argv)
    bag_path = args.output or Path(datetime.datetime.now().strftime("rosbag2_%Y_%m_%d-%H_%M_%S"))
    if bag_path.exists():
        print(f"swim-record: {bag_path} exists; choose another -o", file=sys.stderr)
        return 2
    recording = Recording(bag_path, list(args.topics), args.all, args.include_hidden, sys.stderr)
    stop = StopRequest()
    live = sys.stderr.isatty()
    print(f"swim-record: recording to {bag_path}", file=sys.stderr)
    try:
        next_discovery = next_flush = next_status = time.monotonic()
        while not stop.requested:
            now = time.monotonic()
            if now >= next_discovery:
                recording.discover()
                next_discovery = now + DISCOVERY_PERIOD_S
            if now >= next_flush:
                assert recording.bag is not None
                recording.bag.flush()
                next_flush = now + args.flush_period
            if now >= next_status:
                print(("\r" if live else "") + recording.status_line(), end="" if live else "\n", file=sys.stderr,
                      flush=True)
                next_status = now + STATUS_PERIOD_S
            recording.recorder.take_queued()
            time.sleep(POLL_PERIOD_S)
        recording.recorder.take_queued()   # what arrived since the last turn
    finally:
        line = recording.status_line()
        recording.close()
    print(("\n" if live else "") + f"swim-record: {line}; bag closed: {bag_path}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
