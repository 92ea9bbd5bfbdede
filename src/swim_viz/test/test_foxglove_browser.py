"""In a real browser: headless Chromium loads the test page (test/browser: the Foxglove WebSocket protocol's
published JavaScript client, @foxglove/ws-protocol, with @foxglove/rosmsg2-serialization to decode CDR), which
connects to a foxglove.websocket.v1 server, subscribes to /tracking_state and shows the latest message; the test
reads it from the page.

The server here is a stand-in built on foxglove-sdk with foxglove_node's contract: one channel per ROS topic, its
messages the raw ROS 2 CDR bytes, its schema the type's ros2msg definition as rosbag2's MCAP writes it
(rosbags' generate_msgdef). The harness (swim_ros.testing.browser) takes any server's URL.
"""
import threading
from pathlib import Path

import pytest

from swim_ros.testing.browser import LatestMessagePage, browser_unavailable

#: the test page: index.html, page.ts, and dist/page.js that scripts/setup.sh bundles from it
PAGE_DIR = Path(__file__).resolve().parent / "browser"
TOPIC = "/tracking_state"
MESSAGE_TYPE = "swim_interfaces/msg/TrackingState"
#: the stand-in's period between messages: 50 ms, so the page sees many messages within its first second
LOG_PERIOD_S = 0.05
#: the stamps the stand-in logs: message i is stamped FIRST_STAMP_SEC + i s and i * STAMP_STEP_NS ns
FIRST_STAMP_SEC = 1_700_000_000
STAMP_STEP_NS = 1_000_003
#: message i's plan_time_s: a binary fraction plus a third, so that a value that is not carried exactly (a float32
#: on the way, a misaligned read) differs from what was logged
PLAN_TIME_STEP_S = 0.125
PLAN_TIME_OFFSET_S = 1.0 / 3.0
#: the first message through a fresh browser and subscription: about a second here; 30 s covers a loaded host
FIRST_VALUE_TIMEOUT_S = 30.0
#: the last logged message through to the page once logging stops: one round trip; 10 s covers a loaded host
LAST_VALUE_TIMEOUT_S = 10.0
#: how long the stand-in logs before it is stopped, after the page has shown a first message: a few periods more
MORE_MESSAGES = 5


def _reason_to_skip():
    reason = browser_unavailable(PAGE_DIR)
    if reason is not None:
        return reason
    try:
        import foxglove  # noqa: F401
    except ImportError:
        return "foxglove-sdk is not installed (the stand-in server is built on it)"
    return None


REASON_TO_SKIP = _reason_to_skip()
pytestmark = pytest.mark.skipif(REASON_TO_SKIP is not None, reason=str(REASON_TO_SKIP))


def tracking_state_cdr(index: int) -> tuple[bytes, dict]:
    """Message index of the stand-in, as CDR, and what the page must show for it."""
    from builtin_interfaces.msg import Time
    from rclpy.serialization import serialize_message
    from swim_interfaces.msg import TrackingState
    from trajectory_msgs.msg import JointTrajectoryPoint

    sec, nanosec = FIRST_STAMP_SEC + index, index * STAMP_STEP_NS
    plan_time_s = index * PLAN_TIME_STEP_S + PLAN_TIME_OFFSET_S
    message = TrackingState()
    message.header.stamp = Time(sec=sec, nanosec=nanosec)
    message.header.frame_id = "hub"
    # variable-length fields before plan_time_s: the page decodes past them with the schema's layout
    message.joint_names = ["alpha", "R", "phi", "theta"]
    message.reference = JointTrajectoryPoint(positions=[0.1, 0.43, 0.2, 0.3], velocities=[0.0] * 4)
    message.feedback = JointTrajectoryPoint(positions=[0.1, 0.43, 0.21, 0.29])
    message.error = JointTrajectoryPoint(positions=[0.0, 0.0, -0.01, 0.01])
    message.output_torques = [1.5, -0.5]
    message.torque_saturated = [False, True]
    message.plan_time_s = plan_time_s
    message.time_scale = 1.0
    message.segment_index = index % 7
    return bytes(serialize_message(message)), {"sec": sec, "nanosec": nanosec, "value": plan_time_s}


class StandInServer:
    """A foxglove-sdk WebSocket server on loopback at a free port, in a context of its own, with foxglove_node's
    channel for /tracking_state, and a thread logging tracking_state_cdr(0), (1), ... every LOG_PERIOD_S until
    stop_logging."""

    def __init__(self) -> None:
        import foxglove

        from swim_bringup.bag import swim_typestore

        schema_text, _ = swim_typestore().generate_msgdef(MESSAGE_TYPE, ros_version=2)
        self._context = foxglove.Context()
        self._channel = foxglove.Channel(
            TOPIC, message_encoding="cdr", context=self._context,
            schema=foxglove.Schema(name=MESSAGE_TYPE, encoding="ros2msg", data=schema_text.encode()))
        self._server = foxglove.start_server(name="stand-in for foxglove_node", host="127.0.0.1", port=0,
                                             context=self._context)
        self.url = f"ws://127.0.0.1:{self._server.port}"
        self.logged: list[dict] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._log, name="stand-in-logger", daemon=True)
        self._thread.start()

    def _log(self) -> None:
        index = 0
        while not self._stop.is_set():
            cdr, shown = tracking_state_cdr(index)
            self._channel.log(cdr)
            self.logged.append(shown)
            index += 1
            self._stop.wait(LOG_PERIOD_S)

    def stop_logging(self) -> None:
        self._stop.set()
        self._thread.join()

    def close(self) -> None:
        self.stop_logging()
        self._channel.close()
        self._server.stop()


def test_a_browser_shows_the_latest_tracking_state():
    server = StandInServer()
    try:
        with LatestMessagePage(PAGE_DIR, server.url, TOPIC) as page:
            first = page.latest(FIRST_VALUE_TIMEOUT_S)
            assert first["topic"] == TOPIC and first["field"] == "plan_time_s"
            assert {key: first[key] for key in ("sec", "nanosec", "value")} in server.logged
            # a few more messages, then none: the page must come to show exactly the last one logged
            logged_before = len(server.logged)
            page.latest(LAST_VALUE_TIMEOUT_S, accept=lambda shown: shown["count"] >= first["count"] + MORE_MESSAGES)
            server.stop_logging()
            last = server.logged[-1]
            shown = page.latest(LAST_VALUE_TIMEOUT_S, accept=lambda shown: shown["sec"] == last["sec"])
            assert {key: shown[key] for key in ("sec", "nanosec", "value")} == last
            assert first["count"] + MORE_MESSAGES <= shown["count"] <= len(server.logged)
            assert len(server.logged) > logged_before
            assert page.status().startswith(f"subscribed to {TOPIC} ({MESSAGE_TYPE}")
    finally:
        server.close()
