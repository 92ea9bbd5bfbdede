"""A bag read once into a typed record of the run (no ROS, no files written).

What swim-analyze, swim-demo and swim-maneuver measure and draw.

read_bag reads the bag's index and then, in one pass, every message the analysis uses: joint_states (the joint
motion), tracking_state and plan (the last plan tracked: Run), diagnostics (a bridge_node's faults and timing) and
wake_vortices (the last vortex wake, for its figure). A topic is found under its full name (/joint_states), a
relative one (joint_states) or one namespace (/test/joint_states) (find_topic); wake_vortices only under its full
name. What the bag lacks, or holds in a form that cannot be used, is kept in the record as the error that says
which and why; the functions that make each part from its messages (run_of, joint_series, bridge_measures_of)
take decoded messages and need no bag.
"""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any, Iterable, Optional, Sequence

import numpy as np

from swim_bringup.bag import RUN_TOPICS, BagError, BagInfo, TopicMessages, bag_contents, read_topics
from swim_bringup.reports import BridgeMeasures

#: the topic of the vortex wake, read under this name only (sim_node's flow: wake records it)
WAKE_TOPIC = "/wake_vortices"


class MissingTopic(ValueError):
    """A topic the analysis needs that a bag lacks, or holds in a form it cannot use: which, and why."""

    def __init__(self, bag_path: Path, topic: str, reason: str) -> None:
        super().__init__(f"{bag_path}: {topic}: {reason}")
        self.topic, self.reason = topic, reason


def find_topic(info: BagInfo, name: str) -> str:
    """The bag's name for a run topic.

    The bag's name for the run topic `name` (a key of bag.RUN_TOPICS, /joint_states): the topic recorded under
    that full name (swim-demo's, swim-record's and rosbag2's) or its relative one (joint_states) or, failing both,
    under one namespace (/test/joint_states). MissingTopic if there is none, several, one of another type than
    RUN_TOPICS gives, or one without messages.
    """
    bare = name.lstrip("/")
    candidates = ([topic for topic in info.topics if topic.name.lstrip("/") == bare]
                  or [topic for topic in info.topics if topic.name.endswith("/" + bare)])
    if not candidates:
        raise MissingTopic(info.path, name, "not in the bag")
    if len(candidates) > 1:
        raise MissingTopic(info.path, name, f"several topics could be it ({', '.join(t.name for t in candidates)})")
    topic = candidates[0]
    if topic.msgtype != RUN_TOPICS[name]:
        raise MissingTopic(info.path, name, f"{topic.name} is {topic.msgtype}, not {RUN_TOPICS[name]}")
    if topic.message_count == 0:
        raise MissingTopic(info.path, name, f"{topic.name} was recorded without messages")
    return topic.name


@dataclasses.dataclass
class Run:
    """The tracked periods of one plan: n periods of a vehicle of nq joints (the foil's heave and pitch last)."""

    time_s: np.ndarray            # plan time of each tracked period, (n,)
    q: np.ndarray                 # measured, (n, nq); rad, or m for R
    qdot: np.ndarray              # measured, (n, nq); rad/s, or m/s for R
    q_reference: np.ndarray       # the plan's, (n, nq)
    torque: np.ndarray            # commanded (heave, pitch), (n, 2), N m
    saturated: np.ndarray         # (n, 2) bool
    joint_names: list[str]
    lane_radius_m: float          # the plan's lane (the constrained vehicle's R); 0 when the joints include R
    sliding_mode_enabled: bool


def run_of(bag_path: Path, tracking_topic: str, tracking_states: Iterable[Any], plans: Sequence[Any],
           no_plan: str = "") -> Run:
    """The tracked periods of the last plan, and its lane radius.

    The tracked periods of the last plan in tracking_states (swim_interfaces/TrackingState messages in log-time
    order, recorded on tracking_topic of the bag at bag_path); the lane radius from the last of plans
    (PlannedTrajectory messages; no_plan: why there are none). MissingTopic if no period is tracked, the joints have
    no alpha, or the constrained vehicle has no plan; ValueError if the messages do not make a run.
    """
    rows: list[Any] = []   # the tracking_state messages (the typestore's class)
    for message in tracking_states:
        if rows and message.plan_time_s < rows[-1].plan_time_s:
            rows = []   # a new plan started: keep the last one
        rows.append(message)
    if not rows:
        raise MissingTopic(bag_path, "/tracking_state", f"no message of {tracking_topic} could be read")
    if "alpha" not in rows[0].joint_names:
        raise MissingTopic(bag_path, "/tracking_state", f"its joints {list(rows[0].joint_names)} have no alpha")
    lane_radius_m = plans[-1].lane_radius_m if plans else None
    if lane_radius_m is None and "R" not in rows[0].joint_names:
        raise MissingTopic(bag_path, "/plan", f"no plan message ({no_plan}): the constrained vehicle's lane "
                                              f"radius, which turns its alpha errors into metres, is unknown")
    return Run(time_s=np.array([r.plan_time_s for r in rows]),
               q=np.array([r.feedback.positions for r in rows]),
               qdot=np.array([r.feedback.velocities for r in rows]),
               q_reference=np.array([r.reference.positions for r in rows]),
               torque=np.array([r.output_torques for r in rows]),
               saturated=np.array([r.torque_saturated for r in rows], dtype=bool),
               joint_names=list(rows[0].joint_names),
               lane_radius_m=float(lane_radius_m or 0.0),
               sliding_mode_enabled=bool(rows[-1].sliding_mode_enabled))


def bridge_measures_of(diagnostic_arrays: Iterable[Any]) -> Optional[BridgeMeasures]:
    """The bridge's measures of a run from its diagnostics.

    From a bridge_node's diagnostic_msgs/DiagnosticArray messages, in order (None without any of its I/O loop's
    reports): the faults it latched during the run (a latched fault holds the motors at zero until reset: the
    vehicle did not swim as commanded from then on), its count of overrun periods, and its loop's timing from its
    last report that gives it.
    """
    faults: set[str] = set()
    overruns = None
    timing: dict[str, str] = {}
    for array in diagnostic_arrays:
        for status in array.status:
            if status.name.endswith("bridge_node: I/O loop"):
                values = {pair.key: pair.value for pair in status.values}
                faults.update(name for name in values.get("faults", "NONE").split("|") if name != "NONE")
                overruns = int(values.get("overruns", overruns or 0))
                if "worst_lateness_ms" in values:
                    timing = values
    if overruns is None:
        return None

    def number(key: str) -> Optional[float]:
        try:
            value = float(timing[key])
        except (KeyError, ValueError):
            return None
        return value if math.isfinite(value) else None

    return BridgeMeasures(
        bridge_faults="|".join(sorted(faults)) or "NONE", bridge_overruns=overruns,
        bridge_worst_lateness_ms=number("worst_lateness_ms"),
        bridge_overrun_cause=timing.get("worst_lateness_cause"),
        bridge_wake_lateness_p99_ms=number("wake_lateness_p99_ms"),
        bridge_command_latency_p50_ms=number("command_latency_p50_ms"),
        bridge_command_latency_p99_ms=number("command_latency_p99_ms"),
        bridge_command_jitter_p50_ms=number("command_jitter_p50_ms"),
        bridge_command_jitter_p99_ms=number("command_jitter_p99_ms"),
        bridge_state_interval_max_ms=number("state_interval_max_ms"),
        bridge_state_publish_max_ms=number("state_publish_max_ms"))


@dataclasses.dataclass(frozen=True)
class JointSeries:
    """One joint's samples in a bag's joint_states.

    Log time (when the recorder received the message) in s from the topic's first message, position and velocity in the
    joint's unit (rad for a revolute joint, m for a prismatic one such as R; per s for the velocity), each (n,);
    velocity is empty when the messages carry none.
    """

    time_s: np.ndarray
    position: np.ndarray
    velocity: np.ndarray


@dataclasses.dataclass(frozen=True)
class JointStates:
    """A bag's joint_states, by joint.

    A bag's joint_states: the topic, its messages' log times (s from the first message, (messages,)) and each
    joint's samples by name, in the order the joints first appear.
    """

    topic: str
    message_time_s: np.ndarray
    joints: dict[str, JointSeries]


def joint_series(topic: str, messages: Iterable[tuple[int, Any]]) -> JointStates:
    """The joint states of sensor_msgs/JointState messages recorded on a topic.

    The joint states of sensor_msgs/JointState messages recorded on topic, (log time ns, message) each. A
    message whose position (velocity) list is shorter than its names gives no position (velocity) for the joints
    past its end.
    """
    log_ns: list[int] = []
    samples: dict[str, tuple[list[int], list[float], list[float]]] = {}
    for stamp_ns, message in messages:
        log_ns.append(stamp_ns)
        for k, name in enumerate(message.name):
            if k < len(message.position):
                times, positions, velocities = samples.setdefault(name, ([], [], []))
                times.append(stamp_ns)
                positions.append(float(message.position[k]))
                if k < len(message.velocity):
                    velocities.append(float(message.velocity[k]))
    start_ns = min(log_ns, default=0)

    def seconds(stamps: list[int]) -> np.ndarray:
        return (np.array(stamps, dtype=np.int64) - start_ns) * 1e-9
    return JointStates(topic, seconds(log_ns),
                       {name: JointSeries(seconds(times), np.array(positions),
                                          np.array(velocities) if len(velocities) == len(times) else np.zeros(0))
                        for name, (times, positions, velocities) in samples.items()})


@dataclasses.dataclass(frozen=True)
class WakeSnapshot:
    """The last vortex wake recorded, in the tank frame.

    The last vortex wake recorded (swim_interfaces/WakeVortices, tank frame): the vortices' x and y, m, and
    their circulations, m^2/s, counter-clockwise positive, each (k,).
    """

    x_m: np.ndarray
    y_m: np.ndarray
    circulations_m2_s: np.ndarray


@dataclasses.dataclass(frozen=True)
class RecordedBag:
    """A bag read once: its index and each part of the run, or why it is missing.

    A bag read once: its index, the topics whose messages cannot be decoded (topic, why), and each part of the
    run the bag holds, or the error that says why it is not there (MissingTopic for what the bag lacks, BagError
    for what cannot be read, ValueError for messages that do not make a run).
    """

    info: BagInfo
    undecodable: tuple[tuple[str, str], ...]
    joint_states: Optional[JointStates]
    joint_states_error: Optional[Exception]       # set exactly when joint_states is None
    run: Optional[Run]
    run_error: Optional[Exception]                # set exactly when run is None
    bridge: Optional[BridgeMeasures]              # None: no bridge_node's reports in the bag, or bridge_error
    bridge_error: Optional[BagError]              # the bag's diagnostics could not be read
    wake: Optional[WakeSnapshot]                  # None: no wake recorded, or wake_error
    wake_error: Optional[BagError]


def _found(info: BagInfo, name: str) -> str | MissingTopic:
    try:
        return find_topic(info, name)
    except MissingTopic as err:
        return err


def _messages(read: dict[str, TopicMessages], topic: str) -> list[tuple[int, Any]]:
    """The topic's messages; its BagError if they could not be read."""
    messages = read[topic]
    if isinstance(messages, BagError):
        raise messages
    return messages


def read_bag(bag_path: Path) -> RecordedBag:
    """The bag at bag_path, read once.

    The bag at bag_path (a bag folder, or one .mcap or .db3 file), read once. BagError if there is no readable
    bag there; anything else the bag lacks or holds unreadably is the record's error for that part.
    """
    info, undecodable = bag_contents(bag_path)
    joint_topic, tracking_topic, plan_topic, diagnostics_topic = (
        _found(info, name) for name in ("/joint_states", "/tracking_state", "/plan", "/diagnostics"))
    topics = tuple(dict.fromkeys(topic for topic in (joint_topic, tracking_topic, plan_topic, diagnostics_topic)
                                 if isinstance(topic, str)))
    read = read_topics(bag_path, (*topics, WAKE_TOPIC))
    joint_states, joint_states_error = None, None
    try:
        if isinstance(joint_topic, MissingTopic):
            raise joint_topic
        joint_states = joint_series(joint_topic, _messages(read, joint_topic))
    except (MissingTopic, BagError) as err:
        joint_states_error = err
    run, run_error = None, None
    try:
        if isinstance(tracking_topic, MissingTopic):
            raise tracking_topic
        plans, no_plan = ([], plan_topic.reason) if isinstance(plan_topic, MissingTopic) else (
            [message for _, message in _messages(read, plan_topic)], "")
        run = run_of(bag_path, tracking_topic, (message for _, message in _messages(read, tracking_topic)), plans,
                     no_plan)
    except (ValueError, BagError) as err:   # ValueError: MissingTopic, or messages that do not make a run
        run_error = err
    bridge, bridge_error = None, None
    try:
        if isinstance(diagnostics_topic, str):
            bridge = bridge_measures_of(message for _, message in _messages(read, diagnostics_topic))
    except BagError as err:
        bridge_error = err
    wake, wake_error = None, None
    try:
        wake_messages = _messages(read, WAKE_TOPIC)
        if wake_messages:
            last = wake_messages[-1][1]
            wake = WakeSnapshot(np.asarray(last.x_m), np.asarray(last.y_m), np.asarray(last.circulations_m2_s))
    except BagError as err:
        wake_error = err
    return RecordedBag(info, tuple(sorted(undecodable.items())), joint_states, joint_states_error, run, run_error,
                       bridge, bridge_error, wake, wake_error)
