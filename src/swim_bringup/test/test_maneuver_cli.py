"""swim-maneuver, the operator's command: its options and exit statuses, the plan summary against the plan's own
arrays, the lane a goal starts from; over DDS against planner_node alone (list, plan and their refusals, the wait
for nodes), against the emulated bridge set of swim-bringup (a refused request moves nothing; the paper's lane
keeping, recorded and analysed; status with the bridge's state and faults), and against the simulator's set (a goal
state flown from where the maneuver before left the vehicle; Ctrl-C mid-maneuver: canceled, exit 130, the bag whole
and analysed; status; a plan from its rest state).

The goal state after another maneuver is flown on the simulator: after its lane keeping the emulated free vehicle
in the vortex wake drifts (the water the 14 cruises set turning moves the hub and the platform along its free
rails, up to 4 cm/s), so whether the next command finds it on a lane depends on how long that command takes to
start, seconds on a loaded host; off its lane maneuver_node refuses the goal, as it must. Each set is brought up,
used for all its checks and stopped inside one module fixture, so no two sets share the module's ROS domain at
once; the tests then check what the fixture kept.
"""
import contextlib
import math
import os
import signal
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from swim_ros.processes import run_child, start_child
from swim_ros.testing.fixtures import MESSAGE_TIMEOUT_S, new_rclpy_context, ros_domain, running_node  # noqa: F401

LANE_KEEPING = (["free/accelerate/R0.43/E0.05", "free/cruise/R0.43/E0.05", "free/decelerate/R0.43/E0.05"],
                [1, 14, 1])   # experiments.PAPER_LANE_KEEPING, as an operator types it
#: a swim-maneuver process: its start (Python imports, DDS discovery: seconds on a loaded 2-core host) and its
#: command; a run's maneuver lasts up to 23 s in real time. 300 s only stops a hung process
COMMAND_TIMEOUT_S = 300.0
#: the wait for nodes given to a command whose nodes run already, or to one that must find none, s
SHORT_WAIT_S = 3.0
#: the set's nodes on a loaded host: 30 s of imports, library loading and discovery at most (the command waits)
SET_STARTUP_WAIT_S = 60.0
#: the cruises of the run the sim set stops by Ctrl-C: 20 of 5 s, 108 s of plan with the accelerate and decelerate,
#: 20-40 s in lock-step
CANCELED_CRUISES = 20
#: how late the host may wake the bridge's I/O loop for a run's tolerances to measure the tracking. The emulated rig
#: integrates its plant over the wall time between reads with the torques held, so a stall is a disturbance: one of
#: 323 ms, with 206 late periods, in the lane keeping's accelerate stirred the wake that left the vehicle 36 mm off
#: its lane at the end. A machine that runs only the rig wakes the loop within milliseconds (docs/realtime.md)
HOST_STALL_BOUND_MS = 100.0
#: a vehicle at rest moves under maneuver_node's rest bound (0.15 rad/s) while its goal is planned and its tracking
#: starts (well under a second): its plan starts within this of the alpha measured when tracking begins
START_ALPHA_TOLERANCE_RAD = 0.05


def swim_maneuver(*arguments: str, env=None) -> subprocess.CompletedProcess:
    """`ros2 run swim_bringup swim-maneuver arguments` in this test's ROS domain; its exit status and output."""
    return run_child(["ros2", "run", "swim_bringup", "swim-maneuver", *arguments], capture_output=True,
                     text=True, timeout_s=COMMAND_TIMEOUT_S, env=dict(os.environ if env is None else env))


def assert_clean_exit(result: subprocess.CompletedProcess, status: int) -> None:
    assert result.returncode == status, result.stdout[-3000:] + result.stderr[-3000:]
    assert "Traceback" not in result.stderr, result.stderr[-3000:]


# ----- pure pieces ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("argv", [
    [], ["fly"], ["plan"], ["run", "--primitives", "a", "b", "--repeats", "1"],
    ["run", "--primitives", "a", "--repeats", "0"], ["plan", "--primitives", "a", "--goal", "free/rest/R0.43"],
    ["plan", "--goal", "free/rest/R0.43", "--repeats", "2"], ["plan", "--primitives", "a", "--goal-alpha", "1"],
    ["run", "--goal", "free/rest/R0.43", "--path-tolerance-alpha", "nan"], ["plan", "--primitives", "a",
                                                                            "--time-scale", "fast"],
    ["status", "--wait", "-1"], ["list", "--wait", "nan"],
])
def test_bad_input_is_a_usage_error(argv, capsys):
    from swim_bringup.maneuver_cli import main
    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2
    assert "usage: swim-maneuver" in capsys.readouterr().err


def test_the_forms_an_operator_types():
    from swim_bringup.maneuver import MODE_GOAL, MODE_SEQUENCE
    from swim_bringup.maneuver_cli import maneuver_goal, parse_arguments
    from swim_bringup.recorded_run import RUN_TOLERANCES
    from swim_bringup.run_client import STARTUP_TIMEOUT_S
    args = parse_arguments(["run", "--primitives", *LANE_KEEPING[0], "--repeats", "1", "14", "1",
                            "--time-scale", "0.9", "--record", "out"])
    goal = maneuver_goal(args)
    assert (goal.mode, goal.primitive_ids, goal.repeat_counts) == (MODE_SEQUENCE, tuple(LANE_KEEPING[0]), (1, 14, 1))
    assert goal.time_scale == 0.9 and goal.tolerances == RUN_TOLERANCES and args.record == Path("out")
    assert args.wait == STARTUP_TIMEOUT_S   # swim-demo's wait for the nodes
    args = parse_arguments(["run", "--goal", "free/rest/R0.48", "--goal-alpha", "6.3", "--goal-tolerance-r", "0"])
    goal = maneuver_goal(args)
    assert (goal.mode, goal.goal_state, goal.goal_alpha_rad, goal.time_scale) == (MODE_GOAL, "free/rest/R0.48", 6.3,
                                                                                  0.0)
    assert goal.tolerances.goal_r_m == 0.0 and goal.tolerances.path_alpha_rad == RUN_TOLERANCES.path_alpha_rad
    assert parse_arguments(["plan", "--primitives", "a", "--time-scale", "nan"]).time_scale != 0.0  # the planner's


def test_each_result_code_has_its_exit_status():
    from swim_interfaces.action import PerformManeuver

    from swim_bringup.maneuver_cli import exit_status_of
    result = PerformManeuver.Result
    assert exit_status_of(result.SUCCESSFUL, False) == 0
    for code in (result.PATH_TOLERANCE_VIOLATED, result.GOAL_TOLERANCE_VIOLATED, result.STATE_LOST,
                 result.PREEMPTED, result.CANCELED):
        assert exit_status_of(code, False) == 1
    for code in (result.INVALID_GOAL, result.PLANNING_FAILED, result.NODE_UNAVAILABLE, result.INVALID_PLAN):
        assert exit_status_of(code, False) == 2
    assert exit_status_of(result.CANCELED, True) == 130
    assert exit_status_of(result.SUCCESSFUL, True) == 0   # it ended before the cancel reached it


def test_the_saturation_risk_thresholds():
    from swim_bringup.maneuver_cli import HIGH_RISK_FRACTION, MODERATE_RISK_FRACTION, saturation_risk
    assert [saturation_risk(f) for f in (0.0, 0.49, 0.5, 0.79, 0.8, 1.2)] == ["low", "low", "moderate", "moderate",
                                                                              "high", "high"]
    assert 0.0 < MODERATE_RISK_FRACTION < HIGH_RISK_FRACTION < 1.0


@pytest.fixture(scope="module")
def library():
    from swim_model import load_rig
    from swim_planner.library import PrimitiveLibrary
    from swim_planner.paths import default_library_path
    return PrimitiveLibrary.load(default_library_path(), load_rig())


def plan_message(library, ids, counts, time_scale=1.0, start_alpha_rad=0.0):
    """The planner's plan of the sequence as planner_node sends it, and the Trajectory it came from."""
    from builtin_interfaces.msg import Time

    from swim_model import load_rig
    from swim_planner.maneuver import concatenate, expand_sequence
    from swim_ros.trajectory_messages import trajectory_to_message
    trajectory = concatenate(library, load_rig(), expand_sequence(ids, counts), time_scale, start_alpha_rad)
    return trajectory_to_message(trajectory, Time(sec=1)), trajectory


@pytest.mark.parametrize("ids, counts, time_scale", [
    (["constrained/accelerate/E0.05", "constrained/cruise/E0.05", "constrained/decelerate/E0.05"], [1, 2, 1], 1.0),
    (["free/accelerate/R0.43/E0.05", "free/cruise/R0.43/E0.05", "free/lane_change/R0.43-R0.48/E0.05",
      "free/decelerate/R0.48/E0.05"], [1, 3, 1, 1], 1.25),
])
def test_the_plan_summary_agrees_with_the_plans_arrays(library, ids, counts, time_scale):
    from swim_bringup.maneuver_cli import PlanSummary, saturation_risk
    from swim_model import load_rig
    limits = load_rig().torque_limits_n_m
    message, trajectory = plan_message(library, ids, counts, time_scale, start_alpha_rad=2.0)
    summary = PlanSummary.of(message, limits)
    assert summary.sequence == tuple(zip(ids, counts))
    assert summary.time_scales == (time_scale,)
    assert summary.duration_s == pytest.approx(sum(library.spec(i).duration_s * n for i, n in zip(ids, counts))
                                               / time_scale)
    advance = sum((library.get(i).q[-1, 0] - library.get(i).q[0, 0]) * n for i, n in zip(ids, counts))
    assert summary.start_alpha_rad == pytest.approx(2.0)
    assert summary.advance_rad == pytest.approx(advance, abs=1e-9)
    if trajectory.constrained:   # on the locked rails: an arc of the lane
        assert summary.distance_m == pytest.approx(advance * trajectory.lane_radius_m, rel=1e-9)
        assert summary.start_radius_m == summary.end_radius_m == trajectory.lane_radius_m
    else:   # between the arcs of its innermost and outermost radius, from lane 1 to lane 2
        radius = trajectory.q[:, 1]
        assert radius.min() * advance <= summary.distance_m <= radius.max() * advance
        assert (summary.start_radius_m, summary.end_radius_m) == pytest.approx((0.43, 0.48), abs=1e-3)
    for motor in range(2):
        peak_sample = int(np.argmax(np.abs(trajectory.torque[:, motor])))
        assert summary.peak_torque_n_m[motor] == pytest.approx(abs(trajectory.torque[peak_sample, motor]))
        assert summary.peak_fraction[motor] == pytest.approx(summary.peak_torque_n_m[motor] / limits[motor])
        segment = trajectory.segments[trajectory.segment_index(trajectory.time_s[peak_sample])]
        assert summary.peak_primitive[motor] == segment.primitive_id
    assert summary.risk == saturation_risk(max(summary.peak_fraction))
    # the torques go with lambda^2 (Theorem 1): the same plan slower asks less of the motors
    slower = PlanSummary.of(plan_message(library, ids, counts, 0.5 * time_scale)[0], limits)
    assert np.allclose(slower.peak_fraction, 0.25 * np.array(summary.peak_fraction), rtol=1e-9)


def test_the_plan_is_drawn(library, tmp_path):
    from swim_bringup.maneuver_cli import write_plan_figure
    message, _ = plan_message(library, ["constrained/accelerate/E0.05"], [1])
    path = write_plan_figure(message, (1.25, 0.52), tmp_path / "figures" / "plan.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def vehicle(names, positions):
    from swim_bringup.maneuver import VehicleState
    return VehicleState(tuple(names), np.array(positions, float), np.zeros(len(names)))


STATES = ["constrained/cruise/E0.05", "constrained/rest", "free/cruise/R0.43/E0.05", "free/rest/R0.43",
          "free/rest/R0.48"]


@pytest.mark.parametrize("radius_m, state", [(0.43, "free/rest/R0.43"), (0.4549, "free/rest/R0.43"),
                                             (0.4551, "free/rest/R0.48"), (0.60, "free/rest/R0.48"),
                                             (0.30, "free/rest/R0.43")])
def test_a_goal_starts_from_rest_on_the_lane_nearest_the_measured_radius(radius_m, state):
    from swim_bringup.maneuver import ManeuverGoal
    from swim_bringup.maneuver_cli import plan_request
    request = plan_request(ManeuverGoal(1, goal_state="free/rest/R0.48", goal_alpha_rad=6.3),
                           vehicle(["alpha", "R", "phi", "theta"], [9.7, radius_m, 0.1, -0.1]), STATES)
    assert (request.start_state, request.start_alpha_rad, request.goal_alpha_rad) == (state, 9.7, 6.3)


def test_the_start_of_the_constrained_vehicle_and_of_none():
    from swim_bringup.maneuver import ManeuverGoal
    from swim_bringup.maneuver_cli import plan_request
    goal = ManeuverGoal(1, goal_state="constrained/cruise/E0.05")
    request = plan_request(goal, vehicle(["alpha", "phi", "theta"], [-1.5, 0.0, 0.0]), STATES)
    assert (request.start_state, request.start_alpha_rad) == ("constrained/rest", -1.5)
    request = plan_request(goal, None, STATES)   # no plant: the planner's default start, at alpha 0
    assert (request.start_state, request.start_alpha_rad) == ("", 0.0)
    sequence = plan_request(ManeuverGoal(0, ("constrained/accelerate/E0.05",)),
                            vehicle(["alpha", "phi", "theta"], [0.7, 0.0, 0.0]), STATES)
    assert (list(sequence.repeat_counts), sequence.start_state, sequence.start_alpha_rad) == ([1], "", 0.7)


def test_the_goal_statuses_read_as_a_line():
    from action_msgs.msg import GoalStatus

    from swim_bringup.maneuver_cli import goal_summary
    assert goal_summary({}) == "no goal under way (none seen)"
    statuses = {b"\x01" * 16: GoalStatus.STATUS_SUCCEEDED, b"\x02" * 16: GoalStatus.STATUS_EXECUTING}
    assert goal_summary(statuses) == "executing goal 02020202; 1 ended, the last succeeded"


# ----- planner_node alone ---------------------------------------------------------------------------------------
@contextlib.contextmanager
def joint_states_published(names, positions):
    """A node of this test publishing joint_states (reliable, as a plant) every 20 ms until the block ends."""
    import rclpy
    from sensor_msgs.msg import JointState

    from swim_ros.qos import RECORDABLE_QOS
    with new_rclpy_context() as context:
        node = rclpy.create_node("joint_state_source", context=context)
        publisher = node.create_publisher(JointState, "joint_states", RECORDABLE_QOS)
        stop = threading.Event()

        def publish() -> None:
            while not stop.wait(0.02):
                message = JointState(name=list(names), position=list(positions), velocity=[0.0] * len(names))
                message.header.stamp = node.get_clock().now().to_msg()
                publisher.publish(message)
        thread = threading.Thread(target=publish)
        thread.start()
        try:
            yield
        finally:
            stop.set()
            thread.join()
            node.destroy_node()


@pytest.fixture(scope="module")
def lone_planner(ros_domain, tmp_path_factory):  # noqa: F811
    """planner_node (the paper's library) alone on the domain, asked by swim-maneuver: what each command gave."""
    work = tmp_path_factory.mktemp("lone_planner")
    wait = ("--wait", str(SET_STARTUP_WAIT_S))
    sequence = ["constrained/accelerate/E0.05", "constrained/cruise/E0.05"]
    results = {}
    with running_node("swim_planner", "planner_node", work / "planner_node.log"):
        results["list"] = swim_maneuver("list", *wait)
        results["unknown id"] = swim_maneuver("plan", "--primitives", "constrained/swim/E9", *wait)
        results["nan time scale"] = swim_maneuver("plan", "--primitives", sequence[0], "--time-scale", "nan", *wait)
        results["no plant"] = swim_maneuver("plan", "--goal", "free/cruise/R0.48/E0.05", *wait)
        with joint_states_published(["alpha", "phi", "theta"], [1.234, 0.0, 0.0]):
            results["constrained"] = swim_maneuver("plan", "--primitives", *sequence, "--repeats", "1", "2",
                                                   "--plot", str(work / "plan.png"), *wait)
            results["unreachable"] = swim_maneuver("plan", "--goal", "free/rest/R0.48", *wait)
        with joint_states_published(["alpha", "R", "phi", "theta"], [-0.5, 0.47, 0.0, 0.0]):
            results["free goal"] = swim_maneuver("plan", "--goal", "free/cruise/R0.48/E0.05", *wait)
    return results, work


def test_list_prints_every_primitive_of_the_library(lone_planner, library):
    results, _ = lone_planner
    assert_clean_exit(results["list"], 0)
    lines = {line.split()[0]: line.split() for line in results["list"].stdout.splitlines() if line}
    for primitive_id in library.ids():
        q = library.get(primitive_id).q
        assert primitive_id in lines, results["list"].stdout
        assert f"{library.spec(primitive_id).duration_s:.3f}" in lines[primitive_id]
        assert f"{q[-1, 0] - q[0, 0]:+.3f}" in lines[primitive_id]
    assert "flow model: ideal" in results["list"].stdout
    states = next(line for line in results["list"].stdout.splitlines() if line.startswith("goal states"))
    assert "constrained/rest" in states and "free/rest/R0.48" in states


@pytest.mark.parametrize("case, reason", [
    ("unknown id", "constrained/swim/E9"),
    ("nan time scale", "time scale"),
    ("unreachable", "no sequence of primitives leads from 'constrained/rest' to 'free/rest/R0.48'"),
])
def test_a_request_the_planner_refuses_exits_2_with_its_reason(lone_planner, case, reason):
    results, _ = lone_planner
    assert_clean_exit(results[case], 2)
    lines = results[case].stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("swim-maneuver: the planner refused the maneuver: ")
    assert reason in lines[0]
    assert results[case].stdout == ""


def test_a_plan_starts_at_the_measured_alpha_and_is_summarized(lone_planner, library):
    from swim_model import load_rig
    results, work = lone_planner
    assert_clean_exit(results["constrained"], 0)
    out = results["constrained"].stdout
    advance = sum(library.get(i).q[-1, 0] - library.get(i).q[0, 0] for i in ("constrained/accelerate/E0.05",
                                                                          "constrained/cruise/E0.05",
                                                                          "constrained/cruise/E0.05"))
    lane_m = load_rig().constrained_lane_radius_m
    assert "start: alpha +1.2340 rad (joint_states)" in out
    assert "primitives: constrained/accelerate/E0.05, constrained/cruise/E0.05 x2" in out
    assert "duration: 14.000 s" in out
    assert f"distance: {advance:+.3f} rad of alpha from +1.234 rad, {advance * lane_m:+.3f} m along the lane" in out
    assert f"lanes: R {lane_m:.3f} m at the start, {lane_m:.3f} m at the end" in out
    assert "peak feed-forward torque: heave " in out and "saturation risk: " in out
    assert (work / "plan.png").read_bytes()[:4] == b"\x89PNG"


def test_a_goal_starts_at_the_rest_state_of_the_nearest_lane(lone_planner):
    results, _ = lone_planner
    assert_clean_exit(results["free goal"], 0)
    assert "start: alpha -0.5000 rad, R 0.4700 m (joint_states), state free/rest/R0.48" in results["free goal"].stdout
    assert "primitives: free/accelerate/R0.48/E0.05" in results["free goal"].stdout
    assert_clean_exit(results["no plant"], 0)   # lane 1's rest, the planner's default, at alpha 0
    assert "start: no joint_states on the domain: alpha 0, the planner's default start state" in \
        results["no plant"].stdout
    assert "primitives: free/accelerate/R0.43/E0.05, free/lane_change/R0.43-R0.48/E0.05" in results["no plant"].stdout


@pytest.mark.parametrize("command", [["plan", "--primitives", "constrained/accelerate/E0.05"], ["status"], ["list"],
                                     ["run", "--goal", "constrained/rest"]])
def test_without_nodes_a_command_exits_2_after_its_wait(ros_domain, command):  # noqa: F811
    """No node is discoverable (discovery off: nothing else on the domain counts) within --wait."""
    started = time.monotonic()
    result = swim_maneuver(*command, "--wait", str(SHORT_WAIT_S),
                           env=dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="OFF"))
    assert_clean_exit(result, 2)
    assert time.monotonic() - started >= SHORT_WAIT_S
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and f"within {SHORT_WAIT_S:g} s" in lines[0], result.stderr


def test_an_unknown_subcommand_shows_no_traceback():
    result = swim_maneuver("fly", "--primitives", "x")
    assert_clean_exit(result, 2)
    assert "invalid choice: 'fly'" in result.stderr


# ----- a set brought up by swim-bringup -------------------------------------------------------------------------
@contextlib.contextmanager
def joint_commands_received(timeout_s: float):
    """The joint_commands this test's node receives while the block runs, each a (2,) effort array; the block starts
    once the first has arrived (within timeout_s)."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from sensor_msgs.msg import JointState

    from swim_ros.qos import RECORDABLE_QOS
    with new_rclpy_context() as context:
        node = rclpy.create_node("joint_command_probe", context=context)
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        efforts: list[np.ndarray] = []
        node.create_subscription(JointState, "joint_commands", lambda m: efforts.append(np.array(m.effort)),
                                 RECORDABLE_QOS)
        stop = threading.Event()

        def spin() -> None:
            while not stop.is_set():
                executor.spin_once(timeout_sec=0.05)
        thread = threading.Thread(target=spin)
        thread.start()
        try:
            deadline = time.monotonic() + timeout_s
            while not efforts:
                assert time.monotonic() < deadline, f"no joint_commands within {timeout_s} s"
                time.sleep(0.05)
            efforts.clear()
            yield efforts
        finally:
            stop.set()
            thread.join()
            executor.shutdown()
            node.destroy_node()


@contextlib.contextmanager
def brought_up(work: Path, *arguments: str):
    """`swim-bringup arguments --log-dir work/logs` running until the block ends (then Ctrl-C, as an operator)."""
    log_path = work / "bringup.log"
    with open(log_path, "w") as log:
        process = start_child(["ros2", "run", "swim_bringup", "swim-bringup", *arguments, "--log-dir",
                               str(work / "logs")], stdout=log, stderr=subprocess.STDOUT,
                              start_new_session=True, env=dict(os.environ))
    try:
        yield log_path
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGINT)
        try:
            process.wait(COMMAND_TIMEOUT_S)
        finally:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(process.pid, signal.SIGKILL)


@pytest.fixture(scope="module")
def bridge_set(ros_domain, tmp_path_factory):  # noqa: F811
    """The emulated bridge set (realistic pipeline; the bridge's overrun latch and the tracker's stale limit raised
    for a shared host) asked for a goal the planner refuses, then for the paper's lane keeping, each recorded, then for
    its status, an e-stop and a lifecycle round; the commands' results and their folders."""
    from swim_bringup.testing import shared_host_config
    work = tmp_path_factory.mktemp("bridge_set")
    config = shared_host_config("realistic", work)
    wait = ("--wait", str(SET_STARTUP_WAIT_S))
    results = {}
    with brought_up(work, "bridge", "--config", str(config)):
        # first, while the tracker has had no goal: it commands zero torque until one comes
        with joint_commands_received(SET_STARTUP_WAIT_S) as efforts:
            results["refused"] = swim_maneuver("run", "--goal", "constrained/rest", "--record",
                                               str(work / "refused"), *wait)
        results["refused efforts"] = list(efforts)
        results["lane keeping"] = swim_maneuver("run", "--primitives", *LANE_KEEPING[0], "--repeats",
                                                *map(str, LANE_KEEPING[1]), "--record", str(work / "lane_keeping"),
                                                *wait)
        results["status"] = swim_maneuver("status", *wait)
        # the e-stop and its reset, then a lifecycle round: the bridge stops and comes back without a fault
        results["estop"] = swim_maneuver("estop", *wait)
        results["status after estop"] = swim_maneuver("status", *wait)
        results["reset"] = swim_maneuver("reset", *wait)
        results["deactivate"] = swim_maneuver("bridge", "deactivate", *wait)
        results["activate"] = swim_maneuver("bridge", "activate", *wait)
        results["activate again"] = swim_maneuver("bridge", "activate", *wait)   # active already: refused
        results["status after reset"] = swim_maneuver("status", *wait)
    return results, work


def test_a_refused_request_exits_2_and_moves_nothing(bridge_set):
    from swim_bringup.bag import read_messages
    results, work = bridge_set
    assert_clean_exit(results["refused"], 2)
    assert "PLANNING_FAILED: the planner refused: no sequence of primitives leads from 'free/rest/R0.43' to " \
           "'constrained/rest'" in results["refused"].stderr
    efforts = results["refused efforts"]
    assert len(efforts) > 100   # the whole call, seconds of the tracker's answer to each state at 125 Hz
    assert not np.any(efforts)
    commands = [message.effort for _, _, message in read_messages(work / "refused" / "bag", ("/joint_commands",))]
    assert commands and not np.any(commands)   # the command's own bag: what it recorded, zero too
    assert not (work / "refused" / "report.json").exists()   # nothing was tracked
    assert "no report" in results["refused"].stderr


def host_stalled(report) -> bool:
    """Whether the host woke the bridge's I/O loop later than HOST_STALL_BOUND_MS during the run of report."""
    lateness_ms = report.bridge.bridge_worst_lateness_ms
    return lateness_ms is not None and lateness_ms > HOST_STALL_BOUND_MS


def test_the_paper_lane_keeping_ends_within_the_default_tolerances(bridge_set):
    """The lane keeping from the home pose, recorded: its plan starts at the alpha the bridge measured, it ends
    within the default tolerances with no bridge fault, and its report and plots are written. On a run the host
    stalled (HOST_STALL_BOUND_MS), it is tracked to its end all the same: the goal's tolerances are the only check it
    may fail (a stall of a few hundred milliseconds may leave it within them or not), and the rest holds."""
    import re

    from swim_interfaces.action import ExecutePlan

    from swim_bringup.bag import read_messages
    from swim_bringup.recorded_run import RUN_TOLERANCES
    from swim_bringup.reports import RunReport
    results, work = bridge_set
    run = work / "lane_keeping"
    report = RunReport.load(run / "report.json")
    assert report.bridge is not None and report.bridge.bridge_faults == "NONE"
    if report.result.error_code != 0:
        assert host_stalled(report), report.result
        assert_clean_exit(results["lane keeping"], 1)
        assert report.result.error_code == ExecutePlan.Result.GOAL_TOLERANCE_VIOLATED, report.result
        assert "GOAL_TOLERANCE_VIOLATED: goal tolerance violated; 23.000 s tracked" in results["lane keeping"].stdout
    else:
        assert_clean_exit(results["lane keeping"], 0)
        summary = re.search(r"SUCCESSFUL: succeeded; 23\.000 s tracked, final alpha error ([-+\d.]+) mrad, R error "
                            r"([-+\d.]+) mm", results["lane keeping"].stdout)
        assert summary is not None, results["lane keeping"].stdout[-2000:]
        assert abs(float(summary[1])) * 1e-3 <= RUN_TOLERANCES.goal_alpha_rad
        assert abs(float(summary[2])) * 1e-3 <= RUN_TOLERANCES.goal_r_m
        assert report.result.error_code == 0
    plan = [message for _, _, message in read_messages(run / "bag", ("/plan",))][-1]
    first_tracked = next(message for _, _, message in read_messages(run / "bag", ("/tracking_state",)))
    assert plan.positions[0] == pytest.approx(first_tracked.feedback.positions[0], abs=START_ALPHA_TOLERANCE_RAD)
    assert [segment.primitive_id for segment in plan.segments] == \
        [LANE_KEEPING[0][0]] + [LANE_KEEPING[0][1]] * LANE_KEEPING[1][1] + [LANE_KEEPING[0][2]]
    assert all((run / name).is_file() for name in ("displacement.png", "heave_pitch.png", "cartesian_path.png"))


def test_status_shows_the_bridge_and_its_faults(bridge_set):
    from swim_bringup.reports import RunReport
    results, work = bridge_set
    assert_clean_exit(results["status"], 0)
    out = results["status"].stdout
    assert "up as /bridge_node" in out and "bridge lifecycle state: active" in out, out
    # its level is what the bridge says then (a late command on a loaded host is a watchdog WARN)
    assert "\nbridge I/O loop: " in out and "bridge faults latched: NONE; emergency stop pending: False" in out, out
    # the lane keeping's end: succeeded, or aborted by its goal tolerance on a run the host stalled (as its test
    # checks)
    last = "succeeded" if RunReport.load(work / "lane_keeping" / "report.json").result.error_code == 0 else "aborted"
    assert f"execute_plan (tracker_node): no goal under way; 1 ended, the last {last}" in out
    assert f"perform_maneuver (maneuver_node): no goal under way; 2 ended, the last {last}" in out


@pytest.fixture(scope="module")
def sim_set(ros_domain, tmp_path_factory):  # noqa: F811
    """The simulator's set (the paper's pipeline, lock-step: the constrained vehicle stays where a maneuver left
    it): a maneuver, then a goal state flown from where it ended (recorded), then a run stopped by Ctrl-C once it
    tracks (recorded), then status and a plan; the commands' results and folders, and the stopped run's output."""
    work = tmp_path_factory.mktemp("sim_set")
    canceled, log_path = work / "canceled", work / "canceled.log"
    wait = ("--wait", str(SET_STARTUP_WAIT_S))
    sequence = ["constrained/accelerate/E0.05", "constrained/cruise/E0.05", "constrained/decelerate/E0.05"]
    # the run stopped by Ctrl-C cruises long enough to be seen cruising: the progress line is redrawn at most every
    # 0.1 s (tqdm), and a single cruise in lock-step can pass between two redraws
    canceled_repeats = ("--repeats", "1", str(CANCELED_CRUISES), "1")
    results = {}
    with brought_up(work, "sim", "--pipeline", "paper"):
        results["first"] = swim_maneuver("run", "--primitives", *sequence, *wait)
        results["goal"] = swim_maneuver("run", "--goal", "constrained/rest", "--goal-alpha", "1", "--record",
                                        str(work / "goal"), *wait)
        with open(log_path, "w") as log:
            process = start_child(["ros2", "run", "swim_bringup", "swim-maneuver", "run", "--primitives",
                                   *sequence, *canceled_repeats, "--record", str(canceled), *wait], stdout=log,
                                  stderr=subprocess.STDOUT, start_new_session=True, env=dict(os.environ))
        try:
            deadline = time.monotonic() + COMMAND_TIMEOUT_S
            while "constrained/cruise/E0.05 (" not in log_path.read_text():   # the accelerate done
                assert process.poll() is None and time.monotonic() < deadline, log_path.read_text()[-3000:]
                time.sleep(0.05)
            os.killpg(process.pid, signal.SIGINT)   # Ctrl-C in the operator's terminal
            results["canceled"] = process.wait(COMMAND_TIMEOUT_S)
        finally:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(process.pid, signal.SIGKILL)
        results["status"] = swim_maneuver("status", *wait)
        results["plan"] = swim_maneuver("plan", "--goal", "constrained/cruise/E0.05", *wait)
    return results, work, log_path.read_text()


def test_a_goal_state_is_flown_from_where_the_last_maneuver_ended(sim_set):
    from swim_bringup.bag import read_messages
    from swim_bringup.reports import RunReport
    results, work, _ = sim_set
    assert_clean_exit(results["first"], 0)
    assert_clean_exit(results["goal"], 0)
    assert RunReport.load(work / "goal" / "report.json").result.error_code == 0
    # the last plan: the planner's latched one of the maneuver before comes first
    plan = [message for _, _, message in read_messages(work / "goal" / "bag", ("/plan",))][-1]
    first_tracked = next(message for _, _, message in read_messages(work / "goal" / "bag", ("/tracking_state",)))
    planned_start_alpha = plan.positions[0]
    assert planned_start_alpha == pytest.approx(first_tracked.feedback.positions[0], abs=START_ALPHA_TOLERANCE_RAD)
    assert planned_start_alpha > 0.4   # where the first maneuver left it (0.55 rad of advance), not alpha 0
    assert plan.positions[-3] - planned_start_alpha >= 1.0   # the goal's advance: the last sample's alpha (nq 3)
    assert [s.primitive_id for s in plan.segments][-1] == "constrained/decelerate/E0.05"


def test_ctrl_c_cancels_the_maneuver_and_leaves_a_whole_bag(sim_set):
    from swim_interfaces.action import PerformManeuver

    from swim_bringup.analysis import analyze
    from swim_bringup.bag import read_messages
    from swim_bringup.reports import RunReport
    results, work, output = sim_set
    run_dir = work / "canceled"
    assert results["canceled"] == 130, output[-3000:]
    assert "Traceback" not in output
    assert "CANCELED: canceled" in output and "canceled by Ctrl-C" in output
    report = RunReport.load(run_dir / "report.json")
    assert report.result.error_code == PerformManeuver.Result.CANCELED
    plan = [message for _, _, message in read_messages(run_dir / "bag", ("/plan",))][-1]
    assert len(plan.segments) == CANCELED_CRUISES + 2
    assert 0.0 < report.result.duration_s < plan.time_from_start_s[-1]   # stopped before the plan's end
    assert (run_dir / "bag" / "metadata.yaml").is_file()   # closed
    tracked = [message.plan_time_s for _, _, message in read_messages(run_dir / "bag", ("/tracking_state",))]
    assert tracked[-1] == pytest.approx(report.result.duration_s, abs=1e-6)   # to the last period tracked
    periods_s = np.diff(tracked)
    assert np.allclose(periods_s, periods_s[0], rtol=1e-6), "a tracked period is missing from the bag"
    analysis = analyze(run_dir / "bag")
    assert analysis.measures.periods == len(tracked) == report.measures.periods
    assert analysis.measures.duration_s == pytest.approx(report.result.duration_s)


def test_status_shows_the_simulators_set(sim_set):
    results, _, _ = sim_set
    assert_clean_exit(results["status"], 0)
    lines = {line.split()[0]: line for line in results["status"].stdout.splitlines()[1:] if line.startswith("  ")}
    for name in ("planner_node", "tracker_node", "maneuver_node", "sim_node", "rig_state_publisher", "marker_node"):
        assert f"up as /{name}" in lines[name], results["status"].stdout
    assert "up as" not in lines["bridge_node"] and "bridge lifecycle" not in results["status"].stdout
    assert "execute_plan (tracker_node): no goal under way; 3 ended, the last canceled" in results["status"].stdout
    assert "perform_maneuver (maneuver_node): no goal under way; 3 ended, the last canceled" in \
        results["status"].stdout


def test_a_plan_starts_from_the_simulators_rest(sim_set):
    results, _, _ = sim_set
    assert_clean_exit(results["plan"], 0)
    start = results["plan"].stdout.splitlines()[0]
    assert start.startswith("start: alpha ") and start.endswith("(joint_states), state constrained/rest")
    assert not math.isclose(float(start.split()[2]), 0.0)   # where the canceled run left it


def test_the_bridge_transitions_are_lifecycle_msgs_ids():
    from lifecycle_msgs.msg import Transition

    from swim_bringup.maneuver_cli import BRIDGE_TRANSITIONS
    expected = {name: getattr(Transition, f"TRANSITION_{name.upper()}") for name in BRIDGE_TRANSITIONS}
    assert BRIDGE_TRANSITIONS == expected


def test_the_e_stop_latches_and_its_reset_and_a_lifecycle_round_clear_it(bridge_set):
    results, _ = bridge_set
    assert_clean_exit(results["estop"], 0)
    assert "/emergency_stop: emergency stop latched until reset_emergency_stop" in results["estop"].stdout
    assert "bridge faults latched: EMERGENCY_STOP" in results["status after estop"].stdout, \
        results["status after estop"].stdout
    assert_clean_exit(results["reset"], 0)
    for name in ("deactivate", "activate"):
        assert_clean_exit(results[name], 0)
        assert f"bridge_node: {name} done" in results[name].stdout
    assert_clean_exit(results["activate again"], 2)
    assert "bridge_node refused activate" in results["activate again"].stderr
    after = results["status after reset"].stdout
    assert "bridge lifecycle state: active" in after and "bridge faults latched: NONE; emergency stop pending: " \
        "False" in after, after

