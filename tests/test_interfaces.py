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


def sample_plan():
    from swim_interfaces.msg import PlannedTrajectory, PrimitiveSegment
    plan = PlannedTrajectory()
    plan.interface_version = PlannedTrajectory.INTERFACE_VERSION
    plan.constrained = True
    plan.lane_radius_m = 0.43
    plan.joint_names = ["alpha", "phi", "theta"]
    times = np.linspace(0.0, 1.0, 126)
    plan.time_from_start_s = times.tolist()
    plan.positions = np.column_stack([0.1 * times, np.sin(times), np.cos(times)]).ravel().tolist()
    plan.velocities = np.zeros(3 * len(times)).tolist()
    plan.foil_accelerations = np.ones(2 * len(times)).tolist()
    plan.feedforward_torques = np.full(2 * len(times), 0.25).tolist()
    plan.lqr_gains = np.linspace(-1.0, 1.0, 2 * 7 * len(times)).tolist()
    plan.sliding_gains = np.linspace(0.0, 2.0, 2 * 7 * len(times)).tolist()
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


def test_rosbags_reads_what_rclpy_serializes():
    """Bags are written with rosbags: its reading of our .msg files must match rclpy's wire format."""
    from rclpy.serialization import serialize_message
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    for name in ("PrimitiveSegment", "PlannedTrajectory"):
        text = (INTERFACE_DIR / "msg" / f"{name}.msg").read_text()
        store.register(get_types_from_msg(text, f"swim_interfaces/msg/{name}"))
    decoded = store.deserialize_cdr(serialize_message(sample_plan()), "swim_interfaces/msg/PlannedTrajectory")
    sent = sample_plan()
    assert decoded.lane_radius_m == 0.43 and decoded.library_digest == "abc"
    np.testing.assert_array_equal(decoded.positions, np.asarray(sent.positions))
    assert decoded.segments[0].alpha_offset_rad == 0.5
    assert decoded.INTERFACE_VERSION == 2


def test_result_codes_follow_follow_joint_trajectory():
    from swim_interfaces.action import ExecutePlan
    result = ExecutePlan.Result
    assert (result.SUCCESSFUL, result.INVALID_PLAN, result.PATH_TOLERANCE_VIOLATED,
            result.GOAL_TOLERANCE_VIOLATED) == (0, -1, -4, -5)
    assert len({result.STATE_LOST, result.PREEMPTED, result.CANCELED}) == 3
