"""One rig file's limits reach every part: a rig with other stops, planning ranges and torque limits, loaded by
path, is what the planner plans within, the tracker's range guard and motor limits hold, the simulator stops the
joints at and bounds set_state by, and the bridge's safety layer enforces. Each value is checked against the edited
file, and against the shipped rig's, so that a part still reading the shipped values fails."""
import copy
import math

import numpy as np
import pytest
import yaml

from swim_model import VehicleModel, load_rig
from swim_model.rig import default_rig_path
from swim_ros.testing.fixtures import ros_domain  # noqa: F401

SHIPPED = load_rig()
DEGREE = math.pi / 180.0
#: the edited rig: heave stop 45 deg (range 35), pitch stop 70 deg (range 60), max speeds and torque limits changed
EDITS = {"heave_planning_range": (35, "deg"), "heave_hard_stop": (45, "deg"), "pitch_planning_range": (60, "deg"),
         "pitch_hard_stop": (70, "deg"), "heave_max_speed": (20.0, "rad/s"), "hub_max_speed": (2.0, "rad/s"),
         "heave_torque_limit": (1.0, "N*m"), "pitch_torque_limit": (0.4, "N*m")}
HEAVE_STOP_RAD, PITCH_STOP_RAD = 45 * DEGREE, 70 * DEGREE
TORQUE_LIMITS_N_M = (1.0, 0.4)


@pytest.fixture(scope="module")
def rig_path(tmp_path_factory):
    document = yaml.safe_load(default_rig_path().read_text())
    edited = copy.deepcopy(document)
    for key, (value, unit) in EDITS.items():
        edited["limits"][key].update(value=value, unit=unit)
    path = tmp_path_factory.mktemp("rig") / "other_rig.yaml"
    path.write_text(yaml.safe_dump(edited))
    return path


@pytest.fixture(scope="module")
def rig(rig_path):
    rig = load_rig(rig_path)
    assert rig.hard_limits_rad != SHIPPED.hard_limits_rad and rig.torque_limits_n_m != SHIPPED.torque_limits_n_m
    return rig


def expected_stops():
    return ((-HEAVE_STOP_RAD, HEAVE_STOP_RAD), (-PITCH_STOP_RAD, PITCH_STOP_RAD))


def test_the_planner_plans_within_the_rigs_ranges_and_torque_limits(rig):
    from swim_planner.catalog import default_specs
    from swim_planner.primitive_solver import primitive_nlp
    from swim_planner.primitives import PlanningLimits
    limits = PlanningLimits.of(rig)
    assert (limits.heave_range_rad, limits.pitch_range_rad) == pytest.approx((35 * DEGREE, 60 * DEGREE), rel=1e-12)
    # the NLP's default limits are its model's rig's: the range bounds are the edited ranges, not the shipped ones
    spec = next(s for s in default_specs(rig) if s.primitive_id.startswith("constrained/cruise"))
    model = VehicleModel(rig, constrained=spec.constrained, lane_radius_m=spec.lane_radius_m)
    bounds = np.asarray(primitive_nlp(model, spec).ubg, dtype=float).ravel()
    assert np.isclose(bounds, 35 * DEGREE).any() and np.isclose(bounds, 60 * DEGREE).any()
    assert not np.isclose(bounds, 50 * DEGREE).any() and not np.isclose(bounds, 70 * DEGREE).any()
    torque = PlanningLimits.of(rig).torque_fraction * np.asarray(TORQUE_LIMITS_N_M)
    assert np.isclose(bounds, torque[0]).any() and np.isclose(bounds, torque[1]).any()


@pytest.fixture()
def node_arguments(ros_domain, rig_path):  # noqa: F811
    """rclpy initialised with rig_path as every node's parameter: the nodes read it as at a ros2 run."""
    import rclpy
    rclpy.init(args=["--ros-args", "-p", f"rig_path:={rig_path}"])
    try:
        yield
    finally:
        rclpy.shutdown()


def test_the_tracker_guards_the_rigs_stops_with_its_torque_limits(node_arguments):
    from swim_controller.tracker_node import TrackerNode
    node = TrackerNode()
    try:
        node.trigger_configure()
        assert node.range_guard is not None and node.rig is not None, "configure failed"
        assert node.range_guard.hard_limits_rad == expected_stops()
        assert node.rig.torque_limits_n_m == TORQUE_LIMITS_N_M
    finally:
        node.destroy_node()


def test_the_simulator_stops_the_joints_and_bounds_set_state_at_the_rigs_limits(node_arguments):
    from swim_sim.sim_node import SimNode
    node = SimNode()
    try:
        stops = node.plant.hard_limits_rad
        heave, pitch = node.plant.model.joint_names[-2:]
        assert (stops[heave], stops[pitch]) == expected_stops()
        assert node.plant.model.torque_limits() == pytest.approx(TORQUE_LIMITS_N_M)
        assert node.state_bounds.positions[heave][:2] == expected_stops()[0]
        assert node.state_bounds.speeds[heave][0] == 20.0 and node.state_bounds.speeds["alpha"][0] == 2.0
        q = node.plant.rest_positions()
        q[-2] = 50 * DEGREE   # inside the shipped heave stop, outside this rig's
        with pytest.raises(ValueError, match="hard stops"):
            node.state_bounds.check(node.plant.model.joint_names, q, np.zeros_like(q))
    finally:
        node.destroy_node()


def test_the_bridge_enforces_the_rigs_stops_and_torque_limits(node_arguments):
    from swim_hw_bridge.braking import joint_dynamics_bounds
    from swim_hw_bridge.bridge_node import BridgeNode
    node = BridgeNode()
    try:
        node.trigger_configure()
        assert node.loop is not None, "configure failed"
        limits = node.loop.safety.limits
        assert limits.hard_limits_rad == expected_stops()
        assert limits.torque_limits_n_m == TORQUE_LIMITS_N_M
        assert limits.soft_limit_margins_rad == load_rig().limits.soft_margins_rad
        # the braking bound is the model's with these torque limits: lower torque, smaller decelerations
        shipped_bound = joint_dynamics_bounds(SHIPPED)
        assert all(d < s for d, s in zip(limits.dynamics.decelerations_rad_s2, shipped_bound.decelerations_rad_s2))
        # the emulated rig's own stops are the same rig's
        assert tuple(node.device.plant.hard_limits_rad.values()) == expected_stops()
    finally:
        node.trigger_cleanup()
        node.destroy_node()
