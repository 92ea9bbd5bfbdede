"""The tracker with the circulatory flow model: its lag-state estimate against the model's own lag states, and the
law's feed-forward against the model's inverse dynamics with the flow.

The truth is swim_model's circulatory vehicle integrated by RK4 (integrate_rk4, 1 ms) under torques that make the
foil follow a sinusoidal gait (swim_controller.testing.circulatory); the plans are made from that run (q, qdot,
lag, torques known) with gains of an arbitrary shape, so these tests need neither the planner nor the LQ stage.
"""
import dataclasses

import numpy as np
import pytest

from swim_control.errors import PlanError
from swim_controller.testing.circulatory import gait_run, plan_from_run
from swim_controller.tracker import CascadeTracker, LagEstimator, model_io_linearization, model_lag_rate
from swim_model import VehicleModel

#: the truth's RK4 step and the control period it is sampled at (the paper's 8 ms), s
TRUTH_STEP_S, PERIOD_S = 0.001, 0.008
SUBSTEPS = round(PERIOD_S / TRUTH_STEP_S)
RUN_S = 12.0


@pytest.fixture(scope="module")
def circulatory_model(rig):
    return VehicleModel(rig, constrained=True, flow="circulatory")


@pytest.fixture(scope="module")
def run(circulatory_model):
    return gait_run(circulatory_model, RUN_S, step_s=TRUTH_STEP_S, substeps=SUBSTEPS)


def lag_slopes(model: VehicleModel, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
    """a_i = -d(zdot_i)/dz_i at each sample (n, 2), 1/s, from the model's lag rate (docs/flow_model.md: the rate is
    a_i (Q - z_i))."""
    zero, one = np.zeros(2), np.ones(2)
    return np.array([model.lag_rate(qk, vk, zero) - model.lag_rate(qk, vk, one) for qk, vk in zip(q, qdot)])


def estimate_along(model: VehicleModel, run, stride: int, start_lag: np.ndarray) -> np.ndarray:
    """LagEstimator fed the true q, qdot every stride truth steps from start_lag: z^ at those steps (m, 2)."""
    estimator = LagEstimator(model_lag_rate(model), model.n_lag)
    estimator.reset(start_lag)
    return np.array([estimator.update(stride * TRUTH_STEP_S, run.q[k], run.qdot[k]).copy()
                     for k in range(0, len(run.time_s), stride)])


def test_the_lag_estimate_converges_to_the_true_lag_at_the_flows_own_rates(run):
    """From a wrong start (+-0.2 m/s, as large as the lag states get here) the estimate reaches the true lag of the
    simulated vehicle. The tolerance is derived, not tuned: the estimate's error is the start's error carried by the
    flow's own decay (the update is affine in z^ with slope exp(-abar dt)) plus the error of integrating from the
    right start, which for this second-order method is 4/3 of the change from halving the period (Richardson)."""
    model = run.model
    truth = run.lag[::SUBSTEPS]
    wrong_start = run.lag[0] + np.array([0.2, -0.2])
    wrong = estimate_along(model, run, SUBSTEPS, wrong_start)
    right = estimate_along(model, run, SUBSTEPS, run.lag[0])
    right_half = estimate_along(model, run, SUBSTEPS // 2, run.lag[0])[::2]
    # the two estimates' difference decays at the flow's rates a_i: exp(-int a_i dt) along the true motion
    slopes = lag_slopes(model, run.q, run.qdot)
    decay = np.exp(-np.concatenate([np.zeros((1, 2)), np.cumsum(0.5 * (slopes[1:] + slopes[:-1]), axis=0)
                                    * TRUTH_STEP_S])[::SUBSTEPS])
    np.testing.assert_allclose(wrong - right, (wrong_start - run.lag[0]) * decay, rtol=1e-2, atol=1e-12)
    assert decay[-1, 0] < 0.05 and decay[-1, 1] < 1e-6   # the run is long enough for the slow state to settle
    # from the right start: second order (halving the period quarters the error), and small
    error, error_half = np.abs(right - truth).max(axis=0), np.abs(right_half - truth).max(axis=0)
    assert np.all((error / error_half > 3.0) & (error / error_half < 5.0)), (error, error_half)
    discretization = 4.0 / 3.0 * np.abs(right - right_half)
    assert np.all(error <= 1e-3 * np.abs(truth).max(axis=0))
    tolerance = 1.05 * np.abs(wrong_start - run.lag[0]) * decay + 2.0 * discretization.max(axis=0) + 1e-12
    assert np.all(np.abs(wrong - truth) <= tolerance)
    assert np.abs(wrong - truth)[-1].max() < 0.01   # 10 mm/s off at the end, from 200 mm/s


@pytest.fixture(scope="module")
def plan(run):
    """2 s of the run, sampled every 4 ms."""
    return plan_from_run(run, 2.0, sample_stride=SUBSTEPS // 2)


def circulatory_tracker(model: VehicleModel, period_s: float = PERIOD_S, sliding: bool = True) -> CascadeTracker:
    return CascadeTracker(model_io_linearization(model), model.torque_limits(), sliding_mode_enabled=sliding,
                          sample_period_s=period_s, lag_rate=model_lag_rate(model))


def test_on_the_plan_with_the_planned_lag_the_torque_is_the_feedforward(run, plan, rig):
    """Measured state on the plan and z^ = z_des: zero error state, so tau = the model's inverse dynamics with the
    flow at u_des of the period's midpoint; at the plan's end (u_des clamped there) the plan's own torque."""
    model = run.model
    tracker = circulatory_tracker(model)
    ideal = VehicleModel(rig, constrained=True)
    flow_torques = []
    for time_s in np.linspace(0.0, plan.duration_s, 41):
        point = plan.sample(time_s)
        tracker.start(plan, initial_lag=point.lag)
        out = tracker.step(time_s, point.q, point.qdot)
        assert not out.holding and np.all(out.error_state == 0.0)
        np.testing.assert_array_equal(out.lag_estimate, point.lag)
        u_mid = plan.sample(time_s + 0.5 * PERIOD_S).foil_acceleration
        expected = model.shape_dynamics(point.q, point.qdot, u_mid, point.lag)[1]
        np.testing.assert_allclose(out.torque, expected, rtol=1e-12, atol=1e-14)
        flow_torques.append(out.torque - ideal.shape_dynamics(point.q, point.qdot, u_mid)[1])
    assert np.abs(flow_torques).max() > 1e-3   # the flow's torque is in the law: mN m, not round-off
    np.testing.assert_allclose(out.torque, plan.torque[-1], rtol=1e-12, atol=1e-14)   # the last time: t = T


def test_at_every_sample_the_torque_tends_to_the_plans_feedforward(run, plan):
    """With the period taken to 1 ns the midpoint is the sample: the plan's feed-forward torque at every sample, to
    the change of u_des over half a nanosecond through Mio (plus round-off)."""
    model = run.model
    tracker = circulatory_tracker(model, period_s=1e-9)
    for k, time_s in enumerate(plan.time_s[:-1]):
        point = plan.sample(time_s)
        tracker.start(plan, initial_lag=point.lag)
        out = tracker.step(float(time_s), point.q, point.qdot)
        mio = model.io_linearization(point.q, point.qdot, point.lag)[0]
        slope = (plan.foil_acceleration[k + 1] - plan.foil_acceleration[k]) / (plan.time_s[k + 1] - time_s)
        bound = np.abs(mio) @ np.abs(slope) * 0.5e-9 + 1e-12 * np.abs(plan.torque[k]).max()
        assert np.all(np.abs(out.torque - plan.torque[k]) <= bound), k


def attached_weight(model: VehicleModel, point) -> float:
    """The circulatory flow's attached weight at a plan's sample (1: attached, 0: stalled)."""
    velocity = model.foil_velocity_map(point.q) @ point.qdot
    return float(model.circulatory_flow.evaluate(velocity, point.lag)["attached_weight"])


def test_the_estimate_enters_the_law_and_the_error_state(run, plan):
    """A lag estimate off the plan by dz: the error state's lag block is dz, and tau moves by the flow's response
    through Cio (the model's io_linearization at z^) and the gains' lag columns through Mio. At a period of attached
    flow from 0.5 s on: stalled, the flow's force does not depend on the lag states."""
    model = run.model
    tracker = circulatory_tracker(model, sliding=False)
    offset = np.array([0.03, -0.02])
    time_s = next(t for t in np.arange(0.5, RUN_S, PERIOD_S) if attached_weight(model, plan.sample(t)) > 0.99)
    point = plan.sample(time_s)
    tracker.start(plan, initial_lag=point.lag + offset)
    out = tracker.step(time_s, point.q, point.qdot)
    # (z + dz) - z is dz to round-off, not bit for bit
    np.testing.assert_allclose(out.error_state[-2:], offset, rtol=0.0, atol=4 * np.finfo(float).eps * np.abs(
        point.lag).max())
    assert np.all(out.error_state[:-2] == 0.0)
    mio, cio_qdot = model.io_linearization(point.q, point.qdot, point.lag + offset)
    u = plan.sample(time_s + 0.5 * PERIOD_S).foil_acceleration - point.lqr_gain[:, -2:] @ offset
    np.testing.assert_allclose(out.torque, mio @ u + cio_qdot, rtol=1e-12)
    planned = model.io_linearization(point.q, point.qdot, point.lag)[1]
    assert np.abs(cio_qdot - planned).max() > 1e-6   # the estimate, not the plan's lag, is in Cio (round-off: 1e-17)


def test_in_closed_loop_the_tracker_follows_the_true_lag(run, plan):
    """The tracker stepped on the simulated vehicle (its torques applied, RK4 at 1 ms) from a wrong lag estimate:
    the estimate it reports approaches the vehicle's true lag as the start's error decays at the flow's rates along
    the motion (exp(-int a_i dt), a_i from the model at each period), within 1 mm/s of integration error."""
    model = run.model
    tracker = circulatory_tracker(model)
    plan = dataclasses.replace(plan, lqr_gain=np.zeros_like(plan.lqr_gain),   # feed-forward alone: the plan's
                               riccati_input_gain=np.zeros_like(plan.riccati_input_gain))   # gains are arbitrary
    start_error = np.array([0.1, -0.1])
    tracker.start(plan, initial_lag=plan.lag[0] + start_error)
    q, qdot, lag = plan.q[0], plan.qdot[0], plan.lag[0]
    errors, states = [], []
    for k in range(round(plan.duration_s / PERIOD_S)):
        out = tracker.step(k * PERIOD_S, q, qdot)
        errors.append(out.lag_estimate - lag)
        states.append((q, qdot))
        qs, qdots, lags = model.integrate_rk4(q, qdot, np.tile(out.torque, (SUBSTEPS, 1)), TRUTH_STEP_S, lag=lag)
        q, qdot, lag = qs[-1], qdots[-1], lags[-1]
    slopes = lag_slopes(model, np.array([s[0] for s in states]), np.array([s[1] for s in states]))
    decay = np.exp(-np.sum(0.5 * (slopes[1:] + slopes[:-1]), axis=0) * PERIOD_S)
    np.testing.assert_array_equal(errors[0], start_error)
    assert np.all(np.abs(errors[-1]) <= 1.05 * np.abs(start_error) * decay + 1e-3), (errors[-1], decay)
    assert decay[1] < 0.05 and decay[0] < 0.9   # the fast state mostly settled, the slow one on its way
    assert np.abs(q - plan.q[-1]).max() < 0.1   # the feed-forward alone: near the plan after 2 s


def test_a_plan_of_the_other_flow_model_is_refused(run, plan, rig, make_trajectory):
    model = run.model
    ideal_model = VehicleModel(rig, constrained=True)
    ideal_tracker = CascadeTracker(model_io_linearization(ideal_model), ideal_model.torque_limits())
    with pytest.raises(PlanError, match="made with the circulatory flow model, this tracker runs the ideal one"):
        ideal_tracker.start(plan)
    ideal_plan = make_trajectory(plan.time_s, plan.q, plan.qdot)
    with pytest.raises(PlanError, match="made with the ideal flow model, this tracker runs the circulatory one"):
        circulatory_tracker(model).start(ideal_plan)
    ideal_tracker.start(ideal_plan)
    assert ideal_tracker.step(0.0, plan.q[0], plan.qdot[0]).lag_estimate.shape == (0,)


def test_holding_after_the_plan_keeps_estimating(run, plan):
    """hold() (a state a period, no time given) advances the estimate one sample period per state."""
    model = run.model
    tracker = circulatory_tracker(model)
    tracker.start(plan)
    tracker.step(0.0, plan.q[0], plan.qdot[0])
    before = tracker.lag_estimator.estimate.copy()
    torque, _ = tracker.hold(plan.q[1], plan.qdot[1], plan.q[-1, -2:])
    reference = LagEstimator(model_lag_rate(model), 2)
    reference.reset(before)
    reference.update(0.0, plan.q[0], plan.qdot[0])
    np.testing.assert_array_equal(tracker.lag_estimator.estimate, reference.update(PERIOD_S, plan.q[1], plan.qdot[1]))
    assert np.all(np.isfinite(torque))


@pytest.mark.filterwarnings("ignore:invalid value encountered:RuntimeWarning")
@pytest.mark.parametrize("glitch", [1e300, 1e150, 100.0], ids=["overflow", "huge", "100 rad/s"])
def test_a_state_past_the_models_range_leaves_the_estimate(run, plan, glitch):
    """A state whose lag rate overflows, or whose normal velocity is past any stroke's (a glitch), is not taken
    into z^: the estimate stays, and the next states carry on from it as if the glitch had been a gap."""
    model = run.model
    estimator = LagEstimator(model_lag_rate(model), 2)
    estimator.reset(plan.lag[0])
    step_s = float(plan.time_s[1] - plan.time_s[0])
    estimator.update(0.0, plan.q[0], plan.qdot[0])
    before = estimator.update(step_s, plan.q[1], plan.qdot[1]).copy()
    kept = estimator.update(step_s, plan.q[2], np.full(3, glitch)).copy()
    np.testing.assert_array_equal(kept, before)
    after = estimator.update(step_s, plan.q[3], plan.qdot[3])
    np.testing.assert_array_equal(after, kept)   # restarted: the first state after the gap gives the slopes
    resumed = estimator.update(step_s, plan.q[4], plan.qdot[4])
    # off by what the true lag did over the gap (not integrated), plus the integration's 1e-4 m/s
    assert np.all(np.abs(resumed - plan.lag[4]) <= np.abs(plan.lag[3] - plan.lag[1]) + 1e-4)


@pytest.mark.parametrize("period_s", [PERIOD_S, 0.1, 10.0])
def test_the_estimate_never_overshoots_the_normal_velocity(run, period_s):
    """Whatever the period, z^ lands between its old value and the measured normal velocities Q (the steady lag)."""
    model = run.model
    estimator = LagEstimator(model_lag_rate(model), 2)
    start = np.array([1.0, -1.0])
    estimator.reset(start)
    k0, k1 = 100, 100 + round(period_s / TRUTH_STEP_S) if period_s < 1.0 else 101
    estimator.update(0.0, run.q[k0], run.qdot[k0])
    z = estimator.update(period_s, run.q[k1], run.qdot[k1])
    steady = [model.lag_rate(run.q[k], run.qdot[k], np.zeros(2)) / lag_slopes(model, run.q[k:k + 1],
                                                                              run.qdot[k:k + 1])[0]
              for k in (k0, k1)]
    low = np.minimum(start, np.minimum(*steady)) - 1e-12
    high = np.maximum(start, np.maximum(*steady)) + 1e-12
    assert np.all((low <= z) & (z <= high))
