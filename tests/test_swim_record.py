"""swim-record over DDS: rig_state_publisher's latched robot_description and /tf_static and the joint_states
this test publishes, recorded by a swim-record process started after them under their full names (as rosbag2
records them), a burst faster than its polling whole; SIGINT closes the bag (metadata.yaml
as rosbag2 writes it, the publishers' QoS in it), SIGKILL leaves a bag that reads up to its last flush."""
import contextlib
import os
import signal
import subprocess
import time

import pytest
import yaml
from conftest import MESSAGE_TIMEOUT_S, STARTUP_TIMEOUT_S, WORKSPACE, running_node

from swim_ros.processes import start_child

STATES = 200


@contextlib.contextmanager
def recording_all_published(bag, log_path, publisher, *arguments):
    """swim-record -o bag arguments, its output in log_path, matched to publisher's node and its latched topics in;
    then STATES joint_states published and recorded. Yields the recorder's process (SIGKILLed on the way out if
    still running)."""
    node, joint_states, publish = publisher
    command = f"source scripts/env.sh && exec ros2 run swim_bringup swim-record -o {bag} {' '.join(arguments)}"
    with open(log_path, "w") as log:
        recorder = start_child(["bash", "-c", command], cwd=WORKSPACE, stdout=log, stderr=subprocess.STDOUT,
                               start_new_session=True)
        try:
            wait_for_recorder(node, joint_states, log_path)
            publish(STATES)
            wait_for_line(log_path, f"/joint_states {STATES}", MESSAGE_TIMEOUT_S)
            yield recorder
        finally:
            if recorder.poll() is None:
                os.killpg(recorder.pid, signal.SIGKILL)


def wait_for_line(log_path, text, timeout_s):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if text in log_path.read_text():
            return
        time.sleep(0.1)
    pytest.fail(f"no '{text}' in the recorder's output within {timeout_s} s:\n{log_path.read_text()[-2000:]}")


@pytest.fixture()
def publisher(rclpy_context, tmp_path):
    """rig_state_publisher running, and a node of this test that publishes joint_states (reliable, as sim_node)."""
    import rclpy
    from sensor_msgs.msg import JointState

    from swim_ros.qos import RECORDABLE_QOS
    with running_node("swim_viz", "rig_state_publisher", tmp_path / "rig_state_publisher.log",
                      "-p", f"mesh_dir:={tmp_path / 'meshes'}"):
        node = rclpy.create_node("joint_state_source", context=rclpy_context)
        publisher = node.create_publisher(JointState, "joint_states", RECORDABLE_QOS)

        def publish(count, start=0, pause_s=0.002):
            for k in range(start, start + count):
                message = JointState(name=["alpha", "phi", "theta"], position=[1e-3 * k, 0.1, -0.1])
                message.header.stamp.sec, message.header.stamp.nanosec = 1 + k // 125, (k % 125) * 8_000_000
                publisher.publish(message)
                time.sleep(pause_s)
        yield node, publisher, publish
        node.destroy_node()


def wait_for_recorder(node, publisher, bag_log):
    """The recorder's joint_states subscription matched by the publisher, and its latched topics in.
    rig_state_publisher subscribes to joint_states too, so the publisher's count alone does not tell: the graph
    must show the recorder's subscription and the publisher must have matched every subscription there."""
    def recorder_matched():
        readers = node.get_subscriptions_info_by_topic("/joint_states")
        return any(r.node_name == "swim_record" for r in readers) and publisher.get_subscription_count() >= len(readers)
    deadline = time.monotonic() + STARTUP_TIMEOUT_S
    while not recorder_matched() and time.monotonic() < deadline:
        time.sleep(0.1)
    assert recorder_matched(), bag_log.read_text()
    wait_for_line(bag_log, "/robot_description 1", STARTUP_TIMEOUT_S)
    wait_for_line(bag_log, "/tf_static 1", MESSAGE_TIMEOUT_S)


def test_sigint_closes_the_bag_with_rosbag2_metadata(publisher, tmp_path):
    from swim_bringup.bag import RUN_TOPICS, read_messages
    bag, log_path = tmp_path / "bag", tmp_path / "record.log"
    with recording_all_published(bag, log_path, publisher, "joint_states", "robot_description", "/tf_static") \
            as recorder:
        os.killpg(recorder.pid, signal.SIGINT)
        assert recorder.wait(MESSAGE_TIMEOUT_S) == 0, log_path.read_text()
    assert "bag closed" in log_path.read_text()
    info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert info["version"] == 9 and info["storage_identifier"] == "mcap"
    topics = {t["topic_metadata"]["name"]: t for t in info["topics_with_message_count"]}
    assert set(topics) == {"/joint_states", "/robot_description", "/tf_static"}   # named in full, with or without /
    assert set(topics) <= set(RUN_TOPICS)   # as swim-demo's bags name them
    assert topics["/joint_states"]["message_count"] == STATES
    assert topics["/robot_description"]["message_count"] == 1
    assert topics["/robot_description"]["topic_metadata"]["type"] == "std_msgs/msg/String"
    offered = topics["/robot_description"]["topic_metadata"]["offered_qos_profiles"]
    assert [p["durability"] for p in offered] == ["transient_local"]    # the latched publisher's
    assert {p["reliability"] for p in topics["/joint_states"]["topic_metadata"]["offered_qos_profiles"]} == {"reliable"}
    assert info["message_count"] == sum(t["message_count"] for t in topics.values())
    positions = [m.position[0] for _, _, m in read_messages(bag, ("/joint_states",))]
    assert positions == pytest.approx([1e-3 * k for k in range(STATES)])   # every message, in order


def test_a_burst_between_two_polls_is_recorded_whole_and_in_order(publisher, tmp_path):
    """Messages published faster than the recorder polls its queues (swim_bringup.record.POLL_PERIOD_S), up to the
    publisher's history (RECORDABLE_QOS), wait in the subscription's queue and are all written, in order."""
    from swim_bringup.bag import read_messages
    from swim_ros.qos import RECORDABLE_QOS
    burst = RECORDABLE_QOS.depth - 100   # a reliable writer keeps this many for a reader behind it
    bag, log_path = tmp_path / "bag", tmp_path / "record.log"
    _, _, publish = publisher
    with recording_all_published(bag, log_path, publisher, "joint_states", "robot_description", "/tf_static") \
            as recorder:
        publish(burst, start=STATES, pause_s=0.0)
        wait_for_line(log_path, f"/joint_states {STATES + burst}", MESSAGE_TIMEOUT_S)
        os.killpg(recorder.pid, signal.SIGINT)
        assert recorder.wait(MESSAGE_TIMEOUT_S) == 0, log_path.read_text()
    positions = [m.position[0] for _, _, m in read_messages(bag, ("/joint_states",))]
    assert positions == pytest.approx([1e-3 * k for k in range(STATES + burst)])


def test_a_killed_recorder_leaves_a_bag_that_reads_up_to_its_last_flush(publisher, tmp_path):
    from swim_bringup.bag import read_messages
    bag, log_path = tmp_path / "bag", tmp_path / "record.log"
    with recording_all_published(bag, log_path, publisher, "-a", "--flush-period", "0.2") as recorder:
        time.sleep(1.0)   # several flush periods: all of them on disk
        os.killpg(recorder.pid, signal.SIGKILL)
        recorder.wait(MESSAGE_TIMEOUT_S)
    assert not (bag / "metadata.yaml").exists()     # killed: no summary, no metadata
    positions = [m.position[0] for _, _, m in read_messages(bag, ("/joint_states",))]
    assert positions == pytest.approx([1e-3 * k for k in range(STATES)])
    # Foxglove's own reader (mcap, with its ROS 2 decoder) reads the cut file too, linearly (it has no index), up
    # to the same point, where it meets the end of the file
    from mcap.exceptions import EndOfFile
    from mcap.reader import NonSeekingReader
    from mcap_ros2.decoder import DecoderFactory
    decoded = []
    with open(next(bag.glob("*.mcap")), "rb") as stream:
        with pytest.raises(EndOfFile):
            reader = NonSeekingReader(stream, decoder_factories=[DecoderFactory()])
            for _, _, _, message in reader.iter_decoded_messages(topics=["/joint_states"], log_time_order=False):
                decoded.append(message.position[0])
    assert decoded == pytest.approx(positions)
