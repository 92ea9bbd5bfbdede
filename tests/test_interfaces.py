"""swim_interfaces: documented field by field, built, carried over DDS, and readable by rosbags."""
import re

import numpy as np
import pytest
from conftest import MESSAGE_TIMEOUT_S, WORKSPACE

INTERFACE_DIR = WORKSPACE / "src" / "swim_interfaces"
FIELD = re.compile(r"^\s*([A-Za-z_][\w/]*(\[\d*\])?)\s+([a-z_][a-z0-9_]*)\s*(=.*)?$")


def interface_files():
    return sorted(p for d in ("msg", "srv", "action") for p in (INTERFACE_DIR / d).iterdir())


@pytest.mark.parametrize("path", interface_files(), ids=lambda p: p.name)
def test_every_field_is_documented(path):
    for number, line in enumerate(path.read_text().splitlines(), 1):
        code, _, comment = line.partition("#")
        if code.strip() in ("", "---") or "=" in code:
            continue
        assert FIELD.match(code), f"{path.name}:{number}: not a field: {line!r}"
        assert comment.strip(), f"{path.name}:{number}: field without a comment: {line!r}"


def sample_plan(flow_model="ideal"):
    """A constrained plan of 126 samples; with the circulatory flow, its lag states and gains of n = 9."""
    from swim_interfaces.msg import PlannedTrajectory, PrimitiveSegment
    plan = PlannedTrajectory()
    plan.interface_version = PlannedTrajectory.INTERFACE_VERSION
    plan.constrained = True
    plan.lane_radius_m = 0.43
    plan.flow_model = flow_model
    plan.joint_names = ["alpha", "phi", "theta"]
    times = np.linspace(0.0, 1.0, 126)
    n = 7 if flow_model == "ideal" else 9
    plan.time_from_start_s = times.tolist()
    plan.positions = np.column_stack([0.1 * times, np.sin(times), np.cos(times)]).ravel().tolist()
    plan.velocities = np.zeros(3 * len(times)).tolist()
    plan.foil_accelerations = np.ones(2 * len(times)).tolist()
    plan.feedforward_torques = np.full(2 * len(times), 0.25).tolist()
    if flow_model == "circulatory":
        plan.lag_states = np.column_stack([0.01 * times, -0.02 * times]).ravel().tolist()
    plan.lqr_gains = np.linspace(-1.0, 1.0, 2 * n * len(times)).tolist()
    plan.sliding_gains = np.linspace(0.0, 2.0, 2 * n * len(times)).tolist()
    plan.segments = [PrimitiveSegment(primitive_id="constrained/cruise/E0.05", primitive_type="cruise",
                                      start_time_s=0.0, duration_s=1.0, time_scale=1.2, alpha_offset_rad=0.5,
                                      first_sample=0, sample_count=len(times))]
    plan.library_digest = "abc"
    return plan


def test_plan_travels_over_dds(rclpy_context):
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import QoSDurabilityPolicy, QoSProfile
    from swim_interfaces.msg import PlannedTrajectory

    from swim_ros.calls import spin_until

    qos = QoSProfile(depth=1, durability=QoSDurabilityPolicy.TRANSIENT_LOCAL)
    sender = rclpy.create_node("plan_sender", context=rclpy_context)
    receiver = rclpy.create_node("plan_receiver", context=rclpy_context)
    received = []
    receiver.create_subscription(PlannedTrajectory, "plan", received.append, qos)
    sender.create_publisher(PlannedTrajectory, "plan", qos).publish(sample_plan())
    executor = SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(receiver)
    spin_until(executor, lambda: bool(received), MESSAGE_TIMEOUT_S)
    executor.shutdown()
    sender.destroy_node()
    receiver.destroy_node()
    assert received, f"no plan arrived over DDS within {MESSAGE_TIMEOUT_S:.0f} s"
    got, sent = received[0], sample_plan()
    assert got.segments[0].primitive_id == sent.segments[0].primitive_id
    assert got.segments[0].time_scale == 1.2
    np.testing.assert_array_equal(np.asarray(got.positions), np.asarray(sent.positions))
    assert list(got.joint_names) == ["alpha", "phi", "theta"]


def sample_tracking_state(flow_model):
    from swim_interfaces.msg import TrackingState
    state = TrackingState(joint_names=["alpha", "phi", "theta"], output_torques=[0.1, -0.2], plan_time_s=1.5,
                          time_scale=1.2, segment_index=3, sliding_mode_enabled=True)
    if flow_model == "circulatory":
        state.estimated_lag_states, state.planned_lag_states = [0.01, -0.02], [0.015, -0.025]
    return state


@pytest.mark.parametrize("flow_model", ["ideal", "circulatory"])
def test_rosbags_reads_what_the_nodes_publish(rclpy_context, flow_model):
    """Bags hold the CDR bytes a raw subscription receives (swim_bringup.recorder) and are read with rosbags from
    our .msg files: both must agree on the layout, empty arrays included (an ideal-flow plan's lag states).
    (rclpy.serialization.serialize_message is not the reference: with rmw_fastrtps it sizes its buffer by an
    estimate that counts alignment for empty float64[] fields, so its bytes can end with padding rosbags refuses.)"""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore
    from swim_interfaces.msg import PlannedTrajectory, TrackingState

    from swim_ros.calls import spin_until

    store = get_typestore(Stores.ROS2_JAZZY)
    for name in ("PrimitiveSegment", "PlannedTrajectory", "TrackingState"):
        text = (INTERFACE_DIR / "msg" / f"{name}.msg").read_text()
        store.register(get_types_from_msg(text, f"swim_interfaces/msg/{name}"))
    node = rclpy.create_node("raw_reader", context=rclpy_context)
    received = {}
    sent = {"plan": sample_plan(flow_model), "tracking_state": sample_tracking_state(flow_model)}
    types = {"plan": PlannedTrajectory, "tracking_state": TrackingState}
    publishers = {}
    for topic, message_type in types.items():
        node.create_subscription(message_type, topic, lambda raw, topic=topic: received.setdefault(topic, raw), 10,
                                 raw=True)
        publishers[topic] = node.create_publisher(message_type, topic, 10)
    executor = SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(node)

    def all_received():
        for topic, publisher in publishers.items():
            if topic not in received:
                publisher.publish(sent[topic])
        return len(received) == len(types)
    spin_until(executor, all_received, MESSAGE_TIMEOUT_S)
    executor.shutdown()
    node.destroy_node()
    assert len(received) == len(types), f"not all arrived over DDS within {MESSAGE_TIMEOUT_S:.0f} s: {received}"
    plan = store.deserialize_cdr(received["plan"], "swim_interfaces/msg/PlannedTrajectory")
    assert plan.lane_radius_m == 0.43 and plan.library_digest == "abc" and plan.flow_model == flow_model
    np.testing.assert_array_equal(plan.positions, np.asarray(sent["plan"].positions))
    np.testing.assert_array_equal(plan.lag_states, np.asarray(sent["plan"].lag_states))
    np.testing.assert_array_equal(plan.lqr_gains, np.asarray(sent["plan"].lqr_gains))
    assert plan.segments[0].alpha_offset_rad == 0.5
    assert plan.INTERFACE_VERSION == 5
    state = store.deserialize_cdr(received["tracking_state"], "swim_interfaces/msg/TrackingState")
    assert state.plan_time_s == 1.5 and state.segment_index == 3
    for field in ("output_torques", "estimated_lag_states", "planned_lag_states"):
        np.testing.assert_array_equal(getattr(state, field), np.asarray(getattr(sent["tracking_state"], field)))


def test_result_codes_follow_follow_joint_trajectory():
    from swim_interfaces.action import ExecutePlan
    result = ExecutePlan.Result
    assert (result.SUCCESSFUL, result.INVALID_PLAN, result.PATH_TOLERANCE_VIOLATED,
            result.GOAL_TOLERANCE_VIOLATED) == (0, -1, -4, -5)
    assert len({result.STATE_LOST, result.PREEMPTED, result.CANCELED}) == 3
