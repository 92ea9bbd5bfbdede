"""The QoS profiles of swim's topics, and publishers and subscriptions made with them, once.

Per-period topics (joint_states, joint_commands, tracking_state, wake_statistics) are made without rclpy's
default QoS event handlers: rclpy gives every publisher and subscription two (incompatible QoS and type), each a
waitable the executor re-adds to its wait set on every spin, in Python; at 125 Hz in lock-step that is a
measurable share of the period.
"""
from __future__ import annotations

from typing import Any, Callable

from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks
from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.qos import QoSDurabilityPolicy, QoSProfile, QoSReliabilityPolicy
from rclpy.subscription import Subscription

#: the per-period topics' QoS, for recorders: 8 s of periods at 8 ms kept by the writer. A reliable keep-last
#: writer overwrites samples a reader has not acknowledged: with a shallow history a recorder behind a lock-step
#: loop, or stalled on a loaded host, would lose periods.
RECORDABLE_QOS = QoSProfile(depth=1000, reliability=QoSReliabilityPolicy.RELIABLE)

#: a topic whose last message a late subscriber still receives (the plan): reliable, transient local, depth 1.
LATCHED_QOS = QoSProfile(depth=1, durability=QoSDurabilityPolicy.TRANSIENT_LOCAL)


def per_period_publisher(node: Node, message_type: Any, topic: str,
                         qos: QoSProfile | int = RECORDABLE_QOS) -> Publisher:
    """A publisher for a topic written every control period: recordable QoS, no event handlers."""
    return node.create_publisher(message_type, topic, qos,
                                 event_callbacks=PublisherEventCallbacks(use_default_callbacks=False))


def per_period_subscription(node: Node, message_type: Any, topic: str, callback: Callable[[Any], None],
                            qos: QoSProfile | int = 10, raw: bool = False) -> Subscription:
    """A subscription to a topic written every control period, without event handlers.

    With raw, the callback gets the serialized message (bytes, CDR) as DDS carried it.
    """
    return node.create_subscription(message_type, topic, callback, qos, raw=raw,
                                    event_callbacks=SubscriptionEventCallbacks(use_default_callbacks=False))
