"""A bag recorded with swim_interfaces v2 (PlannedTrajectory and TrackingState before the flow model's fields) still
analyses: its messages are decoded by the definitions the bag carries, not by the installed ones. The v2
definitions are written out here as they were shipped, the bag written with them by rosbags, then analysed."""
import math
from pathlib import Path

import numpy as np
import pytest
from ament_index_python.packages import get_package_share_directory
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from swim_bringup.analysis import analyze, analyze_bag
from swim_bringup.analysis_cli import EXIT_FULL_REPORT, main
from swim_bringup.bag import BagWriter, read_messages
from swim_ros.typestore import swim_typestore

#: swim_interfaces v2's PlannedTrajectory, as shipped (its comments left out)
PLANNED_TRAJECTORY_V2 = """uint32 INTERFACE_VERSION = 2
std_msgs/Header header
uint32 interface_version
bool constrained
float64 lane_radius_m
string[] joint_names
float64[] time_from_start_s
float64[] positions
float64[] velocities
float64[] foil_accelerations
float64[] feedforward_torques
float64[] lqr_gains
float64[] sliding_gains
PrimitiveSegment[] segments
string library_digest
"""
#: swim_interfaces v2's TrackingState, as shipped
TRACKING_STATE_V2 = """std_msgs/Header header
string[] joint_names
trajectory_msgs/JointTrajectoryPoint reference
trajectory_msgs/JointTrajectoryPoint feedback
trajectory_msgs/JointTrajectoryPoint error
float64[] output_torques
float64[] feedforward_torques
bool[] torque_saturated
float64 plan_time_s
float64 time_scale
uint32 segment_index
bool sliding_mode_enabled
"""
PERIOD_S, PERIODS = 0.008, 251
LANE_M, ALPHA_OFFSET_RAD = 0.43, 0.02
JOINTS = ["alpha", "phi", "theta"]
TOPICS = {"plan": "swim_interfaces/msg/PlannedTrajectory", "tracking_state": "swim_interfaces/msg/TrackingState",
          "joint_states": "sensor_msgs/msg/JointState"}


def v2_typestore():
    """ROS 2 Jazzy's types with swim_interfaces v2's PlannedTrajectory and TrackingState (PrimitiveSegment is the
    same in v2 and v3)."""
    store = get_typestore(Stores.ROS2_JAZZY)
    segment = Path(get_package_share_directory("swim_interfaces")) / "msg" / "PrimitiveSegment.msg"
    store.register(get_types_from_msg(segment.read_text(), "swim_interfaces/msg/PrimitiveSegment"))
    store.register(get_types_from_msg(PLANNED_TRAJECTORY_V2, TOPICS["plan"]))
    store.register(get_types_from_msg(TRACKING_STATE_V2, TOPICS["tracking_state"]))
    return store


def v2_messages(store):
    """(topic, log time ns, CDR) of a constrained run ALPHA_OFFSET_RAD behind its plan for 2 s, v2 messages."""
    types = store.types
    Time, Duration = types["builtin_interfaces/msg/Time"], types["builtin_interfaces/msg/Duration"]
    Header = types["std_msgs/msg/Header"]
    empty = np.zeros(0)
    segment = types["swim_interfaces/msg/PrimitiveSegment"]("constrained/cruise/E0.05", "cruise", 0, 0.0, 2.0, 1.0,
                                                            0.0, 0, 2)
    plan = types[TOPICS["plan"]](Header(Time(1, 0), ""), 2, True, LANE_M, JOINTS, np.array([0.0, 2.0]),
                                 np.zeros(6), np.zeros(6), np.zeros(4), np.zeros(4), np.zeros(28), np.zeros(28),
                                 [segment], "v2-library")
    yield "plan", 1, bytes(store.serialize_cdr(plan, TOPICS["plan"]))

    def point(positions):
        return types["trajectory_msgs/msg/JointTrajectoryPoint"](np.array(positions, float), np.zeros(3), empty,
                                                                 empty, Duration(0, 0))
    for k in range(PERIODS):
        time_s = k * PERIOD_S
        reference = [0.3 * time_s, math.sin(time_s), math.cos(time_s)]
        feedback = [reference[0] - ALPHA_OFFSET_RAD, *reference[1:]]
        stamp_ns = 1_000_000_000 + round(time_s * 1e9)
        header = Header(Time(stamp_ns // 1_000_000_000, stamp_ns % 1_000_000_000), "")
        tracking = types[TOPICS["tracking_state"]](
            header, JOINTS, point(reference), point(feedback), point(np.subtract(reference, feedback)),
            np.zeros(2), np.zeros(2), np.zeros(2, bool), time_s, 1.0, 0, True)
        yield "tracking_state", stamp_ns, bytes(store.serialize_cdr(tracking, TOPICS["tracking_state"]))
        joints = types["sensor_msgs/msg/JointState"](header, JOINTS, np.array(feedback), np.zeros(3), empty)
        yield "joint_states", stamp_ns, bytes(store.serialize_cdr(joints, TOPICS["joint_states"]))


def record_v2_run(path: Path, close: bool = True) -> Path:
    """The run recorded as a v2 recorder did: the bag's connections carry the v2 definitions. close False: a
    recorder killed after its last flush (no metadata.yaml)."""
    writer = BagWriter(path, {})
    writer.store = v2_typestore()
    for topic, msgtype in TOPICS.items():
        writer.add_topic(topic, msgtype)
    for topic, stamp_ns, cdr in v2_messages(writer.store):
        writer.write(topic, stamp_ns, cdr)
    if close:
        writer.close()
    else:
        writer.flush()
    return path


def test_the_installed_types_cannot_read_a_v2_message():
    """What makes the bag's own definitions necessary: v2 bytes do not decode as the installed version."""
    store = v2_typestore()
    (_, _, plan), (_, _, tracking) = [m for m, _ in zip(v2_messages(store), range(2))]
    installed = swim_typestore()
    assert installed.types[TOPICS["plan"]].INTERFACE_VERSION == 5
    for cdr, msgtype in ((plan, TOPICS["plan"]), (tracking, TOPICS["tracking_state"])):
        with pytest.raises(Exception):
            installed.deserialize_cdr(cdr, msgtype)


@pytest.mark.parametrize("close", [True, False], ids=["closed", "cut"])
def test_a_v2_bag_analyses_with_its_own_definitions(tmp_path, close, capsys):
    bag = record_v2_run(tmp_path / "bag", close)
    (_, _, plan), = read_messages(bag, ("plan",))
    assert (plan.INTERFACE_VERSION, plan.interface_version, plan.lane_radius_m, plan.library_digest) == \
        (2, 2, LANE_M, "v2-library")
    assert not hasattr(plan, "flow_model")
    tracking = [m for _, _, m in read_messages(bag, ("tracking_state",))]
    assert len(tracking) == PERIODS and not hasattr(tracking[0], "estimated_lag_states")
    analysis = analyze_bag(bag)
    assert analysis.missing == () and analysis.run is not None
    # alpha behind by a constant offset for 2 s at the plan's lane: R_d * offset * sqrt(2 s)
    assert analyze(bag).measures.longitudinal_error_two_norm_m_s05 == pytest.approx(
        LANE_M * ALPHA_OFFSET_RAD * math.sqrt((PERIODS - 1) * PERIOD_S))
    assert main([str(bag)]) == EXIT_FULL_REPORT
    assert "longitudinal_error_two_norm_m_s05" in capsys.readouterr().out
