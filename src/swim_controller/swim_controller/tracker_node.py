"""tracker_node: the cascade tracker (paper Sec. 6) on the rig's state, one plan at a time.

Topics, the execute_plan action, safety, parameters and the vehicle models built off the control thread: see
src/swim_controller/README.md, section "tracker_node". The control law: docs/model_and_method.md, section "5.
Tracking control". The real-time means: docs/realtime.md, section "The means". The per-period messages and
topics: docs/speed.md, section "The closed loop over DDS".
"""
from __future__ import annotations

import concurrent.futures
import dataclasses
import functools
import math
import queue
import threading
import time
from typing import Callable, Generator, Optional

import numpy as np
from builtin_interfaces.msg import Time
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.lifecycle import Node as LifecycleNode
from rclpy.lifecycle import State, TransitionCallbackReturn
from rclpy.task import Future
from rclpy.timer import Timer
from sensor_msgs.msg import JointState
from swim_interfaces.action import ExecutePlan
from swim_interfaces.msg import TrackingState
from trajectory_msgs.msg import JointTrajectoryPoint

from swim_control.errors import PlanError, StateMessageError
from swim_controller.sliding_mode import SlidingMode
from swim_controller.supervisor import Mode, Outcome, StaleStateWatch, Step, Supervisor, Tolerances
from swim_controller.tracker import CascadeTracker, FoilRangeGuard, model_io_linearization, model_lag_rate
from swim_model import RigParameters, SwimModelError, VehicleModel, load_rig
from swim_model.velocity_filter import DEFAULT_CUTOFF_HZ, VelocityEstimator
from swim_ros.codecs import ACTUATED_JOINTS, float_array
from swim_ros.entry import run_node
from swim_ros.lifecycle import configure_and_activate, guard_change_state_service
from swim_ros.parameters import NodeSettings, ParameterSpec, RealtimeParameterSettings, positive, realtime_parameters
from swim_ros.qos import per_period_publisher, per_period_subscription
from swim_ros.realtime import (
    NO_REALTIME_MEANS,
    PeriodicCollector,
    RealtimeSettings,
    make_process_ordinary,
    make_process_realtime,
    make_thread_background,
)
from swim_ros.trajectory_messages import state_from_message, trajectory_from_message
from swim_ros.transport import use_real_time_transport

RESULT_CODES = {
    Outcome.SUCCEEDED: ExecutePlan.Result.SUCCESSFUL,
    Outcome.PATH_TOLERANCE_VIOLATED: ExecutePlan.Result.PATH_TOLERANCE_VIOLATED,
    Outcome.GOAL_TOLERANCE_VIOLATED: ExecutePlan.Result.GOAL_TOLERANCE_VIOLATED,
    Outcome.STATE_LOST: ExecutePlan.Result.STATE_LOST,
    Outcome.PREEMPTED: ExecutePlan.Result.PREEMPTED,
    Outcome.CANCELED: ExecutePlan.Result.CANCELED,
}

_SLIDING_DEFAULTS = SlidingMode()
#: the tracker's parameters (swim_ros.parameters): fixed at start where the node builds from them (the rig, the
#: period its timer runs at, autostart), changeable at run time otherwise. The upper bounds are assumed, each far
#: past any sensible value: they only keep a typo (an extra zero, a wrong unit) from reaching the law.
PARAMETERS = (
    ParameterSpec("rig_path", "", "rig YAML file, its joint limits the range guard's stops (empty: the shipped rig)",
                  read_only=True),
    ParameterSpec("range_guard_enabled", True, "bound the law's foil acceleration so the heave and the pitch can "
                  "still brake short of their hard stops (swim_controller.tracker.FoilRangeGuard)"),
    ParameterSpec("sample_period_s", 0.008, "control period h, s (the paper's 8 ms); the stale-state timer runs at it",
                  range=(0.001, 0.1), read_only=True),
    ParameterSpec("stale_after_periods", 5, "sample periods without a valid state before the torque is zeroed",
                  range=(1, 1000)),
    ParameterSpec("sliding_mode_enabled", True, "add the sliding-mode term to the I/O-linearized law (eqs. 24-25)"),
    ParameterSpec("disturbance_bound_n_m", _SLIDING_DEFAULTS.disturbance_bound_n_m,
                  "sliding-mode disturbance bound D, N m (eq. 25)", range=(0.0, 100.0)),
    ParameterSpec("boundary_layer", _SLIDING_DEFAULTS.boundary_layer,
                  "sliding-mode boundary layer phi (eq. 25), in the units of s", range=(0.0, 1e3), check=positive),
    ParameterSpec("disturbance_bound_margin", _SLIDING_DEFAULTS.disturbance_bound_margin,
                  "factor on a plan's own disturbance bound D(t) (circulatory plans that carry one; the others use "
                  "disturbance_bound_n_m)", range=(1.0, 100.0)),
    ParameterSpec("time_scale", 1.0, "lambda: run plans this many times faster (Theorem 1) when a goal arrives",
                  range=(0.1, 10.0)),
    ParameterSpec("feedback_rate_hz", 10.0, "action feedback rate, Hz", range=(0.1, 1000.0)),
    ParameterSpec("velocity_cutoff_hz", DEFAULT_CUTOFF_HZ,
                  "cut-off of the velocity filter used when states carry no velocities, Hz", range=(0.0, 1e4),
                  check=positive),
    ParameterSpec("autostart", True, "configure and activate at start-up (false: wait for a lifecycle manager's "
                  "configure and activate on tracker_node/change_state)", read_only=True),
) + realtime_parameters(70, "node's threads (executor, middleware; the model builder's runs at the ordinary "
                        "policy)")
#: states between two garbage collections after a command (collect_garbage_between_periods): 1 s at 8 ms
GC_INTERVAL_STATES = 125


@dataclasses.dataclass(frozen=True)
class TrackerSettings(RealtimeParameterSettings):
    """PARAMETERS' values (swim_ros.parameters.NodeSettings): what the periods, the watchdog and the action read."""

    rig_path: str
    range_guard_enabled: bool
    sample_period_s: float
    stale_after_periods: int
    sliding_mode_enabled: bool
    disturbance_bound_n_m: float
    boundary_layer: float
    disturbance_bound_margin: float
    time_scale: float
    feedback_rate_hz: float
    velocity_cutoff_hz: float
    autostart: bool

    @property
    def sliding_mode(self) -> SlidingMode:
        """The sliding mode's settings: disturbance bound (N m), boundary layer and margin."""
        return SlidingMode(self.disturbance_bound_n_m, self.boundary_layer, self.disturbance_bound_margin)

    @property
    def stale_limit_s(self) -> float:
        """How long without a valid state before the torque is zeroed, s."""
        return self.stale_after_periods * self.sample_period_s


@dataclasses.dataclass(frozen=True)
class ModelKey:
    """Which vehicle model a plan runs on."""

    constrained: bool
    lane_radius_m: float   # the constrained vehicle's lane; the rig's default lane for the free vehicle
    flow_model: str        # "ideal" | "circulatory"


def build_model(rig, key: ModelKey) -> VehicleModel:
    """The vehicle model of key, with the compiled entry points the tracker calls loaded.

    Compiled to C the first time, cached on disk after.
    """
    model = VehicleModel(rig, constrained=key.constrained, lane_radius_m=key.lane_radius_m, flow=key.flow_model)
    model_io_linearization(model)
    model_lag_rate(model)
    return model


class ModelBuilder:
    """Builds vehicle models one at a time on a daemon thread of its own.

    A process that stops mid-compilation leaves no library behind: swim_model writes it under another name and renames
    it. on_built is called on that thread after each build, to wake the thread that waits for it.
    """

    def __init__(self, rig, on_built: Callable[[], None],
                 realtime: RealtimeSettings = NO_REALTIME_MEANS) -> None:
        self._rig = rig
        self.realtime = realtime   # the process's means: the builds run as its background thread
        self._on_built = on_built
        self._requests: queue.Queue[Optional[tuple[ModelKey, concurrent.futures.Future]]] = queue.Queue()
        self._thread = threading.Thread(target=self._run, name="tracker_model_builder", daemon=True)
        self._thread.start()

    def submit(self, key: ModelKey) -> concurrent.futures.Future:
        """A future of the model of key."""
        future: concurrent.futures.Future = concurrent.futures.Future()
        self._requests.put((key, future))
        return future

    def stop(self) -> None:
        """No more builds after the one under way (if any)."""
        self._requests.put(None)

    def _run(self) -> None:
        while (request := self._requests.get()) is not None:
            make_thread_background(self.realtime)   # below every period; its compiler an ordinary process
            key, future = request
            try:
                future.set_result(build_model(self._rig, key))
            except Exception as err:  # noqa: BLE001 - handed to the goal that waits for this model
                future.set_exception(err)
            self._on_built()


class _Awaited:
    """A concurrent.futures.Future awaited in an rclpy coroutine.

    Yields (the executor resumes the coroutine on its next wake-up) until the future is done, giving True, or until
    give_up() holds, giving False.
    """

    def __init__(self, future: concurrent.futures.Future, give_up: Callable[[], bool]) -> None:
        self.future = future
        self.give_up = give_up

    def __await__(self) -> Generator[None, None, bool]:
        while not self.future.done():
            if self.give_up():
                return False
            yield
        return True


class ActiveGoal:
    """A goal being executed: its handle, its own supervisor, and the future its execute coroutine awaits."""

    def __init__(self, handle, supervisor: Supervisor, duration_s: float) -> None:
        self.handle = handle
        self.supervisor = supervisor
        self.duration_s = duration_s
        self.done = Future()
        self.outcome: Optional[Outcome] = None
        self.reason = ""
        self.last_feedback_monotonic = -math.inf

    def finish(self, outcome: Outcome, reason: str) -> None:
        """End the goal with outcome and reason (the first call wins)."""
        if not self.done.done():
            self.outcome, self.reason = outcome, reason
            self.done.set_result(outcome)


class TrackerNode(LifecycleNode):
    """The tracker as a lifecycle node (lifecycle_msgs ChangeState on tracker_node/change_state).

    Configure loads the rig and the range guard's stops and builds the start-up models; activate serves joint_states and
    execute_plan (goals are refused while inactive); deactivate zeroes the torque and ends the goal under way
    (PREEMPTED); cleanup drops the models. owns_process: the node is its process's (main() makes it so) and applies the
    real-time means to it while active.
    """

    def __init__(self, owns_process: bool = False) -> None:
        super().__init__("tracker_node")
        self.owns_process = owns_process
        guard_change_state_service(self)
        self.parameters = NodeSettings(self, PARAMETERS, TrackerSettings, on_change=self._apply_parameters)
        self.settings = self.parameters.current
        self.active = False
        self.configure_error: Optional[str] = None   # why the last configure failed
        self.rig: Optional[RigParameters] = None     # the rig and what is built from it: set by configure
        self.range_guard: Optional[FoilRangeGuard] = None
        self._builder: Optional[ModelBuilder] = None
        self._stale_timer: Optional[Timer] = None
        self._models: dict[ModelKey, VehicleModel] = {}
        self._building: dict[ModelKey, concurrent.futures.Future] = {}
        self._goals_received = 0
        self._waiting_for_model: list = []   # goal handles whose execute callback awaits its vehicle model
        self._supervisor: Optional[Supervisor] = None
        self._goal: Optional[ActiveGoal] = None
        self._last_q: Optional[np.ndarray] = None
        self._last_state_stamp = Time()      # zero: "not stamped", before any valid state
        self._stale_watch = StaleStateWatch(time.monotonic(), self.settings.sample_period_s)
        self._last_tracking: Optional[TrackingState] = None
        self._velocity = VelocityEstimator(self.settings.velocity_cutoff_hz)
        self.rejected_states = 0
        self.commands_sent = 0
        self._collector: Optional[PeriodicCollector] = None   # set by _make_realtime

        self.command_publisher = per_period_publisher(self, JointState, "joint_commands")
        self.tracking_publisher = per_period_publisher(self, TrackingState, "tracking_state")
        self._command_message = JointState(name=list(ACTUATED_JOINTS))   # reused every period
        self._tracking_message_reused = TrackingState(reference=JointTrajectoryPoint(),
                                                      feedback=JointTrajectoryPoint(), error=JointTrajectoryPoint())
        # One thread runs every callback (rclpy.spin): the control period, the stale watchdog and the action
        # never race, so no locks. The execute callback is a coroutine that awaits its goal's end instead of
        # blocking a thread; rclpy's MultiThreadedExecutor with a mutually exclusive group stalled here
        # (the subscription stopped being served after a few periods, ros2/rclcpp#832 family).
        per_period_subscription(self, JointState, "joint_states", self._on_state)
        self._action = ActionServer(self, ExecutePlan, "execute_plan", execute_callback=self._execute,
                                    goal_callback=self._on_goal, cancel_callback=self._on_cancel)
        # a build's end wakes the executor (guard conditions may be triggered from any thread)
        self._model_built = self.create_guard_condition(lambda: None)

    # ----- lifecycle -------------------------------------------------------------------------------
    def on_configure(self, state: State) -> TransitionCallbackReturn:
        """Load the rig and build the ideal flow's models of its two vehicles on its default lane.

        The range guard's stops are the rig's limits record's. The models are ready for a first goal (about half a
        second, or a few seconds to compile them).
        """
        self.settings = self.parameters.current
        try:
            rig = load_rig(self.settings.rig_path or None)
            models = {}
            for constrained in (True, False):
                key = ModelKey(constrained, rig.constrained_lane_radius_m, "ideal")
                models[key] = build_model(rig, key)
        except (ValueError, SwimModelError) as err:
            self.configure_error = str(err)
            self.get_logger().error(f"configure failed: {err}")
            return TransitionCallbackReturn.FAILURE
        self.configure_error = None
        self.rig, self.range_guard, self._models = rig, FoilRangeGuard(rig.hard_limits_rad), models
        self._builder = ModelBuilder(rig, self._wake_after_build, self._realtime())
        self._stale_timer = self.create_timer(self.settings.sample_period_s, self._check_stale)
        return super().on_configure(state)

    def on_activate(self, state: State) -> TransitionCallbackReturn:
        """Serve joint_states and goals, the process at its real-time means."""
        self._stale_watch.state_arrived(time.monotonic())   # the first state is due within the limit from now
        self.active = True
        self._make_realtime()
        self.get_logger().info("tracker ready: waiting for joint_states and execute_plan goals")
        return super().on_activate(state)

    def on_deactivate(self, state: State) -> TransitionCallbackReturn:
        """Stop serving (zero torque, the goal under way preempted)."""
        self._stop_serving()
        return super().on_deactivate(state)

    def on_cleanup(self, state: State) -> TransitionCallbackReturn:
        """Drop the models."""
        self._release()
        return super().on_cleanup(state)

    def on_shutdown(self, state: State) -> TransitionCallbackReturn:
        """Stop serving and drop the models."""
        self._stop_serving()
        self._release()
        return super().on_shutdown(state)

    def _stop_serving(self) -> None:
        """Zero torque, the goal under way ended (PREEMPTED), no more states served.

        The process at the ordinary policy again.
        """
        if self.active:
            self.active = False
            if self._supervisor is not None:
                self._supervisor.state_lost()
            if self._goal is not None:
                self._goal.finish(Outcome.PREEMPTED, "preempted: tracker_node deactivated")
            self._supervisor = None
            self._publish_command(np.zeros(2), self._last_state_stamp)
        if self.owns_process and self.settings.realtime.realtime:
            make_process_ordinary()
        if self._collector is not None:
            self._collector.stop()
            self._collector = None

    def _release(self) -> None:
        """Drop what configure built: the models, the model builder, the stale-state timer."""
        if self._builder is not None:
            self._builder.stop()
            self._builder = None
        if self._stale_timer is not None:
            self.destroy_timer(self._stale_timer)
            self._stale_timer = None
        self._models, self._building, self.rig, self.range_guard = {}, {}, None, None

    # ----- parameters ------------------------------------------------------------------------------
    def _apply_parameters(self, previous: TrackerSettings, current: TrackerSettings) -> None:
        """Post-set: accepted values take effect (the active goal's law included)."""
        self.settings = current
        if self._supervisor is not None:
            tracker = self._supervisor.tracker
            tracker.sliding_mode_enabled = current.sliding_mode_enabled
            tracker.sliding_mode = current.sliding_mode
            tracker.range_guard = self.range_guard if current.range_guard_enabled else None
        if current.velocity_cutoff_hz != previous.velocity_cutoff_hz:
            self._velocity = VelocityEstimator(current.velocity_cutoff_hz)

    def _model_key(self, constrained: bool, lane_radius_m: float, flow_model: str) -> ModelKey:
        """The models to build at start-up: per flow and lane for the constrained vehicle, per flow for the free one.

        The free vehicle's lane is a coordinate, so its model is the same for every starting lane.
        """
        assert self.rig is not None   # goals are accepted while active only
        return ModelKey(constrained, lane_radius_m if constrained else self.rig.constrained_lane_radius_m, flow_model)

    async def _model(self, key: ModelKey, give_up: Callable[[], bool]) -> Optional[VehicleModel]:
        """The vehicle a plan runs on, built once, off this thread (ModelBuilder).

        Awaiting it lets the executor serve everything else meanwhile. None if give_up() holds first (the build goes on
        for the next goal).
        """
        model = self._models.get(key)
        if model is not None:
            return model
        future = self._building.get(key)
        if future is None:
            self.get_logger().info(f"building the {key.flow_model} flow's "
                                   f"{'constrained' if key.constrained else 'free'} vehicle model "
                                   f"(lane {key.lane_radius_m} m) for this plan")
            assert self._builder is not None   # goals are accepted while active only
            future = self._building[key] = self._builder.submit(key)
        if not await _Awaited(future, give_up):
            return None
        if self._building.get(key) is future:
            del self._building[key]
        try:
            model = future.result()
        except Exception as err:  # noqa: BLE001 - the goal is refused with the reason, the node keeps running
            raise PlanError(f"the {key.flow_model} flow's vehicle model could not be built: {err!r}") from err
        self._models[key] = model
        return model

    def _wake_after_build(self) -> None:
        try:
            self._model_built.trigger()
        except Exception:  # noqa: BLE001 - the node is being destroyed: nothing waits any more
            pass

    def _realtime(self) -> RealtimeSettings:
        """The means this node applies: its parameters' if it owns its process, none otherwise."""
        return self.settings.realtime if self.owns_process else NO_REALTIME_MEANS

    def _make_realtime(self) -> None:
        """The real-time means of the parameters for this process (on activation, once the start-up's models are built).

        Its threads at realtime_priority, memory locked, the collector between periods. Said once at info level, or as
        one warning with what was refused and why.
        """
        if not self.owns_process:
            return
        settings = self._realtime()
        outcome = make_process_realtime(settings)
        if self._builder is not None:
            self._builder.realtime = settings
        (self.get_logger().warning if outcome.refused else self.get_logger().info)(outcome.summary())
        if settings.collect_garbage_between_periods:
            self._collector = PeriodicCollector(GC_INTERVAL_STATES)

    def destroy_node(self) -> None:
        """Drop the models, then destroy the node."""
        self._release()
        super().destroy_node()

    def _make_tracker(self, model: VehicleModel) -> CascadeTracker:
        settings = self.settings
        return CascadeTracker(model_io_linearization(model), model.torque_limits(), settings.sliding_mode,
                              settings.sliding_mode_enabled, settings.sample_period_s, model_lag_rate(model),
                              self.range_guard if settings.range_guard_enabled else None)

    # ----- the control period ----------------------------------------------------------------------
    def _on_state(self, message: JointState) -> None:
        if not self.active:
            return
        supervisor = self._supervisor
        names = None
        if supervisor is not None:
            assert supervisor.tracker.trajectory is not None   # a supervisor is kept only after begin()
            names = supervisor.tracker.trajectory.joint_names
        try:
            time_s, q, qdot = state_from_message(message, names, self._velocity,
                                                 self.get_clock().now().nanoseconds * 1e-9)
        except StateMessageError as err:
            self.rejected_states += 1
            self.get_logger().warning(f"state rejected ({self.rejected_states} so far): {err}",
                                      throttle_duration_sec=1.0)
            return
        self._stale_watch.state_arrived(time.monotonic())
        self._last_q = q
        self._last_state_stamp = message.header.stamp
        if supervisor is None:
            self._publish_command(np.zeros(2), message.header.stamp)
            return
        try:
            step = supervisor.on_state(time_s, q, qdot)
        except Exception as err:  # noqa: BLE001 - a failing law must stop the motors, not the node
            self.get_logger().error(f"control step failed, torque zeroed: {err!r}", throttle_duration_sec=1.0)
            supervisor.state_lost()
            self._publish_command(np.zeros(2), message.header.stamp)
            return
        self._publish_command(step.torque, message.header.stamp)
        self._report_step(step, message.header.stamp, q, qdot)
        if self._collector is not None:
            self._collector.after_period()   # the command is out: the rest of the period is free

    def _report_step(self, step: Step, stamp: Time, q: np.ndarray, qdot: np.ndarray) -> None:
        """After the period's command: its tracking state published, and the goal under way ended or told."""
        if step.output is not None:
            try:
                self._last_tracking = self._tracking_message(step, stamp, q, qdot)
                self.tracking_publisher.publish(self._last_tracking)
            except Exception as err:  # noqa: BLE001
                self.get_logger().error(f"tracking_state not published: {err!r}", throttle_duration_sec=1.0)
        goal = self._goal
        if goal is not None:
            if step.outcome is not None:
                goal.finish(step.outcome, step.outcome.value)
            else:
                self._publish_feedback(goal)

    def _publish_feedback(self, goal: ActiveGoal) -> None:
        """At most feedback_rate_hz: the latest tracking state and the fraction of the plan done."""
        now = time.monotonic()
        if self._last_tracking is None or now - goal.last_feedback_monotonic < 1.0 / self.settings.feedback_rate_hz:
            return
        goal.last_feedback_monotonic = now
        progress = min(goal.supervisor.elapsed_s / goal.duration_s, 1.0)
        goal.handle.publish_feedback(ExecutePlan.Feedback(phase=ExecutePlan.Feedback.PHASE_TRACKING,
                                                          state=self._last_tracking, progress=progress))

    def _check_stale(self) -> None:
        limit = self.settings.stale_limit_s
        now = time.monotonic()
        watch = self._stale_watch
        if not self.active or not watch.stale(now, limit):
            return
        if self._supervisor is not None and self._supervisor.mode is not Mode.STOPPED:
            self._supervisor.state_lost()
            self.get_logger().error(f"no valid joint_states for {limit * 1e3:.0f} ms: torque zeroed (the newest "
                                    f"arrived {(now - watch.last_state_s) * 1e3:.0f} ms ago, this check "
                                    f"{watch.check_gap_s * 1e3:.1f} ms after the one before; states rejected "
                                    f"so far: {self.rejected_states})")
            if self._goal is not None:
                self._goal.finish(Outcome.STATE_LOST, f"no valid joint_states for {limit * 1e3:.0f} ms")
        self._velocity.reset()
        self._publish_command(np.zeros(2), self._last_state_stamp)

    def _publish_command(self, torque: np.ndarray, stamp) -> None:
        command = self._command_message
        command.header.stamp = stamp
        command.effort = float_array(torque)
        self.command_publisher.publish(command)
        self.commands_sent += 1

    def _tracking_message(self, step: Step, stamp, q: np.ndarray, qdot: np.ndarray) -> TrackingState:
        output = step.output
        supervisor = self._supervisor
        assert output is not None and supervisor is not None   # a tracked period's step
        reference = output.reference
        message = self._tracking_message_reused
        message.header.stamp = stamp
        plan = supervisor.tracker.trajectory
        assert plan is not None
        message.joint_names = list(plan.joint_names)
        for point, positions, velocities in ((message.reference, reference.q, reference.qdot),
                                             (message.feedback, q, qdot),
                                             (message.error, reference.q - q, reference.qdot - qdot)):
            point.positions, point.velocities = float_array(positions), float_array(velocities)
        message.output_torques = float_array(output.torque)
        message.feedforward_torques = float_array(reference.torque)
        message.torque_saturated = list(output.saturated)
        message.plan_time_s = float(reference.time_s)
        message.time_scale = float(plan.time_scale_at(reference.time_s))
        message.segment_index = plan.segment_index(reference.time_s)
        message.sliding_mode_enabled = bool(supervisor.tracker.sliding_mode_enabled)
        message.estimated_lag_states = float_array(output.lag_estimate)
        message.planned_lag_states = float_array(reference.lag)
        return message

    # ----- the action ------------------------------------------------------------------------------
    def _on_goal(self, request: ExecutePlan.Goal) -> GoalResponse:
        """Goals are served while active only."""
        return GoalResponse.ACCEPT if self.active else GoalResponse.REJECT

    def _on_cancel(self, handle) -> CancelResponse:
        """Cancel the active goal.

        Hold the foil where it is now; or a goal still waiting for its vehicle model: it never starts.
        """
        if any(waiting is handle for waiting in self._waiting_for_model):
            return CancelResponse.ACCEPT
        goal = self._goal
        if goal is None or goal.handle is not handle:
            return CancelResponse.REJECT
        goal.supervisor.cancel(self._last_q)
        goal.finish(Outcome.CANCELED, "canceled: holding the foil where it is")
        return CancelResponse.ACCEPT

    async def _execute(self, handle) -> ExecutePlan.Result:
        """Validate the plan, make it the active one (preempting any other), await its end.

        A goal that waited for its vehicle model while a newer goal arrived is preempted by that one, never the other
        way round.
        """
        request = handle.request
        self._goals_received += 1
        arrival = self._goals_received
        try:
            tolerances = Tolerances(request.path_tolerance_alpha_rad, request.path_tolerance_r_m,
                                    request.goal_tolerance_alpha_rad, request.goal_tolerance_r_m)
            tolerances.validate()
            trajectory = trajectory_from_message(request.plan)
            assert self.rig is not None   # goals are accepted while active only
            tank_radius_m = 0.5 * self.rig.tank_diameter_m
            if trajectory.lane_radius_m >= tank_radius_m:   # the rig file's rule for its own lanes
                raise PlanError(f"plan lane radius {trajectory.lane_radius_m!r} m is not inside the tank "
                                f"(radius {tank_radius_m} m)")
            key = self._model_key(trajectory.constrained, trajectory.lane_radius_m, trajectory.flow_model)
            if key not in self._models:
                handle.publish_feedback(ExecutePlan.Feedback(phase=ExecutePlan.Feedback.PHASE_WAITING_FOR_MODEL))
            self._waiting_for_model.append(handle)
            try:
                model = await self._model(key, lambda: (handle.is_cancel_requested or arrival != self._goals_received
                                                        or not self.active))
            finally:
                self._waiting_for_model.remove(handle)
            time_scale = self.settings.time_scale
            # refused past the motor limits, with the largest feasible time scale named
            if model is not None and time_scale != 1.0:
                trajectory = trajectory.time_scaled(time_scale, model.torque_limits())
        except (PlanError, ValueError, SwimModelError) as err:
            handle.abort()
            self.get_logger().warning(f"plan refused: {err}")
            return ExecutePlan.Result(error_code=ExecutePlan.Result.INVALID_PLAN, error_string=str(err))
        if handle.is_cancel_requested:
            handle.canceled()
            return ExecutePlan.Result(error_code=ExecutePlan.Result.CANCELED,
                                      error_string="canceled while its vehicle model was built: not started")
        if arrival != self._goals_received or not self.active:
            handle.abort()
            return ExecutePlan.Result(error_code=ExecutePlan.Result.PREEMPTED,
                                      error_string="preempted by a new goal while its vehicle model was built"
                                      if self.active else "preempted: tracker_node deactivated")
        assert model is not None   # give_up held only for a cancel, a newer goal or a deactivate, answered above
        if self._goal is not None:
            self._goal.finish(Outcome.PREEMPTED, "preempted by a new goal")
        goal = ActiveGoal(handle, Supervisor(self._make_tracker(model)), trajectory.duration_s)
        goal.supervisor.begin(trajectory, tolerances)
        self._goal, self._supervisor, self._last_tracking = goal, goal.supervisor, None
        # a new goal's first state is due within stale_after_periods from now, not from the last one seen
        self._stale_watch.state_arrived(time.monotonic())
        self.get_logger().info(f"executing a {trajectory.duration_s:.2f} s plan ({len(trajectory.segments)} segments)")
        await goal.done
        return self._finish(goal)

    def _finish(self, goal: ActiveGoal) -> ExecutePlan.Result:
        if self._goal is goal:
            self._goal = None
        errors = goal.supervisor.last_errors
        assert goal.outcome is not None   # set by finish() with done
        result = ExecutePlan.Result(error_code=RESULT_CODES[goal.outcome], error_string=goal.reason,
                                    final_alpha_error_rad=errors[0], final_r_error_m=errors[1],
                                    duration_s=min(goal.supervisor.elapsed_s, goal.duration_s))
        if goal.outcome is Outcome.SUCCEEDED:
            goal.handle.succeed()
        elif goal.outcome is Outcome.CANCELED and goal.handle.is_cancel_requested:
            goal.handle.canceled()
        else:
            goal.handle.abort()
        self.get_logger().info(f"plan ended: {goal.reason}")
        return result


def autostart(node: TrackerNode) -> None:
    """Configure, then activate the node, as its autostart parameter asks.

    A configure that fails is a usage error at start (ValueError with its reason: run_node
    stops the process with it).
    """
    if node.settings.autostart and not configure_and_activate(node) and node.configure_error is not None:
        raise ValueError(node.configure_error)


def main(args: list[str] | None = None) -> None:
    """Run the tracker node in its own process (ros2 run swim_controller tracker_node)."""
    # UDP only: a reader's shared-memory port opened mid-run would hold a command's publish (swim_ros.transport)
    run_node(functools.partial(TrackerNode, owns_process=True), args, name="tracker_node",
             fatal_errors=(ValueError, SwimModelError), start=autostart, transport=use_real_time_transport)


if __name__ == "__main__":
    main()
