"""tracker_node fuzzed over DDS (swim_ros.testing.fuzz): its joint_states input, execute_plan goals and parameter
sets.

One node for the module, its stale-state limit far past the test's pace.

joint_states, the node idle: a well-formed state is answered by a command stamped like it, within its deadline; a
malformed one never is (the well-formed state sent after it is answered, and no command carries the malformed
one's stamp); every command is finite and within the motor limits.

execute_plan goals, against test_tracker_node's lock-step plant: the plan of test_tracker_node (a real trajectory,
encoded by swim_ros.trajectory_messages.trajectory_to_message) re-made in ways that keep it valid (cut short, re-timed
by Theorem 1, moved to another lane and alpha, its segment split, any unicode in its labels, gains and single
values huge but within MAX_PLAN_MAGNITUDE), then broken in one way or none (PLAN_DEFECTS), with any tolerances.
A broken goal ends INVALID_PLAN with a reason within its deadline, and a plan being tracked goes on as before (it is
canceled afterwards, not preempted); a valid one preempts it and is tracked until it ends or is canceled, its result
consistent with its tolerances. Every command finite and within the motor limits, every tracking_state and
feedback finite, the node alive; after the fuzz the plan is tracked to its end.
"""
import dataclasses
import math
import time
from typing import Optional

import numpy as np
import pytest
import test_tracker_node
from hypothesis import assume, event, example, given
from hypothesis import strategies as st
from test_tracker_node import PERIOD_S, PLAN_DURATION_S, POLICY, run_until, send

from swim_ros.testing.fixtures import STARTUP_TIMEOUT_S, new_rclpy_context, running_node
from swim_ros.testing.fuzz import (
    EDGE_FLOATS,
    NON_FINITE,
    any_float,
    fuzz_parameter_sets,
    fuzz_settings,
    joint_states,
    to_joint_state,
    unicode_name,
)

JOINTS = ("alpha", "phi", "theta")
#: a state's command: within a period here; 5 s for a loaded 2-core host (and for discovery on the first one)
DEADLINE_S = 5.0
#: a refused goal's result: milliseconds for the plan's checks, a plan of MAX_TRACKED_SAMPLES + 1 samples (8 MB)
#: crossing in fragments included; 10 s for a loaded host
GOAL_DEADLINE_S = 10.0
#: the largest stale-state limit (tracker_node's range): the module's pace never makes a state stale
STALE_AFTER_PERIODS = 1000
#: the module's plan, tracked while a fuzzed goal is sent to it: these periods first
BACKGROUND_PERIODS = 3
#: a canceled or ended goal's result comes within a period of the cancel being taken; 100 periods leave margin
RESULT_PERIODS = 100
#: the module's plan tracked to its end from anywhere in it, with RESULT_PERIODS of margin
BACKGROUND_END_PERIODS = int(round(PLAN_DURATION_S / PERIOD_S)) + RESULT_PERIODS

#: test_tracker_node's fixtures, for this module's node: the plan (a ramped gait with its gains) and the lock-step
#: plant with an action client
plan_message = test_tracker_node.plan_message
rig_loop = test_tracker_node.rig_loop


@pytest.fixture(scope="module")
def tracker(ros_domain, tmp_path_factory):
    # a stale limit far past the test's pace: its zero commands would otherwise come between the test's states
    with running_node("swim_controller", "tracker_node", tmp_path_factory.mktemp("fuzz_tracker") / "log.txt",
                      "-p", f"stale_after_periods:={STALE_AFTER_PERIODS}") as process:
        yield process


class StateSource:
    """The test's side: publishes joint_states with stamps of its own, collects joint_commands."""

    def __init__(self, context):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from sensor_msgs.msg import JointState
        self.node = rclpy.create_node("tracker_fuzz_source", context=context)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.publisher = self.node.create_publisher(JointState, "joint_states", 10)
        self.commands = []
        self.node.create_subscription(JointState, "joint_commands", self.commands.append, 50)
        self.next_second = 100

    def stamp(self):
        from builtin_interfaces.msg import Time
        self.next_second += 1   # never zero: a zero stamp means "not stamped"
        return Time(sec=self.next_second)

    def answered(self, stamp):
        from swim_ros.calls import spin_until
        return spin_until(self.executor, lambda: any(c.header.stamp == stamp for c in self.commands), DEADLINE_S)

    def discover(self):
        """States sent before the node's reader matched are lost: send until one is answered."""
        deadline = time.monotonic() + STARTUP_TIMEOUT_S
        while True:
            stamp = self.stamp()
            self.publisher.publish(valid_state(stamp))
            if self.answered(stamp) or time.monotonic() > deadline:
                break
        assert any(c.header.stamp == stamp for c in self.commands), "tracker_node never answered a state"

    def close(self):
        self.executor.shutdown()
        self.node.destroy_node()


def valid_state(stamp):
    from sensor_msgs.msg import JointState
    message = JointState(name=list(JOINTS), position=[0.0, 0.1, -0.1], velocity=[0.0, 0.0, 0.0])
    message.header.stamp = stamp
    return message


@pytest.fixture(scope="module")
def source(tracker, ros_domain):
    with new_rclpy_context() as context:
        source = StateSource(context)
        source.discover()
        yield source
        source.close()


@pytest.fixture(scope="module")
def torque_limits():
    from swim_model import load_rig
    return np.array(load_rig().torque_limits_n_m)


def values():
    """Positions and velocities: ordinary, at float64's edges (finite: well formed, the node must cope), and any."""
    return st.one_of(st.floats(-3.0, 3.0), st.sampled_from(EDGE_FLOATS), any_float())


def check_commands(efforts, torque_limits):
    """Every command's efforts finite and within the motor limits."""
    for effort in efforts:
        assert all(math.isfinite(v) for v in effort), effort
        assert np.all(np.abs(effort) <= torque_limits), effort


@fuzz_settings(80)
@given(state=joint_states(JOINTS, values()))
def test_fuzzed_states_are_answered_only_when_well_formed_with_finite_torque(tracker, source, torque_limits, state):
    stamp = source.stamp()
    source.commands.clear()
    source.publisher.publish(to_joint_state(state, stamp))
    if state.defect is None:
        start = time.monotonic()
        assert source.answered(stamp), state
        assert time.monotonic() - start < DEADLINE_S
    else:   # refused: the good state after it is answered, and nothing was for the bad one
        good = source.stamp()
        source.publisher.publish(valid_state(good))
        assert source.answered(good)
        assert not any(c.header.stamp == stamp for c in source.commands), state
    check_commands([c.effort for c in source.commands], torque_limits)
    assert tracker.poll() is None


# ----- execute_plan goals ------------------------------------------------------------------------------------
#: the Trajectory arrays and the PlannedTrajectory fields that carry them
PLAN_ARRAYS = {"q": "positions", "qdot": "velocities", "foil_acceleration": "foil_accelerations",
               "torque": "feedforward_torques", "lqr_gain": "lqr_gains", "riccati_input_gain": "sliding_gains"}
#: the PrimitiveSegment fields a "segments" defect sets to a bad value
SEGMENT_FIELDS = {"time scale": "time_scale", "duration": "duration_s", "start": "start_time_s",
                  "alpha offset": "alpha_offset_rad"}
#: float64's largest
LARGEST_FLOAT = 1.7976931348623157e308
#: what a broken plan has, each invalid by PlannedTrajectory's and ExecutePlan's contracts (their .msg and .action
#: comments, swim_ros.trajectory_messages.trajectory_from_message's documented checks, the rig's tank): the ways each
#: is made, (where, value). The first of each runs in every run (AS_PLANNED): among them times from 1e-9 s, an
#: infinite end time, a value whose rates overflow, steps of 1e-300 s and a lane of 1e300 m, plans a Trajectory's
#: own checks pass and only the decoder's range check and tracker_node's tank check refuse.
PLAN_DEFECTS = {
    # every version but those the tracker reads (swim_ros.trajectory_messages.READABLE_INTERFACE_VERSIONS, 4 and 5):
    # the older ones, the next one and the largest uint32
    "interface version": tuple(("", v) for v in (1.0, 0.0, 2.0, 3.0, 6.0, 4294967295.0)),
    "too many samples": (("", 0.0),),
    "no samples": (("", 0.0),),
    "one sample": (("", 0.0),),
    "joint names": tuple((w, 0.0) for w in ("unicode", "missing", "reordered", "R added", "free vehicle")),
    "array length": tuple((w, v) for w in PLAN_ARRAYS.values() for v in (0.0, -3.0, -1.0, 1.0, 2.0)),
    "non-finite value": (("time_from_start_s", math.inf),) + tuple(
        (w, v) for w in ("time_from_start_s", *PLAN_ARRAYS.values()) for v in NON_FINITE),
    "value past the bound": (("positions", LARGEST_FLOAT),) + tuple(
        (w, v) for w in PLAN_ARRAYS.values() for v in (1e151, -1e200, 1e300, -LARGEST_FLOAT)),
    "times out of order": (("swapped", 0.0), ("repeated", 0.0)),
    "times not from 0": tuple(("", v) for v in (1e-9, 0.5, -0.01, -1.0, 1e6)),
    "time span past the bound": tuple(("", v) for v in (1e160, 1e300)),   # every time multiplied by it
    "time steps too short": tuple(("", v) for v in (1e-300, 1e-200)),     # every time multiplied by it
    "lane radius": tuple(("", v) for v in (1e300, *NON_FINITE, 0.0, -0.43, -5e-324, 0.875, 1.0)),
    "segments": tuple((w, 0.0) for w in ("none", "short", "long", "first sample")) + tuple(
        (w, v) for w, values in (("time scale", (0.0, -1.0, *NON_FINITE)), ("duration", (-1.0, *NON_FINITE)),
                                 ("start", NON_FINITE), ("alpha offset", NON_FINITE)) for v in values),
    "tolerance": tuple((w, v) for w in ("0", "1", "2", "3") for v in (-5e-324, -1.0, -1e300, *NON_FINITE)),
}
#: values of a plan array within MAX_PLAN_MAGNITUDE (1e150) with their rates between samples (10 ms apart at the
#: least here): 1e100 is far past any physical plan, a node must cope
HUGE_WITHIN_THE_BOUND = 1e100
#: lanes, m, inside the tank (radius 0.875 m): the rig's second lane and one near the wall
OTHER_LANES_M = (0.48, 0.8)
#: ExecutePlan's tolerances, in the order of PlanEdit.tolerances
TOLERANCE_NAMES = ("path_tolerance_alpha_rad", "path_tolerance_r_m", "goal_tolerance_alpha_rad",
                   "goal_tolerance_r_m")


@dataclasses.dataclass(frozen=True)
class PlanEdit:
    """How one example re-makes the module's plan (every step keeps it valid), the goal's tolerances, which way
    a defect is made (variant, at, text: see break_plan) and how the goal is sent and followed."""

    samples: Optional[int]           # the plan's first samples kept (at least 2); None: all
    time_scale: float                # re-timed by Theorem 1; at most 1, so within the motor limits
    lane_radius_m: Optional[float]   # one of OTHER_LANES_M; None: the plan's own
    alpha_offset_rad: float
    gain_factor: float               # every gain times this: 1, 0 (feed-forward only), HUGE_WITHIN_THE_BOUND
    spike: Optional[tuple[str, float, float]]   # (Trajectory array, at, value): one value set, within the bound
    split_at: Optional[float]        # the one segment split in two at this fraction of the samples
    label: Optional[str]             # the segments' primitive id and type and the library digest
    tolerances: tuple[float, float, float, float]   # TOLERANCE_NAMES: rad, m, rad, m
    variant: int                     # a defect's way of being made: PLAN_DEFECTS[defect][variant % count]
    at: float                        # where in an array a defect is made, a fraction of its length
    text: str                        # a defect's unicode
    while_tracking: bool             # sent while the module's plan is tracked
    periods: int                     # a valid goal: periods stepped before it is canceled, if still running


#: the plan as it is, tolerances unchecked, each defect made its first way at the end of its array: every run's
#: explicit example
AS_PLANNED = PlanEdit(samples=None, time_scale=1.0, lane_radius_m=None, alpha_offset_rad=0.0, gain_factor=1.0,
                      spike=None, split_at=None, label=None, tolerances=(0.0, 0.0, 0.0, 0.0), variant=0, at=1.0,
                      text="", while_tracking=True, periods=60)


def tolerance_values():
    """Valid tolerances: 0 (not checked), ordinary, the smallest and a huge one."""
    return st.one_of(st.just(0.0), st.floats(0.0, 10.0), st.sampled_from((5e-324, 1e300)))


def plan_edits():
    """PlanEdits of every kind (PlanEdit's fields)."""
    return st.builds(
        PlanEdit, samples=st.one_of(st.none(), st.integers(2, 60)),
        time_scale=st.one_of(st.just(1.0), st.floats(0.25, 1.0)),
        lane_radius_m=st.one_of(st.none(), st.sampled_from(OTHER_LANES_M)),
        alpha_offset_rad=st.one_of(st.just(0.0), st.floats(-100.0, 100.0)),
        gain_factor=st.sampled_from((1.0, 0.0, HUGE_WITHIN_THE_BOUND)),
        spike=st.one_of(st.none(), st.tuples(st.sampled_from(tuple(PLAN_ARRAYS)), st.floats(0.0, 1.0),
                                             st.sampled_from((HUGE_WITHIN_THE_BOUND, -HUGE_WITHIN_THE_BOUND) + tuple(
                                                 v for v in EDGE_FLOATS if abs(v) <= HUGE_WITHIN_THE_BOUND)))),
        split_at=st.one_of(st.none(), st.floats(0.0, 1.0)), label=st.one_of(st.none(), unicode_name()),
        tolerances=st.tuples(*[tolerance_values()] * 4), variant=st.integers(0, 1000), at=st.floats(0.0, 1.0),
        text=unicode_name(), while_tracking=st.booleans(), periods=st.integers(1, 60))


def index_at(at, size):
    """The index a fraction at of size items falls on."""
    return min(int(at * size), size - 1)


def remake(edit, plan, torque_limits):
    """The plan re-made by edit's valid steps (a Trajectory: each step checked as it is made)."""
    from swim_control.trajectory import Trajectory
    if edit.samples is not None and edit.samples < len(plan.time_s):
        k = edit.samples
        segment = dataclasses.replace(plan.segments[0], duration_s=float(plan.time_s[k - 1]), sample_count=k)
        plan = Trajectory(plan.time_s[:k], plan.q[:k], plan.qdot[:k], plan.foil_acceleration[:k], plan.torque[:k],
                          plan.lqr_gain[:k], plan.riccati_input_gain[:k], (segment,), plan.lane_radius_m,
                          plan.library_digest)
    plan = plan.time_scaled(edit.time_scale, torque_limits)
    arrays = {name: getattr(plan, name).copy() for name in PLAN_ARRAYS}
    arrays["q"][:, 0] += edit.alpha_offset_rad
    arrays["lqr_gain"] *= edit.gain_factor
    arrays["riccati_input_gain"] *= edit.gain_factor
    if edit.spike is not None:
        name, at, value = edit.spike
        arrays[name].reshape(-1)[index_at(at, arrays[name].size)] = value
    segments = [dataclasses.replace(s, alpha_offset_rad=s.alpha_offset_rad + edit.alpha_offset_rad)
                for s in plan.segments]
    if edit.split_at is not None:   # the junction sample belongs to the earlier segment, as the planner's
        whole, count, time_s = segments[0], len(plan.time_s), plan.time_s
        first = 1 + index_at(edit.split_at, count - 1)
        segments = [dataclasses.replace(whole, duration_s=float(time_s[first - 1]), sample_count=first),
                    dataclasses.replace(whole, start_time_s=float(time_s[first - 1]),
                                        duration_s=float(time_s[-1] - time_s[first - 1]), first_sample=first,
                                        sample_count=count - first)]
    digest = plan.library_digest
    if edit.label is not None:
        segments = [dataclasses.replace(s, primitive_id=edit.label, primitive_type=edit.label) for s in segments]
        digest = edit.label
    return dataclasses.replace(plan, **arrays, segments=tuple(segments),
                               lane_radius_m=edit.lane_radius_m or plan.lane_radius_m, library_digest=digest)


def break_plan(defect, edit, message, tolerances):  # noqa: C901 - one branch per defect the fuzzer draws
    """The defect (a key of PLAN_DEFECTS) made in the encoded plan (message, PlannedTrajectory) or the tolerances
    (a list), the way edit.variant picks; False if that way happens to leave the plan valid (unicode joint names
    that are the plan's own), else True."""
    from swim_control.trajectory import MAX_TRACKED_SAMPLES
    from swim_ros.codecs import float_array
    variants = PLAN_DEFECTS[defect]
    where, value = variants[edit.variant % len(variants)]
    time_s = np.array(message.time_from_start_s)
    samples = len(time_s)
    if defect == "interface version":
        message.interface_version = int(value)
    elif defect == "too many samples":
        message.time_from_start_s = float_array(np.arange(MAX_TRACKED_SAMPLES + 1, dtype=float))
    elif defect == "no samples":
        for field in ("time_from_start_s", *PLAN_ARRAYS.values()):
            setattr(message, field, [])
    elif defect == "one sample":
        for field in ("time_from_start_s", *PLAN_ARRAYS.values()):
            values = np.array(getattr(message, field))
            setattr(message, field, float_array(values[:values.size // samples]))
    elif defect == "joint names":
        names = list(message.joint_names)
        if where == "unicode":
            names[index_at(edit.at, len(names))] = edit.text
            if names == list(message.joint_names):
                return False
        elif where == "missing":
            del names[index_at(edit.at, len(names))]
        elif where == "reordered":
            names = names[1:] + names[:1]
        elif where == "R added":
            names.insert(1, "R")
        else:
            message.constrained = False
        message.joint_names = names
    elif defect == "array length":
        values = list(getattr(message, where))
        values = [] if value == 0.0 else values[:int(value)] if value < 0.0 else values + [0.0] * int(value)
        setattr(message, where, float_array(values))
    elif defect in ("non-finite value", "value past the bound"):
        values = np.array(getattr(message, where))
        values[index_at(edit.at, values.size)] = value
        setattr(message, where, float_array(values))
    elif defect == "times out of order":
        i = index_at(edit.at, samples - 1)
        time_s[i + 1] = time_s[i]
        if where == "swapped":
            time_s[i] = message.time_from_start_s[i + 1]
        message.time_from_start_s = float_array(time_s)
    elif defect == "times not from 0":
        message.time_from_start_s = float_array(time_s + value)
    elif defect in ("time span past the bound", "time steps too short"):
        message.time_from_start_s = float_array(time_s * value)
    elif defect == "lane radius":
        message.lane_radius_m = value
    elif defect == "segments":
        segments = message.segments
        if where == "none":
            message.segments = []
        elif where in ("short", "long"):
            segments[-1].sample_count += -1 if where == "short" else 1
        elif where == "first sample":
            segments[0].first_sample = 1
        else:
            setattr(segments[index_at(edit.at, len(segments))], SEGMENT_FIELDS[where], value)
    elif defect == "tolerance":
        tolerances[int(where)] = value
    return True


@pytest.fixture(scope="module")
def base_plan(plan_message):
    """The module's plan as a Trajectory, to re-make."""
    from swim_ros.trajectory_messages import trajectory_from_message
    return trajectory_from_message(plan_message)


@pytest.fixture()
def tracking(rig_loop):
    """The tracking_state messages the node publishes from now on."""
    from swim_interfaces.msg import TrackingState
    plant, _ = rig_loop
    received = []
    plant.node.create_subscription(TrackingState, "tracking_state", received.append, 10)
    return received


def tracking_values(message):
    """Every float of a TrackingState."""
    points = (message.reference, message.feedback, message.error)
    return [v for p in points for v in (*p.positions, *p.velocities)] + \
        [*message.output_torques, *message.feedforward_torques, message.plan_time_s, message.time_scale]


def check_result(result, tolerances):
    """A tracked goal's result, consistent with its tolerances (0: not checked): finite errors; succeeded only
    within the goal tolerance; a violation only past the tolerance violated."""
    from swim_interfaces.action import ExecutePlan
    codes = ExecutePlan.Result
    path_alpha_rad, _, goal_alpha_rad, _ = tolerances
    alpha_error_rad = abs(result.final_alpha_error_rad)
    assert all(math.isfinite(v) for v in (result.final_alpha_error_rad, result.final_r_error_m, result.duration_s))
    assert result.error_string
    if result.error_code == codes.SUCCESSFUL:
        assert goal_alpha_rad == 0.0 or alpha_error_rad <= goal_alpha_rad
    elif result.error_code == codes.GOAL_TOLERANCE_VIOLATED:
        assert 0.0 < goal_alpha_rad < alpha_error_rad
    elif result.error_code == codes.PATH_TOLERANCE_VIOLATED:
        assert 0.0 < path_alpha_rad < alpha_error_rad
    else:
        assert result.error_code == codes.CANCELED


def start_goal(plant, client, plan_message, message, tolerances, while_tracking):
    """The module's plan sent and tracked a few periods first if while_tracking (its handle and result future,
    else None); then message sent with the tolerances: its handle, result future, feedback list and send time."""
    background = None
    if while_tracking:
        background = send(plant, client, plan_message)
        plant.step_periods(BACKGROUND_PERIODS)
    feedback = []
    sent = time.monotonic()
    handle, future = send(plant, client, message, feedback.append, **dict(zip(TOLERANCE_NAMES, tolerances)))
    return background, handle, future, feedback, sent


def check_published(tracker, plant, tracking, feedback, torque_limits):
    """Every command the plant took finite and within the motor limits, every tracking_state and feedback finite
    (progress within [0, 1]), the node alive."""
    check_commands(plant.torques, torque_limits)
    for state in tracking:
        assert all(math.isfinite(v) for v in tracking_values(state)), state
    for update in feedback:
        assert 0.0 <= update.feedback.progress <= 1.0
        assert all(math.isfinite(v) for v in tracking_values(update.feedback.state))
    assert tracker.poll() is None


def fresh_plan(plant, tracking, edit, base_plan, torque_limits):
    """The plant at rest at the origin, nothing recorded; the plan edit re-makes, encoded."""
    from builtin_interfaces.msg import Time

    from swim_ros.trajectory_messages import trajectory_to_message
    plant.q, plant.qdot = np.zeros(3), np.zeros(3)
    plant.torques.clear()
    tracking.clear()
    return trajectory_to_message(remake(edit, base_plan, torque_limits), Time())


@fuzz_settings(20)
@given(edit=plan_edits())
@example(edit=AS_PLANNED)
def test_fuzzed_valid_plans_preempt_and_are_tracked_within_the_limits(tracker, rig_loop, tracking, plan_message,
                                                                       base_plan, torque_limits, edit):
    from swim_interfaces.action import ExecutePlan
    plant, client = rig_loop
    message = fresh_plan(plant, tracking, edit, base_plan, torque_limits)
    background, handle, future, feedback, _ = start_goal(plant, client, plan_message, message, edit.tolerances,
                                                         edit.while_tracking)
    for _ in range(edit.periods):
        if future.done():
            break
        plant.step()
    if background is not None and edit.lane_radius_m is None:   # its vehicle model there: preempted on arrival
        assert run_until(plant, background[1], 0).error_code == ExecutePlan.Result.PREEMPTED
    if not future.done():
        handle.cancel_goal_async()
    result = run_until(plant, future, RESULT_PERIODS)
    if background is not None and edit.lane_radius_m is not None:
        # a goal on another lane preempts the plan under way once its vehicle model is built; canceled before
        # that, it never started and the plan under way runs on to its end
        assert run_until(plant, background[1], BACKGROUND_END_PERIODS).error_code in (
            ExecutePlan.Result.PREEMPTED, ExecutePlan.Result.SUCCESSFUL)
    event(f"result {result.error_code}")
    check_result(result, edit.tolerances)
    check_published(tracker, plant, tracking, feedback, torque_limits)


def test_no_interface_version_defect_is_a_readable_version():
    """A version bump must move the defects too: a plan of a version the tracker reads is no defect."""
    from swim_ros.trajectory_messages import READABLE_INTERFACE_VERSIONS
    assert all(value not in READABLE_INTERFACE_VERSIONS for _, value in PLAN_DEFECTS["interface version"])


@pytest.mark.parametrize("defect", PLAN_DEFECTS)
@fuzz_settings(3)
@given(edit=plan_edits())
@example(edit=AS_PLANNED)
def test_fuzzed_broken_plans_are_refused_with_a_reason_and_change_nothing(tracker, rig_loop, tracking, plan_message,
                                                                          base_plan, torque_limits, defect, edit):
    from swim_interfaces.action import ExecutePlan

    from swim_ros.calls import spin_until
    plant, client = rig_loop
    message = fresh_plan(plant, tracking, edit, base_plan, torque_limits)
    tolerances = list(edit.tolerances)
    assume(break_plan(defect, edit, message, tolerances))
    background, _, future, feedback, sent = start_goal(plant, client, plan_message, message, tolerances,
                                                       edit.while_tracking)
    assert spin_until(plant.executor, future.done, GOAL_DEADLINE_S), edit
    assert time.monotonic() - sent < GOAL_DEADLINE_S
    result = future.result().result
    assert result.error_code == ExecutePlan.Result.INVALID_PLAN and result.error_string, (edit, result)
    if background is not None:   # the plan being tracked goes on: canceled now, not preempted before
        plant.step_periods(BACKGROUND_PERIODS)
        background[0].cancel_goal_async()
        assert run_until(plant, background[1], RESULT_PERIODS).error_code == ExecutePlan.Result.CANCELED
    check_published(tracker, plant, tracking, feedback, torque_limits)


def test_parameter_sets_are_answered_refused_with_a_reason_or_applied(tracker, rig_loop):
    from swim_controller.tracker_node import PARAMETERS
    from swim_ros.calls import ParameterCalls
    plant, _ = rig_loop
    parameters = ParameterCalls(plant.node, plant.executor, "tracker_node", POLICY)
    fuzz_parameter_sets(parameters, PARAMETERS, 40, DEADLINE_S, lambda: tracker.poll() is None,
                        {"stale_after_periods": STALE_AFTER_PERIODS})


def test_after_the_fuzz_the_plan_is_tracked_to_its_end(tracker, rig_loop, plan_message, torque_limits):
    from swim_interfaces.action import ExecutePlan
    plant, client = rig_loop
    _, future = send(plant, client, plan_message)
    duration_s = plan_message.time_from_start_s[-1]
    result = run_until(plant, future, int(duration_s / PERIOD_S) + RESULT_PERIODS)
    assert result.error_code == ExecutePlan.Result.SUCCESSFUL, result.error_string
    check_commands(plant.torques, torque_limits)
    assert tracker.poll() is None
