"""foxglove_node: the running system, live in the Foxglove app, and a maneuver and the e-stop from it.

Channels, services, the sampling of the per-period topics, the bounds that keep a slow client from slowing the
loop, and why the server listens on loopback: see docs/visualization.md, section "Foxglove live: foxglove_node".
Parameters: src/swim_viz/README.md, section "Nodes and parameters (read at start)".
"""
from __future__ import annotations

import dataclasses
import json
import re
import threading
import time
import urllib.parse
from pathlib import Path
from typing import Any, Callable, Optional

import foxglove
import rclpy
from action_msgs.msg import GoalStatus, GoalStatusArray
from diagnostic_msgs.msg import DiagnosticArray
from foxglove import Capability, MessageSchema, Schema, Service, ServiceSchema
from foxglove.channels import FrameTransformsChannel, LogChannel, SceneUpdateChannel
from foxglove.messages import (
    FrameTransform,
    FrameTransforms,
    Log,
    LogLevel,
    Quaternion,
    SceneUpdate,
    Timestamp,
    Vector3,
)
from foxglove.websocket import ServerListener
from rclpy.action.client import qos_profile_action_status_default
from rclpy.node import Node
from rclpy.qos import QoSProfile, QoSReliabilityPolicy
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool, String
from std_srvs.srv import Trigger
from swim_interfaces.action import PerformManeuver
from swim_interfaces.msg import PlannedTrajectory, TrackingState, WakeStatistics, WakeVortices
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import Marker, MarkerArray

from swim_ros.calls import (
    ActionClient,
    CallFailed,
    GoalStatusWatch,
    ServedElsewhere,
    call_service,
    cancel_goal,
    goal_result,
    send_goal,
)
from swim_ros.entry import run_node
from swim_ros.parameters import NodeSettings, ParameterSpec, positive
from swim_ros.qos import LATCHED_QOS, per_period_subscription
from swim_ros.typestore import message_definition
from swim_viz.live import (
    MANEUVER_REQUEST_SCHEMA,
    LogLine,
    RateGate,
    fault_changes,
    parse_maneuver_request,
    path_entity,
    wake_entity,
)

PARAMETERS = (
    ParameterSpec("host", "127.0.0.1", "the address the server listens on (0.0.0.0: every interface; the server has "
                  "no authentication)", read_only=True),
    ParameterSpec("port", 8765, "the server's TCP port (8765: Foxglove's default; 0: any free port, logged)",
                  range=(0, 65535), read_only=True),
    ParameterSpec("state_rate_hz", 30.0, "how often the per-period streams (joint_states, joint_commands, "
                  "tracking_state, wake_statistics) are sampled, each its newest message, and the most /tf messages "
                  "a second", range=(1.0, 1000.0), read_only=True),
    ParameterSpec("scene_rate_hz", 5.0, "the most updates a second of the scene and of wake_vortices; 0: every one",
                  range=(0.0, 1000.0), read_only=True),
    ParameterSpec("message_backlog", 256, "the most messages queued per client before the oldest are dropped",
                  range=(1, 100000), read_only=True),
    ParameterSpec("maneuver_start_timeout_s", 120.0, "how long perform_maneuver waits for its plan to be tracked "
                  "(planning, and a model build the first time), s", range=(0.0, 3600.0), read_only=True,
                  check=positive),
)


@dataclasses.dataclass(frozen=True)
class FoxgloveSettings:
    """PARAMETERS' values (swim_ros.parameters.NodeSettings)."""

    host: str
    port: int
    state_rate_hz: float
    scene_rate_hz: float
    message_backlog: int
    maneuver_start_timeout_s: float


#: the ROS topics sent as they are: name -> (type, its class, per-period stream: sampled at state_rate_hz)
FORWARDED_TOPICS: dict[str, tuple[str, Any, bool]] = {
    "/joint_states": ("sensor_msgs/msg/JointState", JointState, True),
    "/joint_commands": ("sensor_msgs/msg/JointState", JointState, True),
    "/tracking_state": ("swim_interfaces/msg/TrackingState", TrackingState, True),
    "/wake_statistics": ("swim_interfaces/msg/WakeStatistics", WakeStatistics, True),
    "/plan": ("swim_interfaces/msg/PlannedTrajectory", PlannedTrajectory, False),
    "/diagnostics": ("diagnostic_msgs/msg/DiagnosticArray", DiagnosticArray, False),
    "/robot_description": ("std_msgs/msg/String", String, False),
    "/markers": ("visualization_msgs/msg/MarkerArray", MarkerArray, False),
    "/wake_vortices": ("swim_interfaces/msg/WakeVortices", WakeVortices, False),
}
#: the sampled topics' readers: best effort, the newest message only
SAMPLED_QOS = QoSProfile(depth=1, reliability=QoSReliabilityPolicy.BEST_EFFORT)
#: the ROS topics read whether or not a client watches: what the log and the asset handler need
ALWAYS_READ = ("/diagnostics", "/robot_description")
#: the ROS topics a derived channel is made from: channel -> the ROS topics it needs
DERIVED_FROM = {"/tf": ("/tf",), "/tf_static": ("/tf_static",), "/scene": ("/markers", "/wake_vortices")}
#: how often the ROS subscriptions are brought in line with the clients' (s): a new client's first messages come
#: this much later at most
SUBSCRIPTION_SYNC_PERIOD_S = 0.1
#: the per-period topics, sampled rather than called back
SAMPLED_TOPICS = frozenset(topic for topic, (_, _, per_period) in FORWARDED_TOPICS.items() if per_period)
#: the latched topics: a client that subscribes late gets the last message (sent again to every subscriber of it)
LATCHED_TOPICS = ("/plan", "/robot_description")
#: the frame the scene is drawn in (swim_viz.frames)
SCENE_FRAME = "tank"
#: the tracker's action, whose goals the log follows
TRACKER_ACTION = "execute_plan"
GOAL_STATUS_NAMES = {GoalStatus.STATUS_ACCEPTED: "accepted", GoalStatus.STATUS_EXECUTING: "executing",
                     GoalStatus.STATUS_CANCELING: "canceling", GoalStatus.STATUS_SUCCEEDED: "succeeded",
                     GoalStatus.STATUS_CANCELED: "canceled", GoalStatus.STATUS_ABORTED: "aborted"}
TERMINAL_STATUSES = (GoalStatus.STATUS_SUCCEEDED, GoalStatus.STATUS_CANCELED, GoalStatus.STATUS_ABORTED)
LOG_LEVELS = {"info": LogLevel.Info, "warning": LogLevel.Warning, "error": LogLevel.Error}
#: how often a waiting service call looks at its goal, s
GOAL_POLL_S = 0.02
#: the empty request of the trigger-like services
EMPTY_REQUEST_SCHEMA = {"type": "object", "additionalProperties": False, "properties": {}}
#: a mesh the URDF names: filename="file://..." or package://
MESH_URI = re.compile(r'filename="([^"]+)"')


def _stamp(time_ns: int) -> Timestamp:
    return Timestamp(sec=time_ns // 1_000_000_000, nsec=time_ns % 1_000_000_000)


def _json_service(name: str, request_schema: dict[str, Any], handler: Callable[[bytes], dict[str, Any]]) -> Service:
    """A service whose request and reply are JSON; a handler's exception is the call's error reply."""
    def handle(request: Any) -> bytes:
        if request.encoding != "json":
            raise ValueError(f"{name} takes JSON requests, got encoding {request.encoding!r}")
        return json.dumps(handler(bytes(request.payload))).encode()
    schema = ServiceSchema(name=f"swim/{name}", request=MessageSchema(
        encoding="json", schema=Schema(name=f"swim/{name}/Request", encoding="jsonschema",
                                       data=json.dumps(request_schema).encode())))
    return Service(name, schema=schema, handler=handle)


def _empty_request(payload: bytes) -> None:
    try:
        request = json.loads(payload or b"{}")
    except (UnicodeDecodeError, json.JSONDecodeError) as err:
        raise ValueError(f"the request is not JSON: {err}") from None
    if request not in ({}, None):
        raise ValueError(f"this service takes an empty request, got {request!r}")


class _ClientTopics(ServerListener):
    """What clients watch (their subscriptions, counted per channel), and the topics they publish on.

    A client's /emergency_stop (JSON {"data": bool}) goes to the bridge's topic.
    """

    def __init__(self, node: "FoxgloveNode") -> None:
        self.node = node
        self.emergency_stop_channels: set[tuple[int, int]] = set()   # (client id, client channel id)

    def on_subscribe(self, client: Any, channel: Any) -> None:
        self.node.watch(channel.topic, +1)

    def on_unsubscribe(self, client: Any, channel: Any) -> None:
        self.node.watch(channel.topic, -1)

    def on_client_advertise(self, client: Any, channel: Any) -> None:
        if channel.topic == "/emergency_stop" and channel.encoding == "json":
            self.emergency_stop_channels.add((client.id, channel.id))

    def on_client_unadvertise(self, client: Any, client_channel_id: int) -> None:
        self.emergency_stop_channels.discard((client.id, client_channel_id))

    def on_message_data(self, client: Any, client_channel_id: int, data: bytes) -> None:
        if (client.id, client_channel_id) not in self.emergency_stop_channels:
            return
        try:
            value = json.loads(data).get("data")
        except (UnicodeDecodeError, json.JSONDecodeError, AttributeError):
            value = None
        if not isinstance(value, bool):
            self.node.log(LogLine("warning", f"/emergency_stop from the app ignored: not {{\"data\": true|false}}: "
                                             f"{bytes(data)[:80]!r}"))
            return
        self.node.emergency_stop_publisher.publish(Bool(data=value))
        if value:
            self.node.log(LogLine("warning", "emergency stop published from the app"))


class FoxgloveNode(Node):
    """The Foxglove server's node (module docstring)."""

    def __init__(self) -> None:
        super().__init__("foxglove_node")
        self.settings = NodeSettings(self, PARAMETERS, FoxgloveSettings).current   # all read-only
        state_rate_hz, scene_rate_hz = self.settings.state_rate_hz, self.settings.scene_rate_hz
        self.maneuver_start_timeout_s = self.settings.maneuver_start_timeout_s
        self._mesh_uris: set[str] = set()
        self._faults: dict[str, str] = {}          # bridge diagnostics name -> its last faults
        self._tracker_goals: dict[bytes, int] = {}  # goal id -> its last status
        self._maneuver: Optional[Any] = None        # the goal handle of the maneuver this server started
        self._maneuver_phase = -1
        self._maneuver_lock = threading.Lock()
        self._tf_gate = RateGate(state_rate_hz)

        self.channels: dict[str, foxglove.Channel] = {}
        self.gates: dict[str, RateGate] = {}
        for topic, (type_name, _, per_period) in FORWARDED_TOPICS.items():
            self.channels[topic] = foxglove.Channel(topic, message_encoding="cdr", schema=Schema(
                name=type_name, encoding="ros2msg", data=message_definition(type_name).encode()))
            self.gates[topic] = RateGate(scene_rate_hz if topic in ("/markers", "/wake_vortices") else 0.0)
        self.tf_channel = FrameTransformsChannel("/tf")
        self.tf_static_channel = FrameTransformsChannel("/tf_static")
        self.scene_channel = SceneUpdateChannel("/scene")
        self.log_channel = LogChannel("/log")

        self.emergency_stop_publisher = self.create_publisher(Bool, "emergency_stop", 10)
        self.emergency_stop_client = self.create_client(Trigger, "emergency_stop")
        self.reset_client = self.create_client(Trigger, "reset_emergency_stop")
        self.maneuver_client = ActionClient(self, PerformManeuver, "perform_maneuver")
        self.maneuver_status = GoalStatusWatch(self, "perform_maneuver")

        self._sampler = rclpy.create_node("foxglove_node_sampler", context=self.context,
                                          start_parameter_services=False)
        self._last_sampled: dict[str, bytes] = {}
        self.create_timer(1.0 / state_rate_hz, self._sample)
        self._ros_subscriptions: dict[str, Any] = {}     # ROS topic -> its subscription, while wanted
        self._watched: dict[str, int] = {}            # channel topic -> clients subscribed to it
        self._watched_lock = threading.Lock()
        self._resend: set[str] = set()               # channels a client has just subscribed to
        self._latched: dict[str, tuple[Any, Any]] = {}   # latched channel -> (its channel, its last message)
        self._sync_subscriptions()
        self.create_timer(SUBSCRIPTION_SYNC_PERIOD_S, self._sync_subscriptions)
        self.create_subscription(GoalStatusArray, f"{TRACKER_ACTION}/_action/status", self._on_tracker_status,
                                 qos_profile_action_status_default)

        services = [
            _json_service("perform_maneuver", MANEUVER_REQUEST_SCHEMA, self._perform_maneuver),
            _json_service("cancel_maneuver", EMPTY_REQUEST_SCHEMA, self._cancel_maneuver),
            _json_service("emergency_stop", EMPTY_REQUEST_SCHEMA,
                          lambda payload: self._trigger(self.emergency_stop_client, payload)),
            _json_service("reset_emergency_stop", EMPTY_REQUEST_SCHEMA,
                          lambda payload: self._trigger(self.reset_client, payload)),
        ]
        self.listener = _ClientTopics(self)
        self.server = foxglove.start_server(
            name="swim", host=self.settings.host, port=self.settings.port, supported_encodings=["json"],
            capabilities=[Capability.Services, Capability.ClientPublish], services=services,
            server_listener=self.listener, asset_handler=self._asset,
            message_backlog_size=self.settings.message_backlog)
        self.get_logger().info(f"Foxglove server on ws://{self.settings.host}:{self.server.port} "
                               f"(no authentication: keep it on a trusted network)")

    def close(self) -> None:
        """Stop the server and destroy the sampling node."""
        self.server.stop()
        self._sampler.destroy_node()

    # --- what the system publishes -------------------------------------------------------------------------------
    def watch(self, channel_topic: str, change: int) -> None:
        """A client subscribed to (+1) or left (-1) a channel (on a server thread)."""
        with self._watched_lock:
            self._watched[channel_topic] = max(self._watched.get(channel_topic, 0) + change, 0)
            if change > 0:
                self._resend.add(channel_topic)

    def wanted_topics(self) -> set[str]:
        """The ROS topics to read now: those always read, and those of every channel a client watches."""
        with self._watched_lock:
            watched = {topic for topic, count in self._watched.items() if count > 0}
        wanted = set(ALWAYS_READ) | (watched & set(FORWARDED_TOPICS))
        for channel, sources in DERIVED_FROM.items():
            if channel in watched:
                wanted.update(sources)
        return wanted

    def _sync_subscriptions(self) -> None:
        """Subscribe to the ROS topics now wanted, and leave the others (on the executor's thread)."""
        with self._watched_lock:
            resend, self._resend = self._resend, set()
        for topic in resend & set(self._latched):   # a latched topic's last message, for the new subscriber
            channel, message = self._latched[topic]
            channel.log(message, log_time=self._now_ns())
        wanted = self.wanted_topics()
        for topic in set(self._ros_subscriptions) - wanted:
            subscription = self._ros_subscriptions.pop(topic)
            (self._sampler if topic in SAMPLED_TOPICS else self).destroy_subscription(subscription)
            self._last_sampled.pop(topic, None)
        for topic in wanted - set(self._ros_subscriptions):
            self._ros_subscriptions[topic] = self._subscribe(topic)

    def _subscribe(self, topic: str) -> Any:
        if topic == "/tf":
            return self.create_subscription(TFMessage, "/tf", self._on_tf, 100)
        if topic == "/tf_static":
            return self.create_subscription(TFMessage, "/tf_static", self._on_tf_static, LATCHED_QOS)
        _, message_type, per_period = FORWARDED_TOPICS[topic]
        if per_period:
            # best effort, as the other viewers read them (the loop's reliable writers keep no history for this
            # one), depth 1: the newest message; on the sampler node, which no executor serves (_sample takes it)
            return per_period_subscription(self._sampler, message_type, topic, lambda _: None, SAMPLED_QOS, raw=True)
        return self.create_subscription(message_type, topic, self._forwarder(topic),
                                         LATCHED_QOS if topic in LATCHED_TOPICS else 10, raw=True)

    def _sample(self) -> None:
        """Each sampled stream's newest message, sent if it is new."""
        for topic, subscription in list(self._ros_subscriptions.items()):
            if topic not in SAMPLED_TOPICS:
                continue
            newest = None
            with subscription.handle:
                while (taken := subscription.handle.take_message(subscription.msg_type, True)) is not None:
                    newest = taken[0]
            if newest is not None and newest != self._last_sampled.get(topic):
                self._last_sampled[topic] = newest
                self.channels[topic].log(newest, log_time=self._now_ns())

    def _now_ns(self) -> int:
        return self.get_clock().now().nanoseconds

    def _forwarder(self, topic: str) -> Callable[[bytes], None]:
        channel, gate = self.channels[topic], self.gates[topic]
        convert = {"/diagnostics": self._on_diagnostics, "/markers": self._on_markers,
                   "/wake_vortices": self._on_wake, "/robot_description": self._on_robot_description}.get(topic)

        def forward(raw: bytes) -> None:
            if not gate.due(time.monotonic()):
                return
            now_ns = self._now_ns()
            channel.log(raw, log_time=now_ns)
            if topic in LATCHED_TOPICS:
                self._latched[topic] = (channel, raw)
            if convert is not None:
                try:
                    convert(raw, now_ns)
                except Exception as err:   # noqa: BLE001 - a message we cannot draw is named, never the end
                    self.get_logger().warning(f"{topic} not converted: {err!r}", throttle_duration_sec=5.0)
        return forward

    def _transforms(self, message: TFMessage) -> FrameTransforms:
        return FrameTransforms(transforms=[FrameTransform(
            timestamp=Timestamp(sec=t.header.stamp.sec, nsec=t.header.stamp.nanosec),
            parent_frame_id=t.header.frame_id, child_frame_id=t.child_frame_id,
            translation=Vector3(x=t.transform.translation.x, y=t.transform.translation.y,
                                z=t.transform.translation.z),
            rotation=Quaternion(x=t.transform.rotation.x, y=t.transform.rotation.y, z=t.transform.rotation.z,
                                w=t.transform.rotation.w)) for t in message.transforms])

    def _on_tf(self, message: TFMessage) -> None:
        if self._tf_gate.due(time.monotonic()):
            self.tf_channel.log(self._transforms(message), log_time=self._now_ns())

    def _on_tf_static(self, message: TFMessage) -> None:
        transforms = self._transforms(message)
        self.tf_static_channel.log(transforms, log_time=self._now_ns())
        self._latched["/tf_static"] = (self.tf_static_channel, transforms)

    def _on_markers(self, raw: bytes, now_ns: int) -> None:
        markers = deserialize_message(raw, MarkerArray).markers
        entities = [path_entity(f"{m.ns}/{m.id}", m.header.frame_id or SCENE_FRAME,
                                [(p.x, p.y, p.z) for p in m.points], (m.color.r, m.color.g, m.color.b, m.color.a),
                                m.scale.x, now_ns)
                    for m in markers if m.type == Marker.LINE_STRIP and m.action == Marker.ADD and len(m.points) >= 2]
        self.scene_channel.log(SceneUpdate(entities=entities), log_time=now_ns)

    def _on_wake(self, raw: bytes, now_ns: int) -> None:
        wake = deserialize_message(raw, WakeVortices)
        entity = wake_entity("wake", SCENE_FRAME, wake.x_m, wake.y_m, wake.circulations_m2_s, now_ns)
        self.scene_channel.log(SceneUpdate(entities=[entity]), log_time=now_ns)

    def _on_robot_description(self, raw: bytes, now_ns: int) -> None:
        description = deserialize_message(raw, String).data
        self._mesh_uris = set(MESH_URI.findall(description))

    def _on_diagnostics(self, raw: bytes, now_ns: int) -> None:
        for status in deserialize_message(raw, DiagnosticArray).status:
            values = {pair.key: pair.value for pair in status.values}
            if "faults" not in values:
                continue
            previous = self._faults.get(status.name, "NONE")
            self._faults[status.name] = values["faults"]
            for line in fault_changes(previous, values["faults"], source=status.name or "bridge"):
                self.log(line, now_ns)

    def _on_tracker_status(self, message: GoalStatusArray) -> None:
        for status in message.status_list:
            goal_id = bytes(status.goal_info.goal_id.uuid)
            if self._tracker_goals.get(goal_id) == status.status:
                continue
            self._tracker_goals[goal_id] = status.status
            name = GOAL_STATUS_NAMES.get(status.status, f"status {status.status}")
            level = "warning" if status.status == GoalStatus.STATUS_ABORTED else "info"
            self.log(LogLine(level, f"tracker: goal {goal_id.hex()[:8]} {name}"))

    def log(self, line: LogLine, now_ns: Optional[int] = None) -> None:
        """A line in the app's log panel (and in this node's log)."""
        now_ns = self._now_ns() if now_ns is None else now_ns
        self.log_channel.log(Log(timestamp=_stamp(now_ns), level=LOG_LEVELS[line.level], message=line.text,
                                 name="swim"), log_time=now_ns)
        logger = self.get_logger()   # one call site per severity: rclpy refuses a site that changes it
        if line.level == "error":
            logger.error(line.text)
        elif line.level == "warning":
            logger.warning(line.text)
        else:
            logger.info(line.text)

    def _asset(self, uri: str) -> Optional[bytes]:
        """A mesh the robot description names (file:// URIs), and nothing else."""
        if uri not in self._mesh_uris or not uri.startswith("file://"):
            return None
        try:
            return Path(urllib.parse.urlparse(uri).path).read_bytes()
        except OSError:
            return None

    # --- what the app asks for (each on a server thread; the executor serves the ROS answers meanwhile) ----------
    def _perform_maneuver(self, payload: bytes) -> dict[str, Any]:
        goal = PerformManeuver.Goal(**parse_maneuver_request(payload))
        with self._maneuver_lock:
            self._maneuver_phase = -1
            handle = send_goal(ServedElsewhere(), self.maneuver_client, goal, self.maneuver_status,
                               feedback_callback=self._on_maneuver_feedback)
            if not handle.accepted:
                raise RuntimeError("maneuver_node refused the goal")
            self._maneuver = handle
        goal_id = bytes(handle.goal_id.uuid)
        self.log(LogLine("info", f"maneuver {goal_id.hex()[:8]} requested from the app: {payload.decode()[:200]}"))
        deadline = time.monotonic() + self.maneuver_start_timeout_s
        while time.monotonic() < deadline:
            status = self.maneuver_status.statuses.get(goal_id, GoalStatus.STATUS_UNKNOWN)
            if self._maneuver_phase == PerformManeuver.Feedback.PHASE_TRACKING and self._maneuver is handle:
                return {"goal_id": goal_id.hex(), "phase": "tracking"}
            if status in TERMINAL_STATUSES:
                return self._ended_maneuver(handle, goal_id, status)
            time.sleep(GOAL_POLL_S)
        raise TimeoutError(f"maneuver {goal_id.hex()[:8]} not tracked within {self.maneuver_start_timeout_s} s; "
                           "it goes on: cancel_maneuver stops it")

    def _ended_maneuver(self, handle: Any, goal_id: bytes, status: int) -> dict[str, Any]:
        """A maneuver that ended before it was tracked: its result, or its error."""
        try:
            result = goal_result(ServedElsewhere(), handle, timeout_s=30.0).result
        except CallFailed:
            raise RuntimeError(f"maneuver {goal_id.hex()[:8]} {GOAL_STATUS_NAMES.get(status)}; its result was "
                               "not received") from None
        if result.error_code != PerformManeuver.Result.SUCCESSFUL:
            self.log(LogLine("warning", f"maneuver {goal_id.hex()[:8]} failed: {result.error_string}"))
            raise RuntimeError(f"maneuver failed ({result.error_code}): {result.error_string}")
        return {"goal_id": goal_id.hex(), "phase": "succeeded"}

    def _on_maneuver_feedback(self, message: Any) -> None:
        self._maneuver_phase = message.feedback.phase

    def _cancel_maneuver(self, payload: bytes) -> dict[str, Any]:
        _empty_request(payload)
        handle = self._maneuver
        if handle is None:
            raise RuntimeError("no maneuver started from this server to cancel")
        response = cancel_goal(ServedElsewhere(), handle)
        self.log(LogLine("info", f"maneuver {bytes(handle.goal_id.uuid).hex()[:8]} canceled from the app"))
        return {"goal_id": bytes(handle.goal_id.uuid).hex(), "canceling": len(response.goals_canceling) > 0}

    def _trigger(self, client: Any, payload: bytes) -> dict[str, Any]:
        _empty_request(payload)
        response = call_service(ServedElsewhere(), client, Trigger.Request())
        self.log(LogLine("warning" if response.success else "error",
                         f"{client.srv_name} from the app: {response.message}"))
        if not response.success:
            raise RuntimeError(f"{client.srv_name} refused: {response.message}")
        return {"success": True, "message": response.message}


def main(args: list[str] | None = None) -> None:
    """Run foxglove_node until shut down; args are ROS's command-line arguments."""
    run_node(FoxgloveNode, args, name="foxglove_node", fatal_errors=(ValueError, RuntimeError, OSError),
             stop=FoxgloveNode.close)


if __name__ == "__main__":
    main()
