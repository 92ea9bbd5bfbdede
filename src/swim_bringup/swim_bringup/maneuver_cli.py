"""swim-maneuver: the operator's command: what can be flown, a plan to look at, a maneuver flown, the system's state.

It attaches to whatever runs on the ROS domain of the environment (ROS_DOMAIN_ID; the rig, the emulated bridge, the
simulator in real time or lock-step), and starts nothing:

    swim-maneuver list                              the planner's graph states and primitives (list_primitives)
    swim-maneuver plan --primitives ID ... [--repeats N ...] | --goal STATE [--goal-alpha RAD] [--time-scale L]
                       [--plot FILE]                a plan from where the vehicle is (request_maneuver), summarized
    swim-maneuver run  (the same choice) [--record DIR] [tolerances]
                                                    flown by maneuver_node (perform_maneuver), with a progress bar
    swim-maneuver status                            the nodes up, the bridge's state and faults, the goals under way
    swim-maneuver estop | reset                     the bridge's emergency stop (emergency_stop), and its reset
                                                    with every latched fault (reset_emergency_stop)
    swim-maneuver bridge configure|activate|deactivate|cleanup
                                                    a lifecycle transition of bridge_node

`plan` starts from the alpha of the latest joint_states (0 when no node publishes them) and, for a goal state, from
the rest state of the vehicle that publishes them: the constrained one's, or the free one's on the lane nearest its
R. It prints the duration, the distance, the lanes and the peak feed-forward torques against the motors' limits,
with the risk that the tracker saturates them. `run` is flown by maneuver_node from where the vehicle is; Ctrl-C
cancels the goal (the tracker holds the foil where it is) and waits for its end. With --record DIR the run's topics
(bag.RUN_TOPICS) go to DIR/bag as swim-demo records them, and report.json and the figures are written into DIR,
after a cancel too.

Exit status: 0 done; 1 a maneuver that failed in tracking (a tolerance left, the state lost, preempted, canceled by
another) or, recorded, one during which the bridge latched a fault; 2 bad input, no such nodes within --wait, or a
request refused (invalid goal, planning failed, a node unavailable, an invalid plan), with a one-line reason on
stderr; 130 a run canceled by Ctrl-C.
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import os
import signal
import sys
import time
from pathlib import Path
from types import FrameType
from typing import Any, Callable, Optional, Sequence

import numpy as np

from swim_bringup.analysis import summary_table
from swim_bringup.maneuver import MODE_GOAL, MODE_SEQUENCE, ManeuverGoal, ManeuverGoalError, VehicleState, rest_state_of
from swim_bringup.recorded_run import add_tolerance_arguments, tolerances_of, write_run_report
from swim_bringup.reports import run_failures
from swim_bringup.run_client import PLANNER_POLICY, STARTUP_TIMEOUT_S, RunError
from swim_bringup.run_record import MissingTopic
from swim_controller.supervisor import Tolerances

PROG = "swim-maneuver"
EXIT_DONE = 0
EXIT_FAILED = 1
EXIT_REFUSED = 2
EXIT_INTERRUPTED = 130   # 128 + SIGINT, as a shell reports a command Ctrl-C stopped

#: the saturation risk of a plan, by its largest feed-forward torque as a fraction of that motor's limit. The tracker's
#: feedback (LQR and sliding mode) adds to the feed-forward torque within the same limit, to take out the errors the
#: disturbances make. Measured on the realistic pipeline (docs/experiments.md; the circulatory plans peak at 35 % of
#: the motors' limits at lambda 1, lambda^2 times that when scaled): the constrained maneuver at lambda 1 and 1.2
#: (peaks at 35 % and 50 %) and the lane change at 1.25 (55 %) saturated a motor in 0-0.6 % of the periods, the
#: constrained maneuver at 1.67 (98 %) in 16-19 %. Under half the limit the feedback has at least as much again as
#: the feed-forward uses: low; from 80 % it has under a quarter of it: high.
MODERATE_RISK_FRACTION = 0.5
HIGH_RISK_FRACTION = 0.8
#: how long `plan` waits for a joint_states message once a publisher is known: a plant publishes every control
#: period (8 ms) and a lock-step simulator resends its state every 0.5 s when no command comes; 5 s covers a loaded
#: host's stalls
JOINT_STATE_TIMEOUT_S = 5.0
#: the ROS graph counts as discovered when its nodes and topics have not changed for this long: a participant whose
#: first announcements a busy host missed is found at its next periodic one, 3 s later (Fast DDS's default
#: announcement period; measured here: a publisher found 3-4 s after the command started, one time in three)
GRAPH_STABLE_S = 3.5
#: `status`: bridge_node publishes /diagnostics at diagnostics_rate_hz, 2 Hz in config/bridge.yaml; its publisher may
#: be discovered an announcement period after the node (GRAPH_STABLE_S), then a few periods
DIAGNOSTICS_TIMEOUT_S = GRAPH_STABLE_S + 1.5
#: `status`: an action server's goal statuses (transient local) come soon after its status topic is matched; a server
#: that never had a goal has sent none, so this bounds the wait for them
LATCHED_STATUS_TIMEOUT_S = 1.0
#: `status`: the bridge's lifecycle state (an idempotent get_state), asked with short tries: a status is a glance
STATUS_ATTEMPT_S = 3.0
#: `run`: the wall time a maneuver may take by default, as swim-demo's --timeout
RUN_TIMEOUT_S = 600.0
#: `run`: after a cancel, how long the tracker has to end the goal (it ends it at its next control period; a lost
#: answer is asked again every 10 s, swim_ros.calls.goal_result)
CANCEL_RESULT_TIMEOUT_S = 60.0
#: `run`: how often the maneuver server's presence is checked while a goal is under way, and how long it may be
#: missing from the graph before the run is given up (assumed: a server missed by discovery for a moment is back
#: within a second; one missing for 10 s is gone)
SERVER_CHECK_PERIOD_S = 1.0
SERVER_LOST_AFTER_S = 10.0

#: the nodes `status` looks for, with what each is
KNOWN_NODES = {
    "planner_node": "planner (request_maneuver, list_primitives)",
    "tracker_node": "tracker (execute_plan)",
    "maneuver_node": "maneuver server (perform_maneuver)",
    "sim_node": "simulator",
    "bridge_node": "hardware bridge",
    "rig_state_publisher": "visualization: URDF and /tf",
    "marker_node": "visualization: path markers",
}
#: the plants: one of them makes the loop
PLANT_NODES = ("sim_node", "bridge_node")
#: the actions whose goals `status` shows (server node, action name)
WATCHED_ACTIONS = (("tracker_node", "execute_plan"), ("maneuver_node", "perform_maneuver"))
#: PerformManeuver's result codes by name (ExecutePlan's are among them with the same values)
RESULT_NAMES = ("SUCCESSFUL", "INVALID_PLAN", "INVALID_GOAL", "PLANNING_FAILED", "PATH_TOLERANCE_VIOLATED",
                "GOAL_TOLERANCE_VIOLATED", "STATE_LOST", "PREEMPTED", "CANCELED", "NODE_UNAVAILABLE")
#: the results of a request that was refused before anything moved
REFUSED_RESULTS = ("INVALID_PLAN", "INVALID_GOAL", "PLANNING_FAILED", "NODE_UNAVAILABLE")
#: PerformManeuver.Feedback's phases (PHASE_PLANNING, PHASE_WAITING_FOR_MODEL, PHASE_TRACKING) as the progress bar
#: names them
PHASE_NAMES = {0: "planning", 1: "waiting for the model", 2: "tracking"}
#: the lifecycle transitions an operator asks of bridge_node (lifecycle_msgs/Transition ids)
BRIDGE_TRANSITIONS = {"configure": 1, "cleanup": 2, "activate": 3, "deactivate": 4}
#: diagnostic_msgs/DiagnosticStatus's levels (OK, WARN, ERROR, STALE)
DIAGNOSTIC_LEVELS = {0: "OK", 1: "WARN", 2: "ERROR", 3: "STALE"}


class CommandError(RuntimeError):
    """What stops a subcommand: the one-line reason for stderr and the exit status."""

    def __init__(self, reason: str, exit_status: int = EXIT_REFUSED) -> None:
        super().__init__(reason)
        self.exit_status = exit_status


class Interrupted(Exception):
    """Ctrl-C (SIGINT) arrived while a run waited for its goal's end."""


class ServerLost(Exception):
    """The maneuver server left the ROS graph while its goal was under way."""


def ros_domain() -> str:
    """The ROS domain the command runs on (ROS_DOMAIN_ID, default 0)."""
    return os.environ.get("ROS_DOMAIN_ID") or "0"


# ----- the command line ------------------------------------------------------------------------------------------
def positive_int(text: str) -> int:
    """An argparse type: an integer of 1 or more."""
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be 1 or more, got {value}")
    return value


def non_negative_seconds(text: str) -> float:
    """An argparse type: a finite number of seconds, 0 or more."""
    value = float(text)
    if not (math.isfinite(value) and value >= 0.0):
        raise argparse.ArgumentTypeError(f"must be a finite number of seconds >= 0, got {text}")
    return value


def parse_arguments(argv: Optional[Sequence[str]]) -> argparse.Namespace:
    """The subcommand and its options; a usage error (exit 2, the usage and the reason on stderr) for bad input."""
    parser = argparse.ArgumentParser(
        prog=PROG, description=__doc__.splitlines()[0],
        epilog="exit status: 0 done; 1 a maneuver that failed in tracking; 2 bad input, no such nodes, a request "
               "refused; 130 a run canceled by Ctrl-C")
    commands = parser.add_subparsers(dest="command", required=True,
                                     metavar="{list,plan,run,status,estop,reset,bridge}")
    wait = argparse.ArgumentParser(add_help=False)
    wait.add_argument("--wait", type=non_negative_seconds, default=STARTUP_TIMEOUT_S, metavar="S",
                      help="how long to wait for the nodes, s (default %(default)s)")
    commands.add_parser("list", parents=[wait], help="the planner's graph states and primitives")
    maneuver = argparse.ArgumentParser(add_help=False)
    choice = maneuver.add_mutually_exclusive_group(required=True)
    choice.add_argument("--primitives", nargs="+", metavar="ID", help="a primitive sequence (swim-maneuver list)")
    choice.add_argument("--goal", metavar="STATE", help="a goal state of the planner's graph, e.g. free/rest/R0.48")
    maneuver.add_argument("--repeats", nargs="+", type=positive_int, metavar="N",
                          help="with --primitives: how often each is flown (default 1 each)")
    maneuver.add_argument("--goal-alpha", type=float, default=0.0, metavar="RAD",
                          help="with --goal: at least this advance of alpha, rad (default 0: the quickest path)")
    maneuver.add_argument("--time-scale", type=float, default=0.0, metavar="L",
                          help="lambda (> 1 faster, lambda^2 the torque; default 0: the planner's default)")
    plan = commands.add_parser("plan", parents=[wait, maneuver], help="a plan from where the vehicle is")
    plan.add_argument("--plot", type=Path, default=None, metavar="FILE", help="draw the plan into FILE (PNG)")
    run = commands.add_parser("run", parents=[wait, maneuver], help="fly a maneuver through maneuver_node")
    run.add_argument("--record", type=Path, default=None, metavar="DIR",
                     help="record the run's topics to DIR/bag, then write report.json and figures into DIR")
    run.add_argument("--timeout", type=non_negative_seconds, default=RUN_TIMEOUT_S, metavar="S",
                     help="wall-time limit of the maneuver, s (default %(default)s)")
    add_tolerance_arguments(run)
    commands.add_parser("status", parents=[wait], help="the nodes up, the bridge's state and faults, the goals")
    commands.add_parser("estop", parents=[wait], help="the bridge's emergency stop: zero current, enable line stopped, "
                        "latched until reset")
    commands.add_parser("reset", parents=[wait], help="reset the bridge's emergency stop and every latched fault")
    bridge = commands.add_parser("bridge", parents=[wait], help="a lifecycle transition of bridge_node")
    bridge.add_argument("transition", choices=tuple(BRIDGE_TRANSITIONS))
    args = parser.parse_args(argv)
    if args.command in ("plan", "run"):
        subparser = plan if args.command == "plan" else run
        if args.repeats is not None and args.primitives is None:
            subparser.error("--repeats goes with --primitives")
        if args.repeats is not None and len(args.repeats) != len(args.primitives):
            subparser.error(f"--repeats gives {len(args.repeats)} counts for {len(args.primitives)} primitives")
        if args.goal_alpha != 0.0 and args.goal is None:
            subparser.error("--goal-alpha goes with --goal")
        try:
            args.tolerances = tolerances_of(args) if args.command == "run" else Tolerances()
        except ValueError as err:
            subparser.error(str(err))
    return args


def maneuver_goal(args: argparse.Namespace) -> ManeuverGoal:
    """What plan and run ask for, as maneuver_node reads a goal."""
    if args.primitives is not None:
        return ManeuverGoal(MODE_SEQUENCE, tuple(args.primitives), tuple(args.repeats or ()),
                            time_scale=args.time_scale, tolerances=args.tolerances)
    return ManeuverGoal(MODE_GOAL, goal_state=args.goal, goal_alpha_rad=args.goal_alpha, time_scale=args.time_scale,
                        tolerances=args.tolerances)


# ----- a session on the ROS domain ------------------------------------------------------------------------------
class Session:
    """An rclpy context, node and executor of the command's own.

    They run on the environment's ROS domain. RunClient has the same context, node, executor and close(), and stands in
    for it when a run is recorded.
    """

    def __init__(self) -> None:
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node("swim_maneuver", context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def close(self) -> None:
        """Shut the executor down, destroy the node and shut the context down."""
        import rclpy
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


def spin_until_settled(session: Any, done: Callable[[], bool], timeout_s: float) -> None:
    """Spin until done() holds or the ROS graph has settled.

    Spin until done() holds or the ROS graph's nodes and topics have not changed for GRAPH_STABLE_S, at most
    timeout_s.
    """
    from swim_ros.calls import spin_until
    seen: list[Any] = [None, time.monotonic()]   # the graph last seen, when it changed

    def settled() -> bool:
        graph = (set(session.node.get_node_names_and_namespaces()),
                 {name for name, _ in session.node.get_topic_names_and_types()})
        if graph != seen[0]:
            seen[:] = [graph, time.monotonic()]
        return done() or time.monotonic() - seen[1] >= GRAPH_STABLE_S
    spin_until(session.executor, settled, timeout_s)


def wait_for(session: Any, ready: Callable[[], bool], what: str, wait_s: float) -> None:
    """Spin until ready(); CommandError (exit 2) naming what did not appear on the domain within wait_s."""
    from swim_ros.calls import spin_until
    if not spin_until(session.executor, ready, wait_s):
        raise CommandError(f"no {what} on ROS domain {ros_domain()} within {wait_s:g} s")


def call(session: Any, client: Any, request: Any, what: str, wait_s: float) -> Any:
    """An idempotent (or request-id) service call that survives a lost answer; CommandError if no answer."""
    from swim_ros.calls import CallFailed, call_service
    wait_for(session, client.service_is_ready, what, wait_s)
    try:
        return call_service(session.executor, client, request, dataclasses.replace(PLANNER_POLICY,
                                                                                   discovery_timeout_s=wait_s))
    except CallFailed as err:
        raise CommandError(f"{what}: {err}") from err


def list_primitives(session: Any, wait_s: float) -> Any:
    """The planner's primitive list (ListPrimitives response), waiting up to wait_s for the planner."""
    from swim_interfaces.srv import ListPrimitives
    client = session.node.create_client(ListPrimitives, "list_primitives")
    return call(session, client, ListPrimitives.Request(), "planner_node (list_primitives)", wait_s)


# ----- list ------------------------------------------------------------------------------------------------------
def primitive_table(listing: Any) -> str:
    """The planner's list_primitives reply as text: the flow model, the goal states, one line a primitive."""
    rows = [("id", "type", "start -> end state", "E, J", "duration, s", "advance, rad", "")]
    for info in listing.primitives:
        rows.append((info.primitive_id, info.primitive_type, f"{info.start_state} -> {info.end_state}",
                     f"{info.start_energy_j:g} -> {info.end_energy_j:g}", f"{info.duration_s:.3f}",
                     f"{info.advance_rad:+.3f}", "" if info.in_graph else "not in the graph (sequences only)"))
    widths = [max(len(row[k]) for row in rows) for k in range(len(rows[0]))]
    aligned = ["  ".join(cell.rjust(width) if 3 <= k <= 5 else cell.ljust(width)
                         for k, (cell, width) in enumerate(zip(row, widths))).rstrip() for row in rows]
    return "\n".join([f"flow model: {listing.flow_model}; library digest {listing.library_digest[:12]}",
                      f"goal states (--goal): {', '.join(listing.states)}",
                      f"primitives (--primitives): {len(listing.primitives)}", *aligned])


def list_command(args: argparse.Namespace) -> int:
    """The list command: print the planner's primitives; the exit status."""
    session = Session()
    try:
        listing = list_primitives(session, args.wait)
    finally:
        session.close()
    print(primitive_table(listing))
    return EXIT_DONE


# ----- plan ------------------------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class PlanArrays:
    """A PlannedTrajectory's arrays, shaped.

    Times (N,), s; q and qdot (N, nq) in joint_names' order (rad, m); feed-forward torques (N, 2) heave and pitch, N m;
    radius (N,), m: R, or the constrained plan's lane.
    """

    joint_names: tuple[str, ...]
    time_s: np.ndarray
    q: np.ndarray
    qdot: np.ndarray
    torque_n_m: np.ndarray
    radius_m: np.ndarray

    @classmethod
    def of(cls, plan: Any) -> "PlanArrays":
        """The arrays of a PlannedTrajectory message."""
        names = tuple(plan.joint_names)
        time_s = np.asarray(plan.time_from_start_s, dtype=float)
        q = np.asarray(plan.positions, dtype=float).reshape(len(time_s), len(names))
        radius_m = q[:, names.index("R")] if "R" in names else np.full(len(time_s), float(plan.lane_radius_m))
        return cls(names, time_s, q, np.asarray(plan.velocities, dtype=float).reshape(q.shape),
                   np.asarray(plan.feedforward_torques, dtype=float).reshape(len(time_s), 2), radius_m)

    def column(self, name: str) -> np.ndarray:
        """The positions of the joint name over the plan, (N,), rad or m."""
        return self.q[:, self.joint_names.index(name)]


def saturation_risk(peak_fraction: float) -> str:
    """'low', 'moderate' or 'high' by the peak feed-forward torque's fraction of its motor's limit."""
    if peak_fraction < MODERATE_RISK_FRACTION:
        return "low"
    return "moderate" if peak_fraction < HIGH_RISK_FRACTION else "high"


def repeats_of(primitive_ids: Sequence[str]) -> list[tuple[str, int]]:
    """Consecutive equal ids counted: [a, b, b, c] -> [(a, 1), (b, 2), (c, 1)]."""
    runs: list[tuple[str, int]] = []
    for primitive_id in primitive_ids:
        if runs and runs[-1][0] == primitive_id:
            runs[-1] = (primitive_id, runs[-1][1] + 1)
        else:
            runs.append((primitive_id, 1))
    return runs


@dataclasses.dataclass(frozen=True)
class PlanSummary:
    """What a plan asks of the vehicle and its motors.

    Per motor (heave, pitch): the peak |feed-forward torque|, N m, its fraction of the motor's limit, and the primitive
    it falls in (a junction sample is the earlier one's).
    """

    sequence: tuple[tuple[str, int], ...]   # the primitives in order, consecutive repeats counted
    time_scales: tuple[float, ...]          # the segments' lambdas, each once
    start_alpha_rad: float
    duration_s: float
    advance_rad: float                      # alpha(end) - alpha(start)
    distance_m: float                       # along the path: the integral of R dalpha
    start_radius_m: float
    end_radius_m: float
    peak_torque_n_m: tuple[float, float]
    peak_fraction: tuple[float, float]
    peak_primitive: tuple[str, str]

    @classmethod
    def of(cls, plan: Any, torque_limits_n_m: Sequence[float]) -> "PlanSummary":
        """The summary of a PlannedTrajectory message against the motors' torque limits, N m."""
        arrays = PlanArrays.of(plan)
        alpha = arrays.column("alpha")
        segment_of_sample = np.zeros(len(arrays.time_s), dtype=int)
        for index, segment in enumerate(plan.segments):
            segment_of_sample[segment.first_sample:segment.first_sample + segment.sample_count] = index
        peaks = np.abs(arrays.torque_n_m).max(axis=0)
        where = np.abs(arrays.torque_n_m).argmax(axis=0)
        names = [segment.primitive_id for segment in plan.segments]
        return cls(sequence=tuple(repeats_of(names)),
                   time_scales=tuple(dict.fromkeys(float(s.time_scale) for s in plan.segments)),
                   start_alpha_rad=float(alpha[0]), duration_s=float(arrays.time_s[-1] - arrays.time_s[0]),
                   advance_rad=float(alpha[-1] - alpha[0]),
                   distance_m=float(np.sum(0.5 * (arrays.radius_m[1:] + arrays.radius_m[:-1]) * np.diff(alpha))),
                   start_radius_m=float(arrays.radius_m[0]), end_radius_m=float(arrays.radius_m[-1]),
                   peak_torque_n_m=(float(peaks[0]), float(peaks[1])),
                   peak_fraction=(float(peaks[0] / torque_limits_n_m[0]), float(peaks[1] / torque_limits_n_m[1])),
                   peak_primitive=(names[segment_of_sample[where[0]]], names[segment_of_sample[where[1]]]))

    @property
    def risk(self) -> str:
        """The plan's saturation risk by its larger peak fraction: 'low', 'moderate' or 'high'."""
        return saturation_risk(max(self.peak_fraction))

    def lines(self, torque_limits_n_m: Sequence[float]) -> list[str]:
        """The summary as lines of text, the torques beside torque_limits_n_m (N m)."""
        sequence = ", ".join(f"{pid} x{count}" if count > 1 else pid for pid, count in self.sequence)
        motor = int(np.argmax(self.peak_fraction))
        torques = [f"{name} {peak:.3f} N m ({100 * fraction:.0f} % of {limit:.3g} N m, in {primitive})"
                   for name, peak, fraction, limit, primitive in zip(
                       ("heave", "pitch"), self.peak_torque_n_m, self.peak_fraction, torque_limits_n_m,
                       self.peak_primitive)]
        return [f"primitives: {sequence}",
                f"time scale: {', '.join(f'{scale:g}' for scale in self.time_scales)}",
                f"duration: {self.duration_s:.3f} s",
                f"distance: {self.advance_rad:+.3f} rad of alpha from {self.start_alpha_rad:+.3f} rad, "
                f"{self.distance_m:+.3f} m along the lane",
                f"lanes: R {self.start_radius_m:.3f} m at the start, {self.end_radius_m:.3f} m at the end",
                f"peak feed-forward torque: {'; '.join(torques)}",
                f"saturation risk: {self.risk} (the {('heave', 'pitch')[motor]} at "
                f"{100 * self.peak_fraction[motor]:.0f} % of its limit in {self.peak_primitive[motor]}; low under "
                f"{100 * MODERATE_RISK_FRACTION:.0f} %, high from {100 * HIGH_RISK_FRACTION:.0f} %)"]


def write_plan_figure(plan: Any, torque_limits_n_m: Sequence[float], path: Path) -> Path:
    """Draw the plan against plan time into path.

    The plan drawn: alpha and alphadot, heave and pitch, the feed-forward torques against the motors' limits,
    against plan time, the primitives' junctions marked.
    """
    from swim_bringup.figures import pyplot, save_figure
    arrays = PlanArrays.of(plan)
    figure, axes = pyplot().subplots(4, 1, sharex=True, figsize=(8, 10))
    alpha = arrays.joint_names.index("alpha")
    axes[0].plot(arrays.time_s, arrays.q[:, alpha])
    axes[0].set_ylabel("alpha [rad]")
    axes[1].plot(arrays.time_s, arrays.qdot[:, alpha])
    axes[1].set_ylabel("alphadot [rad/s]")
    for name, label in (("phi", "phi (heave)"), ("theta", "theta (pitch)")):
        axes[2].plot(arrays.time_s, arrays.column(name), label=label)
    axes[2].set_ylabel("foil [rad]")
    axes[2].legend()
    for column, (name, limit) in enumerate(zip(("heave", "pitch"), torque_limits_n_m)):
        line, = axes[3].plot(arrays.time_s, arrays.torque_n_m[:, column], label=f"{name} torque")
        for sign in (1.0, -1.0):
            axes[3].axhline(sign * limit, color=line.get_color(), linestyle="--", linewidth=0.8)
    axes[3].set_ylabel("feed-forward [N m]\n(dashed: limits)")
    axes[3].set_xlabel("plan time [s]")
    axes[3].legend()
    for segment in list(plan.segments)[1:]:
        for axis in axes:
            axis.axvline(segment.start_time_s, color="grey", linewidth=0.3)
    axes[0].set_title(f"plan: {len(plan.segments)} primitives, {arrays.time_s[-1]:.2f} s")
    path.parent.mkdir(parents=True, exist_ok=True)
    return save_figure(figure, path)


def latest_vehicle(session: Any, timeout_s: float) -> Optional[VehicleState]:
    """The vehicle as the latest joint_states gives it, or None without a plant.

    The vehicle as the latest joint_states gives it, or None when, once the graph has settled, no node publishes
    joint_states and no plant node (PLANT_NODES) is up; CommandError if one is and no joint_states arrives within
    timeout_s (a plant's publisher may be discovered after the plant).
    """
    from rclpy.qos import QoSProfile, QoSReliabilityPolicy
    from sensor_msgs.msg import JointState

    from swim_ros.calls import spin_until
    latest: list[Any] = []
    # best effort: matches a reliable publisher and a best-effort one alike
    subscription = session.node.create_subscription(
        JointState, "joint_states", latest.append, QoSProfile(depth=1, reliability=QoSReliabilityPolicy.BEST_EFFORT))

    def published() -> bool:
        return subscription.get_publisher_count() > 0 or any(
            name in PLANT_NODES for name, _ in session.node.get_node_names_and_namespaces())
    spin_until_settled(session, lambda: bool(latest), timeout_s)
    if not latest and published():
        spin_until(session.executor, lambda: bool(latest), timeout_s)
    plant = published()
    session.node.destroy_subscription(subscription)
    if not latest:
        if not plant:
            return None
        raise CommandError(f"a plant runs, or joint_states has a publisher, but no joint_states arrived within "
                           f"{timeout_s:g} s")
    from swim_bringup.maneuver_node import vehicle_of
    from swim_control.errors import StateMessageError
    try:
        return vehicle_of(latest[-1])
    except StateMessageError as err:
        raise CommandError(f"the latest joint_states is not the vehicle's (alpha, [R,] phi, theta): {err}") from err


def plan_request(goal: ManeuverGoal, vehicle: Optional[VehicleState], states: Sequence[str]) -> Any:
    """The RequestManeuver a goal makes from where the vehicle is.

    It carries the vehicle's alpha (0 without one) and, for a goal state, the rest state of its vehicle on the lane
    nearest its R (without one: the planner's default start).
    """
    from swim_interfaces.srv import RequestManeuver

    from swim_ros.calls import new_request_id
    request = RequestManeuver.Request(mode=goal.mode, primitive_ids=list(goal.primitive_ids),
                                      repeat_counts=list(goal.repeats), goal_state=goal.goal_state,
                                      goal_alpha_rad=goal.goal_alpha_rad, time_scale=goal.time_scale,
                                      start_alpha_rad=vehicle.alpha_rad if vehicle is not None else 0.0,
                                      request_id=new_request_id())
    if goal.mode == MODE_GOAL and vehicle is not None:
        try:   # the nearest lane, however far: the plan shows where a vehicle on it would go
            request.start_state = rest_state_of(vehicle, states, math.inf)
        except ManeuverGoalError as err:
            raise CommandError(str(err)) from err
    return request


def vehicle_line(vehicle: Optional[VehicleState], request: Any) -> str:
    """The line that says where the maneuver starts."""
    if vehicle is None:
        return "start: no joint_states on the domain: alpha 0" + (
            ", the planner's default start state" if request.mode == MODE_GOAL else "")
    where = f"alpha {vehicle.alpha_rad:+.4f} rad" + (
        "" if vehicle.lane_radius_m is None else f", R {vehicle.lane_radius_m:.4f} m")
    return f"start: {where} (joint_states)" + (f", state {request.start_state}" if request.start_state else "")


def plan_command(args: argparse.Namespace) -> int:
    """The plan command: plan the maneuver from where the vehicle is and print it; the exit status."""
    from swim_interfaces.srv import RequestManeuver

    from swim_model import load_rig
    goal = maneuver_goal(args)
    session = Session()
    try:
        planner = session.node.create_client(RequestManeuver, "request_maneuver")
        wait_for(session, planner.service_is_ready, "planner_node (request_maneuver)", args.wait)
        states = list_primitives(session, args.wait).states if goal.mode == MODE_GOAL else []
        vehicle = latest_vehicle(session, JOINT_STATE_TIMEOUT_S)
        request = plan_request(goal, vehicle, states)
        reply = call(session, planner, request, "planner_node (request_maneuver)", args.wait)
    finally:
        session.close()
    if not reply.success:
        raise CommandError(f"the planner refused the maneuver: {reply.message}")
    limits = load_rig(None).torque_limits_n_m
    print(vehicle_line(vehicle, request))
    print("\n".join(PlanSummary.of(reply.plan, limits).lines(limits)))
    if args.plot is not None:
        print(f"plot: {write_plan_figure(reply.plan, limits, args.plot)}")
    return EXIT_DONE


# ----- run -------------------------------------------------------------------------------------------------------
class InterruptWatch:
    """Ctrl-C as a request, never as an exception in the middle of a callback.

    Ctrl-C never raises in the middle of a callback (a bag write): the signal handler sets
    requested and triggers a guard condition of the session's node; the executor runs its callback between other
    callbacks, and it raises Interrupted there while armed, which ends the wait under way (goal_result) at once.
    """

    def __init__(self, node: Any) -> None:
        self.requested = False
        self.armed = False
        self._guard = node.create_guard_condition(self._on_guard)
        self._previous = signal.signal(signal.SIGINT, self._on_signal)

    def _on_signal(self, signum: int, frame: Optional[FrameType]) -> None:
        if self.requested:
            print(f"\n{PROG}: Ctrl-C again: still waiting for the goal's end (and the bag's)", file=sys.stderr,
                  flush=True)
        self.requested = True
        self._guard.trigger()

    def _on_guard(self) -> None:
        if self.armed and self.requested:
            self.armed = False
            raise Interrupted()

    def arm(self) -> None:
        """Raise Interrupted from now on (at once if Ctrl-C came already)."""
        if self.requested:
            raise Interrupted()
        self.armed = True

    def restore(self) -> None:
        """Give SIGINT back to the handler it had before."""
        signal.signal(signal.SIGINT, self._previous)


def goal_message(goal: ManeuverGoal) -> Any:
    """The PerformManeuver goal of a ManeuverGoal (maneuver_node.goal_of reads it back)."""
    from swim_interfaces.action import PerformManeuver
    return PerformManeuver.Goal(mode=goal.mode, primitive_ids=list(goal.primitive_ids),
                                repeat_counts=list(goal.repeat_counts), goal_state=goal.goal_state,
                                goal_alpha_rad=goal.goal_alpha_rad, time_scale=goal.time_scale,
                                path_tolerance_alpha_rad=goal.tolerances.path_alpha_rad,
                                path_tolerance_r_m=goal.tolerances.path_r_m,
                                goal_tolerance_alpha_rad=goal.tolerances.goal_alpha_rad,
                                goal_tolerance_r_m=goal.tolerances.goal_r_m)


def result_name(code: int) -> str:
    """The name of a PerformManeuver result code."""
    from swim_interfaces.action import PerformManeuver
    names = {getattr(PerformManeuver.Result, name): name for name in RESULT_NAMES}
    return names.get(code, f"code {code}")


def exit_status_of(code: int, interrupted: bool) -> int:
    """A PerformManeuver result code as swim-maneuver's exit status."""
    name = result_name(code)
    if name == "SUCCESSFUL":
        return EXIT_DONE
    if name in REFUSED_RESULTS:
        return EXIT_REFUSED
    return EXIT_INTERRUPTED if name == "CANCELED" and interrupted else EXIT_FAILED


def progress_text(feedback: Any) -> tuple[str, str]:
    """A PerformManeuver feedback as the progress bar's description and its line after the bar."""
    phase = PHASE_NAMES.get(feedback.phase, f"phase {feedback.phase}")
    if not feedback.primitive_id:
        return phase, ""
    return phase, (f"{feedback.primitive_id} ({feedback.segment_index + 1}/{feedback.segment_count}), alpha error "
                   f"{1e3 * feedback.alpha_error_rad:+.1f} mrad, R error {1e3 * feedback.r_error_m:+.1f} mm")


class ManeuverRun:
    """One perform_maneuver goal from its sending to its result, on a session (a RunClient when recorded)."""

    def __init__(self, session: Any, interrupt: InterruptWatch) -> None:
        from swim_interfaces.action import PerformManeuver

        from swim_ros.calls import ActionClient, GoalStatusWatch
        self.session, self.interrupt = session, interrupt
        self.action = ActionClient(session.node, PerformManeuver, "perform_maneuver")
        self.status = GoalStatusWatch(session.node, "perform_maneuver")
        self._server_seen_s = time.monotonic()
        self._watching_server = False
        session.node.create_timer(SERVER_CHECK_PERIOD_S, self._check_server)

    def _check_server(self) -> None:
        now_s = time.monotonic()
        if self.action.server_is_ready() or not self._watching_server:
            self._server_seen_s = now_s
        elif now_s - self._server_seen_s > SERVER_LOST_AFTER_S:
            self._watching_server = False
            raise ServerLost()

    def wait_for_server(self, wait_s: float) -> None:
        """Wait up to wait_s for the maneuver server; CommandError if it does not come."""
        wait_for(self.session, self.action.server_is_ready, "maneuver_node (perform_maneuver)", wait_s)

    def fly(self, goal: ManeuverGoal, timeout_s: float, on_feedback: Callable[[Any], None]) -> Any:
        """Send the goal and return its result.

        The result is a PerformManeuver.Result, at its end or after a cancel on Ctrl-C (self.interrupt.requested then
        holds). CommandError if it was not accepted or gave no result.
        """
        from swim_ros.calls import CallFailed, cancel_goal, goal_result, send_goal
        executor = self.session.executor
        self.interrupt.armed = False   # a goal sent is never left without its handle: Ctrl-C waits for it
        try:
            handle = send_goal(executor, self.action, goal_message(goal), self.status,
                               lambda message: on_feedback(message.feedback))
        except CallFailed as err:
            raise CommandError(f"maneuver_node (perform_maneuver): {err}") from err
        if not handle.accepted:
            raise CommandError("maneuver_node refused the goal")
        self._watching_server = True
        try:
            try:
                self.interrupt.arm()
                return goal_result(executor, handle, timeout_s).result
            except Interrupted:
                print(f"\n{PROG}: Ctrl-C: canceling the maneuver", file=sys.stderr, flush=True)
                timed_out = False
            except CallFailed:
                timed_out = True
            finally:
                self.interrupt.armed = False
            try:
                cancel_goal(executor, handle)
                result = goal_result(executor, handle, CANCEL_RESULT_TIMEOUT_S).result
            except CallFailed as err:
                raise CommandError(f"the cancel's end was not confirmed: {err}", EXIT_FAILED) from err
        except ServerLost:
            raise CommandError(f"maneuver_node left the ROS graph during the maneuver (missing for "
                               f"{SERVER_LOST_AFTER_S:g} s)", EXIT_FAILED) from None
        finally:
            self._watching_server = False
        if timed_out:
            raise CommandError(f"no end of the maneuver within {timeout_s:g} s: canceled, "
                               f"{result_name(result.error_code)}", EXIT_FAILED)
        return result


def run_command(args: argparse.Namespace) -> int:
    """The run command: the maneuver flown by the maneuver server, recorded with --record; the exit status."""
    from tqdm import tqdm

    from swim_bringup.run_client import RunClient
    goal = maneuver_goal(args)
    bag_path = None if args.record is None else args.record / "bag"
    if bag_path is not None and bag_path.exists():
        raise CommandError(f"{bag_path} exists; choose another --record folder")
    started_s = time.monotonic()
    session = Session() if bag_path is None else RunClient(bag_path)
    interrupt = InterruptWatch(session.node)
    try:
        interrupt.arm()
        run = ManeuverRun(session, interrupt)
        run.wait_for_server(args.wait)
        if isinstance(session, RunClient):
            try:
                session.wait_for_nodes(args.wait)
            except RunError as err:
                raise CommandError(f"recording: {err}") from err
        with tqdm(total=100, unit="%", desc="sending", file=sys.stderr) as bar:
            def on_feedback(feedback: Any) -> None:
                description, postfix = progress_text(feedback)
                bar.set_description_str(description, refresh=False)
                bar.set_postfix_str(postfix, refresh=False)
                bar.update(round(100 * feedback.progress) - bar.n)
            result = run.fly(goal, args.timeout, on_feedback)
        interrupted = interrupt.requested
        name = result_name(result.error_code)
        if isinstance(session, RunClient) and name not in REFUSED_RESULTS and result.duration_s > 0.0:
            try:
                session.drain(result.duration_s)
            except RunError as err:
                print(f"{PROG}: the bag may miss the last periods: {err}", file=sys.stderr)
    except Interrupted:   # Ctrl-C before the goal was sent: nothing moved
        raise CommandError("Ctrl-C: no maneuver sent", EXIT_INTERRUPTED) from None
    finally:
        interrupt.restore()
        session.close()
    status = exit_status_of(result.error_code, interrupted)
    print(f"{PROG}: {name}: {result.error_string}; {result.duration_s:.3f} s tracked, final alpha error "
          f"{1e3 * result.final_alpha_error_rad:+.2f} mrad, R error {1e3 * result.final_r_error_m:+.2f} mm")
    if status != EXIT_DONE:
        print(f"{PROG}: {'canceled by Ctrl-C' if status == EXIT_INTERRUPTED else name}: {result.error_string}",
              file=sys.stderr)
    if args.record is not None:
        status = max(status, report_recorded_run(args.record, result, started_s))
    return status


def report_recorded_run(run_dir: Path, result: Any, started_s: float) -> int:
    """Write the report and figures of a recorded run; the exit status.

    report.json and figures of a recorded run, a summary printed; EXIT_FAILED when the bridge latched a fault
    during it (the motors were then off), else EXIT_DONE.
    """
    from swim_bringup.reports import TrackerResult
    tracker_result = TrackerResult(error_code=result.error_code, error_string=result.error_string,
                                   final_alpha_error_rad=result.final_alpha_error_rad, duration_s=result.duration_s)
    try:
        report = write_run_report(run_dir, tracker_result, started_s)
    except MissingTopic as err:
        print(f"{PROG}: no report: {err}; the bag is in {run_dir / 'bag'}", file=sys.stderr)
        return EXIT_DONE
    print(summary_table({run_dir.name: report}))
    print(f"{PROG}: report, figures and bag in {run_dir}")
    failures = [failure for failure in run_failures(report) if failure.startswith("the bridge")]
    for failure in failures:
        print(f"{PROG}: {failure}", file=sys.stderr)
    return EXIT_FAILED if failures else EXIT_DONE


# ----- status ----------------------------------------------------------------------------------------------------
def goal_summary(statuses: dict[bytes, int]) -> str:
    """An action's goals (its latched status list, in the order the server lists them) as a line."""
    from action_msgs.msg import GoalStatus
    names = {GoalStatus.STATUS_ACCEPTED: "accepted", GoalStatus.STATUS_EXECUTING: "executing",
             GoalStatus.STATUS_CANCELING: "canceling", GoalStatus.STATUS_SUCCEEDED: "succeeded",
             GoalStatus.STATUS_CANCELED: "canceled", GoalStatus.STATUS_ABORTED: "aborted"}
    under_way = {goal_id: status for goal_id, status in statuses.items()
                 if status in (GoalStatus.STATUS_ACCEPTED, GoalStatus.STATUS_EXECUTING, GoalStatus.STATUS_CANCELING)}
    ended = [status for goal_id, status in statuses.items() if goal_id not in under_way]
    parts = [f"{names[status]} goal {goal_id.hex()[:8]}" for goal_id, status in under_way.items()]
    if not parts:
        parts.append("no goal under way")
    if ended:
        parts.append(f"{len(ended)} ended, the last {names.get(ended[-1], str(ended[-1]))}")
    return "; ".join(parts) if statuses else "no goal under way (none seen)"


def bridge_lines(session: Any, diagnostics: list[Any]) -> list[str]:
    """The bridge's lifecycle state (get_state) and the latest /diagnostics of its I/O loop."""
    from lifecycle_msgs.srv import GetState

    from swim_ros.calls import CallFailed, RetryPolicy, call_service, spin_until
    lines = []
    client = session.node.create_client(GetState, "/bridge_node/get_state")
    try:
        policy = RetryPolicy(attempt_timeout_s=STATUS_ATTEMPT_S, attempts=2,
                             discovery_timeout_s=STATUS_ATTEMPT_S)
        state = call_service(session.executor, client, GetState.Request(), policy).current_state
        lines.append(f"bridge lifecycle state: {state.label}")
    except CallFailed as err:
        lines.append(f"bridge lifecycle state: unknown ({err})")
    spin_until(session.executor, lambda: bool(diagnostics), DIAGNOSTICS_TIMEOUT_S)
    if not diagnostics:
        return lines + [f"bridge diagnostics: none on /diagnostics within {DIAGNOSTICS_TIMEOUT_S:g} s"]
    status = diagnostics[-1]
    values = {pair.key: pair.value for pair in status.values}
    lines.append(f"bridge I/O loop: {DIAGNOSTIC_LEVELS.get(ord(status.level), 'level ?')}: {status.message}")
    lines.append(f"bridge faults latched: {values.get('faults', 'unknown')}; emergency stop pending: "
                 f"{values.get('emergency_stop_pending', 'unknown')}; watchdog {values.get('watchdog', 'unknown')}; "
                 f"overruns {values.get('overruns', 'unknown')}")
    return lines


def status_command(args: argparse.Namespace) -> int:
    """The status command: print the system's nodes, their goals and the bridge's state; the exit status."""
    from diagnostic_msgs.msg import DiagnosticArray

    from swim_ros.calls import GoalStatusWatch, spin_until
    session = Session()
    try:
        watches = {action: GoalStatusWatch(session.node, action) for _, action in WATCHED_ACTIONS}
        diagnostics: list[Any] = []

        def on_diagnostics(array: Any) -> None:
            diagnostics.extend(s for s in array.status if s.name.endswith("bridge_node: I/O loop"))
        session.node.create_subscription(DiagnosticArray, "/diagnostics", on_diagnostics, 10)

        def nodes_up() -> dict[str, str]:
            return {name: (namespace.rstrip("/") + "/" + name) for name, namespace
                    in session.node.get_node_names_and_namespaces() if name in KNOWN_NODES}
        wait_for(session, lambda: bool(nodes_up()), f"node of the swim system ({', '.join(KNOWN_NODES)})",
                 args.wait)
        spin_until_settled(session, lambda: set(KNOWN_NODES) - set(PLANT_NODES) <= set(nodes_up())
                           and any(plant in nodes_up() for plant in PLANT_NODES), args.wait)
        up = nodes_up()
        spin_until(session.executor, lambda: all(watches[action].statuses for server, action in WATCHED_ACTIONS
                                                  if server in up), LATCHED_STATUS_TIMEOUT_S)
        lines = [f"ROS domain {ros_domain()}: {len(up)} of the system's nodes up"]
        lines += [f"  {name:<20} {'up as ' + up[name] if name in up else '-':<28} {role}"
                  for name, role in KNOWN_NODES.items()]
        if not any(name in up for name in PLANT_NODES):
            lines.append("no plant (sim_node or bridge_node): nothing moves")
        if "bridge_node" in up:
            lines += bridge_lines(session, diagnostics)
        for server, action in WATCHED_ACTIONS:
            lines.append(f"{action} ({server}): " + (goal_summary(watches[action].statuses) if server in up
                                                      else "server not up"))
    finally:
        session.close()
    print("\n".join(lines))
    return EXIT_DONE


def trigger(service: str, wait_s: float) -> int:
    """Call a std_srvs/Trigger service of the bridge and print its answer; the exit status.

    Call the bridge's std_srvs/Trigger service (the e-stop and its reset: asking twice does what asking once
    does, so a lost answer is asked again); print its answer.
    """
    from std_srvs.srv import Trigger
    session = Session()
    try:
        client = session.node.create_client(Trigger, service)
        response = call(session, client, Trigger.Request(), f"bridge_node ({service})", wait_s)
    finally:
        session.close()
    if not response.success:
        raise CommandError(f"{service} refused: {response.message}")
    print(f"{PROG}: {service}: {response.message}")
    return EXIT_DONE


def estop_command(args: argparse.Namespace) -> int:
    """The estop command: the bridge's emergency stop; the exit status."""
    return trigger("/emergency_stop", args.wait)


def reset_command(args: argparse.Namespace) -> int:
    """The reset command: reset the bridge's emergency stop; the exit status."""
    return trigger("/reset_emergency_stop", args.wait)


def bridge_command(args: argparse.Namespace) -> int:
    """Make a lifecycle transition of bridge_node.

    A lifecycle transition of bridge_node (swim_ros.calls.change_lifecycle_state: asked again only after its
    state shows it was not made).
    """
    from swim_ros.calls import CallFailed, change_lifecycle_state
    session = Session()
    try:
        policy = dataclasses.replace(PLANNER_POLICY, discovery_timeout_s=args.wait)
        try:
            made = change_lifecycle_state(session.node, session.executor, "bridge_node",
                                          BRIDGE_TRANSITIONS[args.transition], policy)
        except CallFailed as err:
            raise CommandError(f"bridge_node ({args.transition}): {err}") from err
    finally:
        session.close()
    if not made:
        raise CommandError(f"bridge_node refused {args.transition} (swim-maneuver status: its state and faults)")
    print(f"{PROG}: bridge_node: {args.transition} done")
    return EXIT_DONE


COMMANDS = {"list": list_command, "plan": plan_command, "run": run_command, "status": status_command,
            "estop": estop_command, "reset": reset_command, "bridge": bridge_command}


def main(argv: Optional[list[str]] = None) -> int:
    """The swim-maneuver command; its exit status."""
    args = parse_arguments(argv)
    try:
        return COMMANDS[args.command](args)
    except CommandError as err:
        print(f"{PROG}: {err}", file=sys.stderr)
        return err.exit_status
    except KeyboardInterrupt:
        print(f"\n{PROG}: Ctrl-C", file=sys.stderr)
        return EXIT_INTERRUPTED


if __name__ == "__main__":
    sys.exit(main())
