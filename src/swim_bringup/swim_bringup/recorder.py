"""Topics into a bag, from inside a node.

One raw subscription per topic, each message written as the CDR bytes received, stamped with the wall time of receipt.
RunClient (swim-demo, the tests) and swim-record share it.

The QoS a recording subscription needs is the publishers': a latched topic (transient local) is recorded with a
transient-local subscription, which gets the last message even when it subscribes late; offered_qos_for picks it
from the publishers a node has discovered, as rosbag2's recorder does.
"""
from __future__ import annotations

import importlib
import time
from typing import TYPE_CHECKING, Any, Callable, Sequence

from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime

from swim_bringup.bag import BagWriter

if TYPE_CHECKING:
    from rclpy.node import Node
    from rclpy.qos import QoSProfile
    from rclpy.subscription import Subscription

RECORD_DEPTH = 10000   # the recorder may fall behind a lock-step loop; it must not drop periods


def message_class(type_name: str) -> type:
    """The Python class of a ROS type name such as 'sensor_msgs/msg/JointState'."""
    package, kind, name = type_name.split("/")
    return getattr(importlib.import_module(f"{package}.{kind}"), name)


class TopicRecorder:
    """Raw subscriptions of node writing into bag; subscriptions and latest_cdr are by topic."""

    def __init__(self, node: "Node", bag: BagWriter, clock_ns: Callable[[], int] = time.time_ns) -> None:
        self.node, self.bag, self.clock_ns = node, bag, clock_ns
        self.subscriptions: dict[str, Subscription] = {}
        self.latest_cdr: dict[str, bytes] = {}   # topic -> the latest message recorded, as received

    def record(self, topic: str, type_name: str, qos: "QoSProfile | int") -> None:
        """Subscribe to topic (a type bag already has a connection for) and write what comes into the bag."""

        def write(cdr: bytes) -> None:
            # the executor hands over one message per subscription per wait, at ~0.2 ms of Python each: slower
            # than a lock-step loop on 2 busy cores. So take every message queued now, in one callback.
            # At most a queue's depth per callback: the rest stays queued, and the other topics get their turn.
            self._write(topic, cdr)
            self._take(topic, RECORD_DEPTH - 1)
        self.subscriptions[topic] = self.node.create_subscription(message_class(type_name), topic, write, qos,
                                                                  raw=True)

    def take_queued(self) -> int:
        """Write the messages queued on every subscription into the bag; how many.

        Write the messages queued now on every subscription into the bag (at most RECORD_DEPTH a topic), each
        stamped with the wall time it is taken; returns how many. Polled by a process that only records, in place
        of an executor, which wakes and builds its wait set for each arriving message: several times the cost of
        writing it.
        """
        return sum(self._take(topic, RECORD_DEPTH) for topic in self.subscriptions)

    def _take(self, topic: str, most: int) -> int:
        """Write up to ``most`` of the messages queued on topic's subscription; returns how many."""
        subscription = self.subscriptions[topic]
        with subscription.handle:
            for written in range(most):
                taken = subscription.handle.take_message(subscription.msg_type, True)
                if taken is None:
                    return written
                self._write(topic, taken[0])
        return most

    def _write(self, topic: str, cdr: bytes) -> None:
        self.bag.write(topic, self.clock_ns(), cdr)
        self.latest_cdr[topic] = cdr


def recording_qos(publishers: Sequence[Any]) -> "QoSProfile":
    """The subscription QoS profile that receives what every publisher sends.

    The subscription that receives what every publisher (rclpy TopicEndpointInfo) sends: reliable if all of
    them are, else best effort; transient local if all of them are (a latched topic), else volatile; a queue of
    RECORD_DEPTH (depth 1 for a transient-local topic: its publishers keep their last message for late readers).
    """
    from rclpy.qos import QoSDurabilityPolicy, QoSProfile, QoSReliabilityPolicy
    reliable = all(p.qos_profile.reliability == QoSReliabilityPolicy.RELIABLE for p in publishers)
    latched = bool(publishers) and all(p.qos_profile.durability == QoSDurabilityPolicy.TRANSIENT_LOCAL
                                       for p in publishers)
    return QoSProfile(depth=1 if latched else RECORD_DEPTH,
                      reliability=QoSReliabilityPolicy.RELIABLE if reliable else QoSReliabilityPolicy.BEST_EFFORT,
                      durability=QoSDurabilityPolicy.TRANSIENT_LOCAL if latched else QoSDurabilityPolicy.VOLATILE)


def _qos_time(duration: Any) -> QosTime:
    nanoseconds = int(duration.nanoseconds)
    return QosTime(sec=nanoseconds // 1_000_000_000, nsec=nanoseconds % 1_000_000_000)


def offered_qos(publishers: Sequence[Any]) -> list[Qos]:
    """The publishers' QoS profiles as rosbag2's metadata.yaml lists them.

    They are rosbags' Qos values. A history the graph does not report (a remote publisher's) is written as
    system_default: rosbag2's readers accept no 'unknown'.
    """
    profiles = []
    for publisher in publishers:
        profile = publisher.qos_profile
        history = QosHistory[profile.history.name]
        if history == QosHistory.UNKNOWN:
            history = QosHistory.SYSTEM_DEFAULT
        profiles.append(Qos(history=history, depth=int(profile.depth),
                            reliability=QosReliability[profile.reliability.name],
                            durability=QosDurability[profile.durability.name],
                            deadline=_qos_time(profile.deadline), lifespan=_qos_time(profile.lifespan),
                            liveliness=QosLiveliness[profile.liveliness.name],
                            liveliness_lease_duration=_qos_time(profile.liveliness_lease_duration),
                            avoid_ros_namespace_conventions=bool(profile.avoid_ros_namespace_conventions)))
    return profiles
