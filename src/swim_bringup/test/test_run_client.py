"""The recorder's stamp reader against rclpy's own serialization of the loop's message types; the environment the
run client leaves to the nodes it starts; a closed client's subscriptions leave the ROS graph at once; the run's topic
names, fully qualified as rosbag2 records them."""
import pytest

from swim_ros.testing.fixtures import new_rclpy_context, ros_domain  # noqa: F401


@pytest.mark.parametrize("sec, nanosec", [(0, 0), (63, 184_000_000), (1_795_444_603, 86_991_424), (-5, 999_999_999)])
def test_header_stamp_read_from_cdr_equals_the_messages_stamp(sec, nanosec):
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import JointState
    from swim_interfaces.msg import TrackingState

    from swim_bringup.bag import RUN_TOPICS
    from swim_bringup.run_client import LOOP_TOPICS, header_stamp_ns
    assert {RUN_TOPICS[topic] for topic in LOOP_TOPICS} == {"sensor_msgs/msg/JointState",
                                                           "swim_interfaces/msg/TrackingState"}   # the types below
    for message in (JointState(name=["phi", "theta"], effort=[0.1, -0.2]),
                    TrackingState(joint_names=["alpha", "phi", "theta"], plan_time_s=4.5, output_torques=[1.0, 2.0])):
        message.header.stamp.sec, message.header.stamp.nanosec = sec, nanosec
        message.header.frame_id = "a frame id of some length"   # after the stamp: must not matter
        assert header_stamp_ns(serialize_message(message)) == sec * 1_000_000_000 + nanosec


@pytest.mark.usefixtures("ros_domain")
def test_the_run_client_leaves_the_nodes_it_starts_fast_dds_defaults(tmp_path, monkeypatch):
    """The run client starts the nodes of a run, which inherit its environment: it sets no Fast DDS profile, or
    every node would take planner_node's large shared-memory segment (swim_ros.transport)."""
    import os

    from swim_bringup.run_client import RunClient
    from swim_ros.transport import PROFILE_VARIABLES
    for variable in PROFILE_VARIABLES:
        monkeypatch.delenv(variable, raising=False)
    client = RunClient(tmp_path / "bag")
    try:
        assert not any(os.environ.get(variable) for variable in PROFILE_VARIABLES)
    finally:
        client.close()


@pytest.mark.usefixtures("ros_domain")
def test_a_closed_run_client_leaves_the_graph_at_once(tmp_path):
    """Closing a client takes its recording subscriptions out of the ROS graph, without waiting for the garbage
    collector: a reader left matched is sent every message of the next run's loop. The client is kept
    referenced here, as a caller holding it would."""
    import rclpy
    with new_rclpy_context() as context:
        probe = rclpy.create_node("run_client_probe", context=context)
        try:
            _closed_clients_leave(tmp_path, probe)
        finally:
            probe.destroy_node()


def _closed_clients_leave(tmp_path, probe) -> None:
    import time

    from swim_bringup.run_client import RunClient

    def readers() -> list[str]:
        return [info.node_name for info in probe.get_subscriptions_info_by_topic("/joint_states")]

    def wait_until(condition, timeout_s: float = 10.0) -> bool:
        deadline = time.monotonic() + timeout_s
        while not condition() and time.monotonic() < deadline:
            time.sleep(0.05)
        return condition()
    clients: list[RunClient] = []
    try:
        clients += [RunClient(tmp_path / f"bag_{k}") for k in range(2)]
        assert wait_until(lambda: readers().count("swim_run_client") == 2), readers()
        clients[0].close()
        clients[0].close()   # twice: nothing more happens
        assert wait_until(lambda: readers().count("swim_run_client") == 1), readers()
        clients[1].close()
        assert wait_until(lambda: "swim_run_client" not in readers()), readers()
    finally:
        for client in clients:
            client.close()


def test_the_run_topics_are_fully_qualified_and_the_client_records_none_other(tmp_path):
    """The names a run's bag holds are rosbag2's (/joint_states): RUN_TOPICS and the subsets the client waits on
    name topics in full, and a relative name given to the client is refused before anything starts."""
    from swim_bringup.bag import LATCHED_TOPICS, RUN_TOPICS
    from swim_bringup.run_client import IDLE_LOOP_TOPICS, LOOP_TOPICS, RunClient
    assert all(topic.startswith("/") and "/" not in topic[1:] for topic in RUN_TOPICS)   # the root namespace
    assert set(LATCHED_TOPICS) | set(LOOP_TOPICS) <= set(RUN_TOPICS) and set(IDLE_LOOP_TOPICS) <= set(LOOP_TOPICS)
    with pytest.raises(ValueError, match="joint_states"):
        RunClient(tmp_path / "bag", {"joint_states": RUN_TOPICS["/joint_states"]})
    assert not (tmp_path / "bag").exists()
