"""tracker_node over DDS with a plan made with the circulatory flow model: the node builds that vehicle model off its
control thread while it keeps answering states, then tracks the plan on the lag states it estimates, and reports
them in tracking_state. The plant is swim_model's circulatory constrained vehicle in lock-step (its lag states
integrated with it); the plan is that vehicle's own motion under known torques
(swim_controller.testing.circulatory), with zero gains: the feed-forward and the lag estimate alone.
"""
import time

import numpy as np
import pytest
from test_tracker_node import PERIOD_S, STALE_AFTER_PERIODS, LockStepPlant, run_until, send

from swim_ros.calls import spin_until
from swim_ros.testing.fixtures import MESSAGE_TIMEOUT_S, STARTUP_TIMEOUT_S, running_node

PLAN_S = 2.0
#: the lag estimate against the plant's true lag states, m/s: from the plan's own start (the plant's), integrating
#: the measured motion every 8 ms, its error is about 1e-4 m/s (test_tracker_circulatory); 2e-3 leaves margin
LAG_TOLERANCE_M_S = 2e-3
#: the node builds the circulatory vehicle model for the goal: 0.5 s from the disk cache, about 7 s compiling on a
#: cold one on a quiet 2-core host; every state must be answered meanwhile. 60 s for a loaded host
MODEL_BUILD_TIMEOUT_S = 60.0
#: a state's command while the model is built, s: milliseconds (the build is on its own thread); loading a model's
#: compiled library holds the interpreter for a while, and a fresh-clone CI run saw 0.34 s in a 0.62 s build
SLOWEST_ANSWER_S = 0.5
#: states answered while the model is built: a build on the control thread would answer none before it ends (the
#: state that asked waits for the whole build); from the cache 15-95 are answered
MIN_ANSWERS_DURING_BUILD = 3


@pytest.fixture(scope="module")
def circulatory_tracker(ros_domain, tmp_path_factory):
    log = tmp_path_factory.mktemp("tracker_node_circulatory") / "log.txt"
    with running_node("swim_controller", "tracker_node", log, "-p", f"stale_after_periods:={STALE_AFTER_PERIODS}"):
        yield log


@pytest.fixture(scope="module")
def circulatory_run():
    from swim_controller.testing.circulatory import gait_run
    from swim_model import VehicleModel, load_rig
    return gait_run(VehicleModel(load_rig(), constrained=True, flow="circulatory"), PLAN_S,
                    step_s=PERIOD_S / 8, substeps=8)


def stamp_ns(stamp) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


class CirculatoryPlant(LockStepPlant):
    """The lock-step plant on the circulatory vehicle: q, qdot and the flow's lag states, RK4 at PERIOD_S / 8."""

    def __init__(self, node, executor, run):
        super().__init__(node, executor)
        self.model = run.model
        self.q, self.qdot, self.lag = run.q[0].copy(), run.qdot[0].copy(), run.lag[0].copy()
        self.true_lag = {}   # stamp (ns) of each state published: the plant's lag states then, m/s

    def step(self, timeout_s=MESSAGE_TIMEOUT_S):
        message = self.state_message()
        self.true_lag[stamp_ns(message.header.stamp)] = self.lag.copy()
        self.publisher.publish(message)
        stamp = message.header.stamp
        if not spin_until(self.executor, lambda: any(c.header.stamp == stamp for c in self.commands), timeout_s):
            raise AssertionError(f"no command for the state within the timeout after {len(self.torques)} steps")
        torque = np.asarray([c for c in self.commands if c.header.stamp == stamp][-1].effort)
        self.commands.clear()
        qs, qdots, lags = self.model.integrate_rk4(self.q, self.qdot, np.tile(torque, (8, 1)), PERIOD_S / 8,
                                                   lag=self.lag)
        self.q, self.qdot, self.lag = qs[-1], qdots[-1], lags[-1]
        self.time_s += PERIOD_S
        self.torques.append(torque)
        return torque


def _plant_and_client(name, rclpy_context, circulatory_run):
    """(node, its executor, the lock-step CirculatoryPlant on it, the TrackingState messages received, an
    execute_plan action client) for one test."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from swim_interfaces.action import ExecutePlan
    from swim_interfaces.msg import TrackingState

    from swim_ros.calls import ActionClient, GoalStatusWatch
    from swim_ros.qos import per_period_subscription

    node = rclpy.create_node(name, context=rclpy_context)
    executor = SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(node)
    plant = CirculatoryPlant(node, executor, circulatory_run)
    tracking = []
    per_period_subscription(node, TrackingState, "tracking_state", tracking.append)
    client = ActionClient(node, ExecutePlan, "execute_plan")
    plant.goal_status = GoalStatusWatch(node, "execute_plan")
    return node, executor, plant, tracking, client


def test_a_circulatory_plan_is_tracked_on_its_estimated_lag_states(circulatory_tracker, circulatory_run,
                                                                   rclpy_context):
    from builtin_interfaces.msg import Time
    from swim_interfaces.action import ExecutePlan

    from swim_control.riccati import error_state_size
    from swim_controller.testing.circulatory import plan_from_run
    from swim_ros.trajectory_messages import trajectory_to_message

    samples = round(PLAN_S / circulatory_run.step_s / 4) + 1
    zero_gains = np.zeros((samples, 2, error_state_size(3, 1, 2)))
    plan = plan_from_run(circulatory_run, PLAN_S, sample_stride=4, gains=(zero_gains, zero_gains))
    node, executor, plant, tracking, client = _plant_and_client("tracker_circulatory_plant", rclpy_context,
                                                                 circulatory_run)
    try:
        assert client.wait_for_server(timeout_sec=STARTUP_TIMEOUT_S), "tracker_node did not come up"
        _, result_future = send(plant, client, trajectory_to_message(plan, Time()), goal_tolerance_alpha_rad=0.02,
                                path_tolerance_alpha_rad=0.2)
        start = plant.q.copy(), plant.qdot.copy(), plant.lag.copy()
        sent_s = time.monotonic()
        answers_s = []
        # answered with zero torque while the model is built; the plant is held at the plan's start meanwhile
        while True:
            asked_s = time.monotonic()
            if np.any(plant.step() != 0.0):
                break
            answers_s.append(time.monotonic() - asked_s)
            plant.q, plant.qdot, plant.lag = (a.copy() for a in start)
            assert time.monotonic() - sent_s < MODEL_BUILD_TIMEOUT_S, "the circulatory plan never started"
        print(f"model built in {time.monotonic() - sent_s:.2f} s: {len(answers_s)} states answered meanwhile, the "
              f"slowest in {max(answers_s, default=0.0) * 1e3:.0f} ms")
        assert len(answers_s) >= MIN_ANSWERS_DURING_BUILD, "states were not answered while the model was built"
        assert max(answers_s, default=0.0) < SLOWEST_ANSWER_S
        result = run_until(plant, result_future, int(PLAN_S / PERIOD_S) + 50)
    finally:
        executor.shutdown()
        node.destroy_node()
    assert result.error_code == ExecutePlan.Result.SUCCESSFUL, result.error_string
    tracked = [m for m in tracking if m.plan_time_s <= plan.duration_s]
    assert len(tracked) > 0.9 * PLAN_S / PERIOD_S
    planned = np.array([m.planned_lag_states for m in tracked])
    np.testing.assert_allclose(planned, [plan.sample(m.plan_time_s).lag for m in tracked], atol=1e-12)
    estimated = np.array([m.estimated_lag_states for m in tracked])
    truth = np.array([plant.true_lag[stamp_ns(m.header.stamp)] for m in tracked])
    assert np.abs(estimated - truth).max() < LAG_TOLERANCE_M_S
    assert np.abs(truth).max() > 0.02   # lag states of the size the stroke makes, not still water


def test_a_goal_canceled_while_its_model_is_built_never_starts(circulatory_tracker, circulatory_run, rclpy_context):
    """A circulatory plan on a lane the node has no model for: the model is being built (0.2 s from the disk cache
    at the least) when the cancel arrives, so the goal ends CANCELED without a period tracked."""
    import dataclasses

    from builtin_interfaces.msg import Time
    from swim_interfaces.action import ExecutePlan

    from swim_controller.testing.circulatory import plan_from_run
    from swim_ros.trajectory_messages import trajectory_to_message

    plan = dataclasses.replace(plan_from_run(circulatory_run, PLAN_S), lane_radius_m=0.48)   # the rig's second lane
    node, executor, plant, tracking, client = _plant_and_client("tracker_circulatory_canceler", rclpy_context,
                                                                 circulatory_run)
    try:
        assert client.wait_for_server(timeout_sec=STARTUP_TIMEOUT_S), "tracker_node did not come up"
        handle, result_future = send(plant, client, trajectory_to_message(plan, Time()))
        cancel = handle.cancel_goal_async()
        assert spin_until(executor, cancel.done, MESSAGE_TIMEOUT_S)
        assert len(cancel.result().goals_canceling) == 1
        assert spin_until(executor, result_future.done, MODEL_BUILD_TIMEOUT_S)
        plant.step_periods(5)   # states after it: answered, nothing tracked
    finally:
        executor.shutdown()
        node.destroy_node()
    result = result_future.result().result
    assert result.error_code == ExecutePlan.Result.CANCELED and "not started" in result.error_string
    assert tracking == [] and len(plant.torques) == 5
