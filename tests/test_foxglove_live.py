"""foxglove_node live, as the Foxglove app meets it: `swim-bringup bridge --foxglove PORT` (the emulated rig in
real time, the planner, the tracker, the maneuver server and the visualization nodes; the latches a shared host
needs raised, swim_bringup.testing) in a ROS domain of the test's, and a client speaking the Foxglove WebSocket
protocol (swim_ros.testing.foxglove_client).

It checks the server's info and advertised channels with their schemas; that the messages a client receives are the
ones DDS carried (joint_states byte for byte, /tf transform for transform, stamps included; those DDS told the test
it lost excepted); that the maneuver
service flies a short maneuver and the e-stop service stops the emulated bridge (its /diagnostics show it); that a
malformed call gets an error and nothing moves; that a message the app publishes on /emergency_stop reaches the
bridge; and, in headless Chromium with the protocol's JavaScript client (swim_viz's browser test page), that the
page shows a tracking_state DDS carried during the maneuver.
"""
from __future__ import annotations

import contextlib
import json
import time
from pathlib import Path

import pytest
from conftest import WORKSPACE
from test_viz_demo_bag import layout_reads

from swim_ros.processes import start_child
from swim_ros.testing.browser import LatestMessagePage, browser_unavailable
from swim_ros.testing.fixtures import new_rclpy_context
from swim_ros.testing.foxglove_client import (
    FoxgloveClient,
    channel_schema,
    decode_protobuf,
    frame_transforms_keys,
    free_port,
    tf_message_keys,
)
from swim_ros.typestore import message_definition

FOXGLOVE_LAYOUT = WORKSPACE / "docs" / "foxglove_layout.json"
#: the test page of swim_viz's browser test (its bundle made by scripts/setup.sh)
PAGE_DIR = WORKSPACE / "src" / "swim_viz" / "test" / "browser"
BROWSER_MISSING = browser_unavailable(PAGE_DIR)

#: the bring-up and the first states: the emulated rig loads its wake's kernels, the tracker builds its models
SET_UP_TIMEOUT_S = 180.0
#: how long messages are compared for, s
COMPARE_S = 3.0
#: a short maneuver of the free vehicle on the emulated rig's lane: start and stop (about 10 s of plan)
SHORT_MANEUVER = {"mode": "sequence", "primitive_ids": ["free/accelerate/R0.43/E0.05", "free/decelerate/R0.43/E0.05"],
                  "path_tolerance_alpha_rad": 1.0, "goal_tolerance_alpha_rad": 0.25, "goal_tolerance_r_m": 0.025}
#: the maneuver's wall time: its plan, and the model the tracker builds for it the first time on a loaded host
MANEUVER_TIMEOUT_S = 300.0
#: the depth of the observer's subscriptions: a reader's keep-last history drops its oldest unread message once full,
#: and the observer reads only while a test spins it; minutes of 125 Hz topics fit, so it loses nothing
OBSERVER_DEPTH = 100_000
FORWARDED = ("/joint_states", "/joint_commands", "/tracking_state", "/plan", "/diagnostics", "/wake_statistics",
             "/wake_vortices", "/robot_description", "/markers")


class Observer:
    """The test's own node on the set's domain: what DDS carries, as it carries it."""

    def __init__(self, context) -> None:
        import rclpy
        from action_msgs.msg import GoalStatusArray  # noqa: F401 - the watch's type, imported where rclpy is up
        from diagnostic_msgs.msg import DiagnosticArray
        from rclpy.executors import SingleThreadedExecutor
        from sensor_msgs.msg import JointState
        from tf2_msgs.msg import TFMessage

        from swim_ros.calls import GoalStatusWatch
        self.node = rclpy.create_node("foxglove_test_observer", context=context)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        from swim_interfaces.msg import TrackingState
        self.joint_states: list[bytes] = []
        self.joint_states_carried: set[bytes] = set()
        self.tracking: set[tuple[int, int, float]] = set()   # (sec, nanosec, plan_time_s) of each tracking_state
        self.transforms: set[tuple] = set()
        self.faults: list[str] = []
        #: the messages DDS told the observer it lost, by topic: a reliable keep-last writer overwrites what a reader
        #: starved by a loaded host has not acknowledged yet
        self.lost: dict[str, int] = {"/joint_states": 0, "/tf": 0}
        self.node.create_subscription(JointState, "/joint_states", self._on_joint_state, OBSERVER_DEPTH, raw=True,
                                      event_callbacks=self._losses("/joint_states"))
        self.node.create_subscription(TFMessage, "/tf", self._on_tf, OBSERVER_DEPTH,
                                      event_callbacks=self._losses("/tf"))
        self.node.create_subscription(TrackingState, "/tracking_state", lambda m: self.tracking.add(
            (m.header.stamp.sec, m.header.stamp.nanosec, m.plan_time_s)), OBSERVER_DEPTH)
        self.node.create_subscription(DiagnosticArray, "/diagnostics", self._on_diagnostics, 100)
        self.maneuvers = GoalStatusWatch(self.node, "perform_maneuver")

    def _losses(self, topic: str):
        from rclpy.event_handler import SubscriptionEventCallbacks

        def count(status) -> None:
            self.lost[topic] = status.total_count
        return SubscriptionEventCallbacks(message_lost=count)

    def _on_joint_state(self, raw: bytes) -> None:
        self.joint_states.append(raw)
        self.joint_states_carried.add(raw)

    def _on_tf(self, message) -> None:
        self.transforms |= tf_message_keys(message)

    def _on_diagnostics(self, message) -> None:
        for status in message.status:
            self.faults += [pair.value for pair in status.values if pair.key == "faults"]

    def spin_for(self, duration_s: float) -> None:
        deadline = time.monotonic() + duration_s
        while time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.02)

    def spin_until(self, done, timeout_s: float, what) -> None:
        """Spin until done() holds; what (a string, or a callable that gives one at the time) names it if not."""
        deadline = time.monotonic() + timeout_s
        while not done():
            assert time.monotonic() < deadline, f"not within {timeout_s} s: {what() if callable(what) else what}"
            self.executor.spin_once(timeout_sec=0.05)

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()


@pytest.fixture(scope="module")
def live(ros_domain, tmp_path_factory):  # noqa: F811 - the session's domain fixture (conftest)
    """The bridge set with foxglove_node, its client and the test's observer, up and swimming at rest.

    The realistic pipeline's parameter files with the bridge's overrun latch and the tracker's stale limit raised
    for a shared host (swim_bringup.testing): the host's stalls latched OVERRUN mid-maneuver with the shipped latch.
    """
    from ament_index_python.packages import get_package_prefix

    from swim_bringup.testing import shared_host_config
    folder = tmp_path_factory.mktemp("foxglove_live")
    config = shared_host_config("realistic", folder)
    port = free_port()
    executable = Path(get_package_prefix("swim_bringup")) / "lib" / "swim_bringup" / "swim-bringup"
    with open(folder / "swim-bringup.out", "w") as output:
        bringup = start_child([str(executable), "bridge", "--foxglove", str(port), "--config", str(config),
                               "--log-dir", str(folder / "logs")], stdout=output, stderr=output)
    try:
        with new_rclpy_context() as context:
            observer = Observer(context)
            try:
                deadline = time.monotonic() + SET_UP_TIMEOUT_S
                client = None
                while client is None:
                    assert bringup.poll() is None, (folder / "swim-bringup.out").read_text()
                    assert time.monotonic() < deadline, "foxglove_node did not listen"
                    try:
                        client = FoxgloveClient(f"ws://127.0.0.1:{port}")
                    except OSError:
                        observer.spin_for(0.5)
                observer.spin_until(lambda: len(observer.joint_states) > 50 and observer.faults, SET_UP_TIMEOUT_S,
                                    "joint_states and diagnostics flowing")
                with client:
                    yield client, observer
            finally:
                observer.close()
    finally:
        bringup.terminate()
        try:
            bringup.wait(60.0)
        except Exception:   # noqa: BLE001 - whatever is left is killed
            bringup.kill()
            bringup.wait()


def test_the_server_says_who_it_is_and_advertises_every_channel_with_its_schema(live):
    client, _ = live
    assert client.wait_for(lambda: client.info and len(client.channels) >= len(FORWARDED) + 4
                           and len(client.services) >= 4, 30.0)
    assert client.connection.subprotocol in ("foxglove.sdk.v1", "foxglove.websocket.v1")
    assert client.info["name"] == "swim"
    assert {"services", "clientPublish"} <= set(client.info["capabilities"])
    by_topic = {channel["topic"]: channel for channel in client.channels.values()}
    for topic in FORWARDED:
        channel = by_topic[topic]
        assert channel["encoding"] == "cdr" and channel["schemaEncoding"] == "ros2msg"
        assert channel["schema"] == message_definition(channel["schemaName"])
    assert by_topic["/tf"]["schemaName"] == "foxglove.FrameTransforms"
    assert by_topic["/scene"]["schemaName"] == "foxglove.SceneUpdate"
    assert by_topic["/log"]["schemaName"] == "foxglove.Log"
    assert {"perform_maneuver", "cancel_maneuver", "emergency_stop", "reset_emergency_stop"} <= set(client.services)


def test_the_meshes_the_urdf_names_are_served_and_nothing_else(live, tmp_path):
    """The app's 3D panel fetches the foil's mesh the URDF names (file://) from the server; any other file is
    refused, an existing one included."""
    import re

    from rclpy.serialization import deserialize_message
    from std_msgs.msg import String
    client, _ = live
    client.subscribe("/robot_description")
    assert client.wait_for(lambda: client.messages("/robot_description"), 30.0)
    urdf = deserialize_message(client.messages("/robot_description")[-1].payload, String).data
    meshes = re.findall(r'filename="(file://[^"]+)"', urdf)
    assert meshes
    for uri in meshes:
        data, error = client.fetch_asset(uri)
        assert data == Path(uri[len("file://"):]).read_bytes() and error == ""
    secret = tmp_path / "secret.txt"
    secret.write_text("not for the app")
    for uri in (f"file://{secret}", "file:///etc/passwd", f"{meshes[0]}/../../../etc/passwd", "package://swim_viz/x"):
        data, error = client.fetch_asset(uri)
        assert data is None and error, uri


def test_the_layout_opens_live_every_topic_and_service_it_reads_is_served(live):
    """docs/foxglove_layout.json on a live connection: the topics of its 3D panel and plots are channels, the
    services of its call-service panels are advertised, and their default requests are well-formed calls."""
    from swim_viz.live import parse_maneuver_request
    client, _ = live
    layout = json.loads(FOXGLOVE_LAYOUT.read_text())
    topics, paths = layout_reads(layout)
    for topic in topics | {topic for topic, _ in paths}:
        client.channel(topic)
    calls = [panel for key, panel in layout["configById"].items() if key.startswith("CallService!")]
    assert {panel["serviceName"] for panel in calls} == {"perform_maneuver", "emergency_stop"}
    assert client.wait_for(lambda: all(panel["serviceName"] in client.services for panel in calls), 10.0)
    maneuver = next(panel for panel in calls if panel["serviceName"] == "perform_maneuver")
    parse_maneuver_request(maneuver["requestPayload"].encode())


def test_a_ros_topic_is_read_only_while_a_client_watches_its_channel(live):
    """foxglove_node subscribes to /joint_commands once a client subscribes to its channel, not before."""
    client, observer = live

    def foxglove_reads() -> bool:
        return any(info.node_name.startswith("foxglove_node")   # the node or its sampler
                   for info in observer.node.get_subscriptions_info_by_topic("/joint_commands"))
    observer.spin_for(1.0)
    assert not foxglove_reads()
    client.subscribe("/joint_commands")
    observer.spin_until(foxglove_reads, 10.0, "foxglove_node subscribed to /joint_commands")
    assert client.wait_for(lambda: len(client.messages("/joint_commands")) > 0, 10.0)


def test_the_client_gets_what_dds_carried_stamps_and_values(live):
    """What the client got, DDS brought the observer too: joint_states byte for byte (the same stamps and values), /tf
    transform for transform. A message the observer lacks is one DDS told it it lost, and never one it got otherwise:
    a message of the same stamp that the observer got with other values is a distortion."""
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import JointState
    client, observer = live
    client.subscribe("/joint_states")
    client.subscribe("/tf")
    deadline = time.monotonic() + COMPARE_S
    while time.monotonic() < deadline:
        client.receive_for(0.05)
        observer.spin_for(0.05)
    states, transforms = client.messages("/joint_states"), client.messages("/tf")
    assert len(states) >= 10 and len(transforms) >= 10, (len(states), len(transforms))
    received = set(frame_transforms_keys(client))

    def stamp(raw: bytes) -> tuple[int, int]:
        header = deserialize_message(raw, JointState).header
        return header.stamp.sec, header.stamp.nanosec

    def missing() -> tuple[list[bytes], set[tuple]]:
        return ([m.payload for m in states if m.payload not in observer.joint_states_carried],
                received - observer.transforms)

    def accounted() -> bool:
        missing_states, missing_transforms = missing()
        # one TFMessage carries the rig's moving transforms at one stamp
        return (len(missing_states) <= observer.lost["/joint_states"]
                and len({key[:2] for key in missing_transforms}) <= observer.lost["/tf"])
    # the observer may still have queued messages to read on a loaded host
    observer.spin_until(accounted, 30.0, lambda: "the client's messages the observer lacks beyond those DDS told it it "
                        f"lost: {[len(part) for part in missing()]} (joint_states, transforms); lost {observer.lost}")
    missing_states, missing_transforms = missing()
    observed_stamps = {stamp(raw) for raw in observer.joint_states}
    assert not [stamp(raw) for raw in missing_states if stamp(raw) in observed_stamps], "joint_states distorted"
    observed_frames = {key[:4] for key in observer.transforms}
    assert not [key for key in missing_transforms if key[:4] in observed_frames], "transforms distorted"


def test_a_malformed_call_gets_an_error_and_nothing_moves(live):
    client, observer = live
    observer.spin_for(0.5)
    maneuvers_before = dict(observer.maneuvers.statuses)
    for payload in (b"not json", b'{"mode": "sequence"}', b'{"mode": "sequence", "primitive_ids": ["x"], '
                                                          b'"time_scale": -1}', b'{"mode": "dance"}', b"[1, 2]"):
        reply = client.call_service("perform_maneuver", payload)
        assert reply.payload is None and reply.failure, payload
    reply = client.call_service("emergency_stop", b'{"now": true}')
    assert reply.payload is None and "empty request" in reply.failure
    reply = client.call_service("cancel_maneuver", b"{}")   # none started from this server
    assert reply.payload is None and "no maneuver" in reply.failure
    observer.spin_for(1.0)
    assert observer.maneuvers.statuses == maneuvers_before
    assert observer.faults[-1] == "NONE"


def test_a_maneuver_from_the_app_flies_and_the_e_stop_stops_the_bridge(live):
    from action_msgs.msg import GoalStatus
    client, observer = live
    client.subscribe("/log")
    with contextlib.ExitStack() as stack:
        # the app in a real browser, watching tracking_state while the maneuver flies (where Chromium is here)
        page = None if BROWSER_MISSING else stack.enter_context(
            LatestMessagePage(PAGE_DIR, f"ws://127.0.0.1:{client.port}", "/tracking_state", field="plan_time_s"))
        reply = client.call_service("perform_maneuver", json.dumps(SHORT_MANEUVER).encode(),
                                    timeout_s=MANEUVER_TIMEOUT_S)
        assert reply.payload is not None, reply.failure
        answer = json.loads(reply.payload)
        assert answer["phase"] in ("tracking", "succeeded")
        goal_id = bytes.fromhex(answer["goal_id"])
        observer.spin_until(lambda: observer.maneuvers.statuses.get(goal_id) in (
            GoalStatus.STATUS_SUCCEEDED, GoalStatus.STATUS_ABORTED, GoalStatus.STATUS_CANCELED), MANEUVER_TIMEOUT_S,
            "the maneuver's end")
        assert observer.maneuvers.statuses[goal_id] == GoalStatus.STATUS_SUCCEEDED
        if page is not None:
            shown = page.latest(accept=lambda shown: shown["value"] > 0.0)
            # the observer may still have queued states to read on a loaded host
            observer.spin_until(lambda: (shown["sec"], shown["nanosec"], shown["value"]) in observer.tracking, 30.0,
                                f"the page's {shown} among the tracking_states DDS carried")

    reply = client.call_service("emergency_stop", b"{}")
    assert reply.payload is not None and json.loads(reply.payload)["success"], reply.failure
    observer.spin_until(lambda: "EMERGENCY_STOP" in observer.faults[-1], 10.0, "the e-stop in /diagnostics")
    reply = client.call_service("reset_emergency_stop", b"{}")
    assert reply.payload is not None, reply.failure
    observer.spin_until(lambda: observer.faults[-1] == "NONE", 10.0, "the e-stop reset in /diagnostics")

    channel = client.advertise("/emergency_stop")   # the app's publish panel
    client.publish(channel, b'{"data": true}')
    observer.spin_until(lambda: "EMERGENCY_STOP" in observer.faults[-1], 10.0, "the e-stop topic's stop")
    assert client.call_service("reset_emergency_stop", b"{}").payload is not None

    # the app's log panel told the story: the maneuver asked for, the tracker's goal, the e-stop latched and cleared
    log = client.channel("/log")

    def lines() -> list[str]:
        return [decode_protobuf(log["schemaName"], channel_schema(log), m.payload).message
                for m in client.messages("/log")]
    expected = (f"maneuver {answer['goal_id'][:8]} requested from the app", "tracker: goal", "succeeded",
                "EMERGENCY_STOP latched, motors off", "faults cleared (EMERGENCY_STOP)")
    assert client.wait_for(lambda: all(any(part in line for line in lines()) for part in expected), 10.0), lines()
