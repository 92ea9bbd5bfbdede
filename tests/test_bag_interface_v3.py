"""A bag recorded with swim_interfaces v3 (PlannedTrajectory before the sliding mode's disturbance bound) still
analyses: its messages are decoded by the definitions the bag carries, not by the installed v4 ones. The v3
PlannedTrajectory is written out here as it was shipped (TrackingState and PrimitiveSegment are the same in v3 and
v4), the bag written with it by rosbags, then analysed."""
import math
from pathlib import Path

import numpy as np
import pytest
from ament_index_python.packages import get_package_share_directory
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from swim_bringup.analysis import analyze, analyze_bag
from swim_bringup.bag import BagWriter, read_messages
from swim_ros.typestore import swim_typestore

#: swim_interfaces v3's PlannedTrajectory, as shipped (its comments left out)
PLANNED_TRAJECTORY_V3 = """uint32 INTERFACE_VERSION = 3
std_msgs/Header header
uint32 interface_version
bool constrained
float64 lane_radius_m
string flow_model
string[] joint_names
float64[] time_from_start_s
float64[] positions
float64[] velocities
float64[] foil_accelerations
float64[] feedforward_torques
float64[] lag_states
float64[] lqr_gains
float64[] sliding_gains
PrimitiveSegment[] segments
string library_digest
"""
PLAN = "swim_interfaces/msg/PlannedTrajectory"
TOPICS = {"plan": PLAN, "tracking_state": "swim_interfaces/msg/TrackingState",
          "joint_states": "sensor_msgs/msg/JointState"}
PERIOD_S, PERIODS = 0.008, 126
LANE_M, ALPHA_OFFSET_RAD = 0.43, 0.03
JOINTS = ["alpha", "phi", "theta"]


def v3_typestore():
    """ROS 2 Jazzy's types with swim_interfaces v3's PlannedTrajectory and the installed TrackingState and
    PrimitiveSegment (unchanged since v3)."""
    store = get_typestore(Stores.ROS2_JAZZY)
    share = Path(get_package_share_directory("swim_interfaces")) / "msg"
    store.register(get_types_from_msg((share / "PrimitiveSegment.msg").read_text(),
                                      "swim_interfaces/msg/PrimitiveSegment"))
    store.register(get_types_from_msg((share / "TrackingState.msg").read_text(), TOPICS["tracking_state"]))
    store.register(get_types_from_msg(PLANNED_TRAJECTORY_V3, PLAN))
    return store


def v3_messages(store):
    """(topic, log time ns, CDR): a circulatory v3 plan, then a constrained run ALPHA_OFFSET_RAD behind it for 1 s."""
    types = store.types
    Time, Header = types["builtin_interfaces/msg/Time"], types["std_msgs/msg/Header"]
    segment = types["swim_interfaces/msg/PrimitiveSegment"]("constrained/cruise/E0.05", "cruise", 0, 0.0, 1.0, 1.0,
                                                            0.0, 0, 2)
    plan = types[PLAN](Header(Time(1, 0), ""), 3, True, LANE_M, "circulatory", JOINTS, np.array([0.0, 1.0]),
                       np.zeros(6), np.zeros(6), np.zeros(4), np.zeros(4), np.zeros(4), np.zeros(36), np.zeros(36),
                       [segment], "v3-library")
    yield "plan", 1, bytes(store.serialize_cdr(plan, PLAN))
    empty, lag = np.zeros(0), np.zeros(2)

    def point(positions):
        return types["trajectory_msgs/msg/JointTrajectoryPoint"](positions, np.zeros(3), empty, empty,
                                                                 types["builtin_interfaces/msg/Duration"](0, 0))
    for k in range(PERIODS):
        time_s = k * PERIOD_S
        stamp_ns = 1_000_000_000 + round(time_s * 1e9)
        header = Header(Time(stamp_ns // 1_000_000_000, stamp_ns % 1_000_000_000), "")
        reference = np.array([0.3 * time_s, math.sin(time_s), math.cos(time_s)])
        feedback = reference - np.array([ALPHA_OFFSET_RAD, 0.0, 0.0])
        state = types[TOPICS["tracking_state"]](
            header, JOINTS, point(reference), point(feedback), point(reference - feedback), np.zeros(2), np.zeros(2),
            np.zeros(2, bool), time_s, 1.0, 0, True, lag, lag)
        yield "tracking_state", stamp_ns, bytes(store.serialize_cdr(state, TOPICS["tracking_state"]))
        joints = types["sensor_msgs/msg/JointState"](header, JOINTS, feedback, np.zeros(3), np.zeros(0))
        yield "joint_states", stamp_ns, bytes(store.serialize_cdr(joints, TOPICS["joint_states"]))


def test_the_installed_plan_cannot_read_a_v3_one():
    """What makes the bag's own definitions necessary: v3 bytes do not decode as the installed version."""
    (_, _, plan), = [m for m, _ in zip(v3_messages(v3_typestore()), range(1))]
    installed = swim_typestore()
    assert installed.types[PLAN].INTERFACE_VERSION == 5
    with pytest.raises(Exception):
        installed.deserialize_cdr(plan, PLAN)


def test_a_v3_bag_analyses_with_its_own_definitions(tmp_path):
    writer = BagWriter(tmp_path / "bag", {})
    writer.store = v3_typestore()
    for topic, msgtype in TOPICS.items():
        writer.add_topic(topic, msgtype)
    for topic, stamp_ns, cdr in v3_messages(writer.store):
        writer.write(topic, stamp_ns, cdr)
    writer.close()
    (_, _, plan), = read_messages(tmp_path / "bag", ("plan",))
    assert (plan.INTERFACE_VERSION, plan.interface_version, plan.flow_model) == (3, 3, "circulatory")
    assert not hasattr(plan, "disturbance_bounds_n_m")
    analysis = analyze_bag(tmp_path / "bag")
    assert analysis.missing == () and analysis.run is not None
    # alpha behind by a constant offset at the plan's lane: R_d * offset * sqrt(duration)
    assert analyze(tmp_path / "bag").measures.longitudinal_error_two_norm_m_s05 == pytest.approx(
        LANE_M * ALPHA_OFFSET_RAD * math.sqrt((PERIODS - 1) * PERIOD_S))
