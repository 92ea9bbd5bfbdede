"""The tracker's control step against the law written out from its definition (tracker.py's module docstring) with
plain numpy, bit for bit: the step computes on Python floats where numpy's per-call overhead would dominate, and
these tests hold it to the numbers of the direct formulation (np.concatenate, np.linalg.solve, np.clip) over many
steps, with the ideal flow (the paper's law, on real LQ gains of the constrained and the free vehicle) and the
circulatory one (its lag estimate and a plan's disturbance bound D(t)).

Bit for bit is possible because every vector operation moved to Python floats is elementwise (one IEEE rounding per
operation, the same as numpy's), while the products with matrices (K x, G'P x, Mio u) and the solve stay numpy's.
"""
import dataclasses
import math

import numpy as np
import pytest

from swim_control.riccati import LqrWeights
from swim_control.time_scaling import lqr_gain_from
from swim_control.trajectory import Segment, Trajectory
from swim_controller.sliding_mode import SlidingMode
from swim_controller.testing.circulatory import gait_run, plan_from_run
from swim_controller.tracker import (
    HOLD_DAMPING_PER_S,
    HOLD_STIFFNESS_PER_S2,
    CascadeTracker,
    LagEstimator,
    model_io_linearization,
    model_lag_rate,
    solve,
)
from swim_model import VehicleModel

#: the steps of the ideal-flow run: as many as bench_control_step times (20 s of a 1 kHz loop)
IDEAL_STEPS = 20000
#: the other runs (sliding mode off, the free vehicle, the circulatory plan): enough to cross every sample interval
#: of their plans several times
OTHER_STEPS = 4000
#: the measured state's spread about the plan (rad or m, rad/s or m/s): tracking errors of the paper's size, and
#: large enough that the sliding term leaves its boundary layer and the torques saturate in some steps
Q_NOISE, QDOT_NOISE = 0.02, 0.2


def plan_times(plan: Trajectory, steps: int, period_s: float, seed: int) -> list[float]:
    """Plan times at which to step: a 1 kHz clock wrapped around the plan, with periods that vary (jitter, a
    repeated and a backward time), one before the start and a stretch past the end (the hold law)."""
    rng = np.random.default_rng(seed)
    duration_s = plan.duration_s
    times = [(k * period_s + rng.uniform(0.0, 0.3 * period_s)) % duration_s for k in range(steps)]
    times[10:13] = [times[10], times[10], times[10] - 0.5 * period_s]
    return [-0.01] + times + [duration_s + k * period_s for k in range(1, 50)]


def reference_law(plan: Trajectory, io, limits: np.ndarray, sliding_mode: SlidingMode, sliding_enabled: bool,
                  period_s: float):
    """The law of tracker.py's module docstring on plain numpy arrays of the plan: a function (t, q, qdot, lag,
    elapsed_s (None at the first step), integral) -> (command, unsaturated torque, sliding term, error state,
    integral after the step, whether s was outside the boundary layer)."""
    time_s = plan.time_s
    duration_s = float(time_s[-1])
    nq = plan.nq

    def interval(t: float) -> tuple[int, float, float]:
        k = min(max(int(np.searchsorted(time_s, t, side="right")) - 1, 0), len(time_s) - 2)
        return k, t - time_s[k], time_s[k + 1] - time_s[k]

    def linear(values: np.ndarray, t: float) -> np.ndarray:
        k, offset, step = interval(t)
        return values[k] + offset * ((values[k + 1] - values[k]) / step)

    def step(t: float, q: np.ndarray, qdot: np.ndarray, lag: np.ndarray, elapsed_s: float, integral: np.ndarray):
        holding = t > duration_s
        clamped = min(max(t, 0.0), duration_s)
        k, offset, step = interval(clamped)
        secant = (plan.q[k + 1] - plan.q[k]) / step
        w = offset / step
        q_ref = (plan.q[k] + offset * secant
                 + step * w * (1.0 - w) * ((plan.qdot[k] - secant) * (1.0 - w) - (plan.qdot[k + 1] - secant) * w))
        error_q = q - q_ref
        if elapsed_s is not None and not holding:
            integral = integral + error_q[:nq - 2] * max(elapsed_s, 0.0)
        parts = [integral, error_q, qdot - linear(plan.qdot, clamped)]
        if plan.lag is not None:
            parts.append(lag - linear(plan.lag, clamped))
        x = np.concatenate(parts)
        mio, cio_qdot = io(q, qdot, lag)
        if holding:
            u = (-HOLD_STIFFNESS_PER_S2 * (q[-2:] - plan.q[-1, -2:]) - HOLD_DAMPING_PER_S * qdot[-2:])
        else:
            u_des = linear(plan.foil_acceleration, min(max(t + 0.5 * period_s, 0.0), duration_s))
            u = u_des - linear(plan.lqr_gain, clamped) @ x
        torque = mio @ u + cio_qdot
        eps, outside_layer = np.zeros(2), False
        if sliding_enabled and not holding:
            s = np.linalg.solve(mio, linear(plan.riccati_input_gain, clamped) @ x)
            bound = sliding_mode.disturbance_bound_n_m if plan.disturbance_bound is None else \
                sliding_mode.disturbance_bound_margin * linear(plan.disturbance_bound, clamped)
            norm, layer = math.hypot(s[0], s[1]), sliding_mode.boundary_layer
            eps, outside_layer = s * (-bound / max(norm, layer)), norm > layer
            torque = torque + eps
        command = np.clip(torque, -limits, limits) if np.all(np.isfinite(torque)) else np.zeros(2)
        return command, torque, eps, x, integral, outside_layer
    return step


def assert_steps_match_the_reference(model: VehicleModel, plan: Trajectory, steps: int, sliding_enabled: bool,
                                     seed: int, period_s: float = 0.001) -> None:
    io, limits, lag_rate = model_io_linearization(model), model.torque_limits(), model_lag_rate(model)
    tracker = CascadeTracker(io, limits, SlidingMode(), sliding_enabled, period_s, lag_rate)
    tracker.start(plan)
    reference = reference_law(plan, io, limits, SlidingMode(), sliding_enabled, period_s)
    estimator = None
    if lag_rate is not None:   # the estimate itself is LagEstimator's (test_tracker_circulatory); fed alike here
        estimator = LagEstimator(lag_rate, model.n_lag)
        estimator.reset(plan.lag[0])
    rng = np.random.default_rng(seed)
    integral, previous_s = np.zeros(plan.ny), None
    stepped, expected = [], []
    for t in plan_times(plan, steps, period_s, seed):
        k = min(max(int(np.searchsorted(plan.time_s, t)), 0), len(plan.time_s) - 1)
        q = plan.q[k] + rng.normal(scale=Q_NOISE, size=plan.nq)
        qdot = plan.qdot[k] + rng.normal(scale=QDOT_NOISE, size=plan.nq)
        elapsed_s = None if previous_s is None else t - previous_s
        lag = np.zeros(0) if estimator is None else estimator.update(0.0 if elapsed_s is None else elapsed_s, q, qdot)
        command, torque, eps, x, integral, outside_layer = reference(t, q, qdot, lag, elapsed_s, integral)
        previous_s = t
        out = tracker.step(t, q, qdot)
        stepped.append(np.concatenate([out.torque, out.unsaturated_torque, out.sliding_torque, out.error_state,
                                       out.lag_estimate, out.saturated]))
        saturated = (abs(torque[0]) > limits[0], abs(torque[1]) > limits[1])
        expected.append(np.concatenate([command, torque, eps, x, lag, saturated, [outside_layer]]))
    stepped_rows, expected_rows = np.array(stepped), np.array(expected)
    np.testing.assert_array_equal(stepped_rows, expected_rows[:, :-1])
    # the run reaches the law's branches: saturation, and (with the sliding mode) s outside its boundary layer
    assert np.any(expected_rows[:, -3:-1])
    assert not sliding_enabled or np.any(expected_rows[:, -1])


@pytest.fixture(scope="module")
def stroke_plans(strokes):
    """{"constrained" | "free": the stroke's samples with its LQ gains (K = R^-1 G'P) as a plan}."""
    input_weights = np.array([LqrWeights().heave_input_weight, LqrWeights().pitch_input_weight])
    plans = {}
    for kind, stroke in strokes.items():
        gains = stroke.gains.riccati_input_gain
        plans[kind] = Trajectory(stroke.time_s, stroke.q, stroke.qdot, stroke.foil_acceleration,
                                 np.zeros((len(stroke.time_s), 2)), lqr_gain_from(gains, input_weights), gains,
                                 (Segment("test/stroke", "cruise", 0, 0.0, float(stroke.time_s[-1]), 1.0, 0.0, 0,
                                          len(stroke.time_s)),), lane_radius_m=stroke.spec.lane_radius_m)
    return plans


@pytest.mark.parametrize(("sliding_enabled", "steps"), [(True, IDEAL_STEPS), (False, OTHER_STEPS)])
def test_the_ideal_step_is_the_law_bit_for_bit(model_for, strokes, stroke_plans, sliding_enabled, steps):
    stroke = strokes["constrained"]
    assert_steps_match_the_reference(model_for(stroke.spec), stroke_plans["constrained"], steps, sliding_enabled,
                                     seed=1)


def test_the_free_vehicles_step_is_the_law_bit_for_bit(model_for, strokes, stroke_plans):
    stroke = strokes["free"]
    assert_steps_match_the_reference(model_for(stroke.spec), stroke_plans["free"], OTHER_STEPS, True, seed=2)


def test_the_circulatory_step_with_a_planned_bound_is_the_law_bit_for_bit(rig):
    model = VehicleModel(rig, constrained=True, flow="circulatory")
    plan = plan_from_run(gait_run(model, 2.0), 2.0)
    # a bound D(t) varying along the plan (N m), of the size of the constant one, so that it is interpolated
    bound = SlidingMode().disturbance_bound_n_m * (1.0 + np.sin(2.0 * math.pi * plan.time_s))
    plan = dataclasses.replace(plan, disturbance_bound=bound)
    assert_steps_match_the_reference(model, plan, OTHER_STEPS, True, seed=3)


def test_solve_is_numpys_solve_bit_for_bit():
    """The tracker's solve is numpy.linalg.solve's kernel without its wrapper: the same numbers, for the symmetric
    positive definite 2 x 2 matrices Mio is, over six decades of conditioning."""
    rng = np.random.default_rng(5)
    for _ in range(2000):
        root = rng.normal(size=(2, 2)) * 10.0 ** rng.uniform(-3, 3, size=(2, 1))
        matrix = root @ root.T + 1e-6 * np.eye(2)
        rhs = rng.normal(size=2) * 10.0 ** rng.uniform(-3, 3)
        np.testing.assert_array_equal(solve(matrix, rhs), np.linalg.solve(matrix, rhs))


def test_the_mid_period_feed_forward_is_the_sampled_one(stroke_plans):
    plan = stroke_plans["constrained"]
    for t in np.linspace(-0.1, plan.duration_s + 0.1, 997):
        assert plan.foil_acceleration_at(float(t)) == tuple(plan.sample(float(t)).foil_acceleration)
