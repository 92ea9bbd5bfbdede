"""The sliding mode's disturbance bound D(t) carried by a plan: checked when the plan is made, sampled linearly,
time-scaled as a torque (lambda^2 D(lambda t)), sent and received in PlannedTrajectory (v4), and used by the
tracker's sliding term with its margin; a plan without one leaves the law exactly as with the constant bound."""
import dataclasses
import math

import numpy as np
import pytest
from builtin_interfaces.msg import Time
from hypothesis import given, settings
from hypothesis import strategies as st

from swim_control.errors import PlanError
from swim_controller.sliding_mode import SlidingMode
from swim_controller.tracker import CascadeTracker
from swim_ros.codecs import float_array
from swim_ros.trajectory_messages import MAX_PLAN_MAGNITUDE, trajectory_from_message, trajectory_to_message

LIMITS_N_M = np.array([1.25, 0.524])
SAMPLES = 6


def _bounded(make_trajectory, bound=None):
    """A one-segment constrained plan with distinct values, and its disturbance bound (default: distinct, >= 0)."""
    rng = np.random.default_rng(11)
    time_s = np.linspace(0.0, 1.0, SAMPLES)
    plan = make_trajectory(time_s, rng.normal(size=(SAMPLES, 3)), rng.normal(size=(SAMPLES, 3)),
                           torque=0.05 * rng.normal(size=(SAMPLES, 2)), gain=0.3)
    bound = np.abs(rng.normal(scale=0.05, size=SAMPLES)) if bound is None else bound
    return dataclasses.replace(plan, disturbance_bound=bound)


def test_a_plan_without_a_bound_samples_none(make_trajectory):
    plan = make_trajectory(np.linspace(0.0, 1.0, 4), np.zeros((4, 3)), np.zeros((4, 3)))
    assert plan.disturbance_bound is None and plan.sample(0.3).disturbance_bound_n_m is None


def test_the_bound_is_sampled_linearly_and_leaves_the_other_rows_as_they_were(make_trajectory):
    plan = _bounded(make_trajectory)
    without = dataclasses.replace(plan, disturbance_bound=None)
    t = 0.53   # between samples 2 (0.4 s) and 3 (0.6 s)
    w = (t - 0.4) / 0.2
    point, reference = plan.sample(t), without.sample(t)
    assert point.disturbance_bound_n_m == pytest.approx((1 - w) * plan.disturbance_bound[2]
                                                        + w * plan.disturbance_bound[3], rel=1e-13)
    for name in ("q", "qdot", "foil_acceleration", "torque", "lqr_gain", "riccati_input_gain", "lag"):
        np.testing.assert_array_equal(getattr(point, name), getattr(reference, name), err_msg=name)
    assert plan.sample(plan.time_s[4]).disturbance_bound_n_m == plan.disturbance_bound[4]


@pytest.mark.parametrize("bound, message", [
    (np.zeros(SAMPLES - 1), r"disturbance_bound must have shape \(6,\)"),
    (np.zeros((SAMPLES, 2)), r"disturbance_bound must have shape \(6,\)"),
    (np.where(np.arange(SAMPLES) == 2, np.nan, 0.0), "disturbance_bound has non-finite"),
    (np.where(np.arange(SAMPLES) == 3, -1e-3, 0.0), "disturbance_bound has negative values"),
])
def test_a_malformed_bound_is_refused(make_trajectory, bound, message):
    with pytest.raises(PlanError, match=message):
        _bounded(make_trajectory, bound)


def test_time_scaling_scales_the_bound_as_a_torque_and_composes(make_trajectory):
    """D_l(t) = lambda^2 D(lambda t), as tau_l (trajectory's module docstring): lambda2 after lambda1 is
    lambda1 lambda2, and the sampled bound at t / lambda is lambda^2 times the nominal one at t."""
    nominal = _bounded(make_trajectory)
    first, second = 1.3, 0.85
    both = first * second
    composed = nominal.time_scaled(first, LIMITS_N_M).time_scaled(second, LIMITS_N_M)
    np.testing.assert_allclose(composed.disturbance_bound, both ** 2 * nominal.disturbance_bound, rtol=1e-15)
    np.testing.assert_allclose(composed.disturbance_bound / composed.torque[:, 0],
                               nominal.disturbance_bound / nominal.torque[:, 0], rtol=1e-14)
    assert composed.sample(0.37 / both).disturbance_bound_n_m == pytest.approx(
        both ** 2 * nominal.sample(0.37).disturbance_bound_n_m, rel=1e-13)


@settings(max_examples=100, deadline=None)
@given(st.floats(-50, 50), st.floats(-50, 50), st.floats(0.0, 1.0), st.floats(1.0, 5.0), st.floats(0.0, 0.5))
def test_the_sliding_term_with_the_plans_bound(s0, s1, layer_fraction, margin, bound):
    """eps = -margin D s / max(||s||, phi) with the plan's D; None gives the constant bound's term bit for bit."""
    mode = SlidingMode(disturbance_bound_n_m=0.02, boundary_layer=0.5 + layer_fraction, disturbance_bound_margin=margin)
    s = np.array([s0, s1])
    expected = -margin * bound * s / max(math.hypot(s0, s1), mode.boundary_layer)
    np.testing.assert_allclose(mode.term(s, bound), expected, rtol=1e-13, atol=1e-300)
    constant = s * (-0.02 / max(math.hypot(s0, s1), mode.boundary_layer))
    np.testing.assert_array_equal(mode.term(s), constant)
    np.testing.assert_array_equal(mode.term(s, None), constant)


@pytest.mark.parametrize("margin", [0.99, math.nan, math.inf])
def test_a_margin_below_one_or_not_finite_is_refused(margin):
    with pytest.raises(ValueError, match="disturbance bound margin"):
        SlidingMode(disturbance_bound_margin=margin).validate()


def _static_io(q, qdot, lag):
    return np.diag([2.0, 0.5]), np.array([0.01, -0.02])


def test_the_tracker_uses_the_plans_bound_times_its_margin(make_trajectory):
    """A plan whose D(t) is the constant bound over the margin gives the constant bound's torques exactly (0.04 =
    2 x 0.02 in binary floating point); a plan with a time-varying D gives eps of norm margin D(t) outside the
    boundary layer; the same plan without D gives the constant bound's."""
    plan = _bounded(make_trajectory)
    constant = dataclasses.replace(plan, disturbance_bound=None)
    halved = dataclasses.replace(plan, disturbance_bound=np.full(SAMPLES, 0.02))
    mode = SlidingMode(disturbance_bound_n_m=0.04, boundary_layer=1e-6, disturbance_bound_margin=2.0)
    q, qdot = plan.q[0] + 0.1, plan.qdot[0] - 0.2
    outputs = {}
    for name, trajectory in (("constant", constant), ("halved", halved), ("varying", plan)):
        tracker = CascadeTracker(_static_io, np.array([100.0, 100.0]), mode)
        tracker.start(trajectory)
        outputs[name] = [tracker.step(t, q, qdot) for t in (0.0, 0.008, 0.53)]
    for a, b in zip(outputs["constant"], outputs["halved"]):
        np.testing.assert_array_equal(a.torque, b.torque)
        assert np.linalg.norm(a.sliding_torque) == pytest.approx(0.04, rel=1e-12)
    for out in outputs["varying"]:
        expected = 2.0 * plan.sample(out.reference.time_s).disturbance_bound_n_m
        assert np.linalg.norm(out.sliding_torque) == pytest.approx(expected, rel=1e-9)


def test_the_bound_travels_in_the_message_bit_for_bit(make_trajectory):
    sent = _bounded(make_trajectory).time_scaled(1.2, LIMITS_N_M)
    message = trajectory_to_message(sent, Time(sec=1))
    np.testing.assert_array_equal(np.asarray(message.disturbance_bounds_n_m), sent.disturbance_bound)
    got = trajectory_from_message(message)
    np.testing.assert_array_equal(got.disturbance_bound, sent.disturbance_bound)
    unbounded = trajectory_to_message(dataclasses.replace(sent, disturbance_bound=None), Time())
    assert len(unbounded.disturbance_bounds_n_m) == 0
    assert trajectory_from_message(unbounded).disturbance_bound is None


@pytest.mark.parametrize("change, reason", [
    (lambda b: b[:-1], f"plan disturbance_bounds_n_m has {SAMPLES - 1} values, expected {SAMPLES} for"),
    (lambda b: np.append(b, 0.1), f"plan disturbance_bounds_n_m has {SAMPLES + 1} values, expected {SAMPLES} for"),
    (lambda b: np.where(np.arange(SAMPLES) == 1, np.inf, b), "plan disturbance_bound has non-finite values"),
    (lambda b: np.where(np.arange(SAMPLES) == 1, -0.1, b), "plan disturbance_bound has negative values"),
    (lambda b: np.where(np.arange(SAMPLES) == 1, 10 * MAX_PLAN_MAGNITUDE, b),
     "plan disturbance_bound has values or changes per second past"),
])
def test_a_bad_bound_in_a_message_is_refused_with_its_reason(make_trajectory, change, reason):
    message = trajectory_to_message(_bounded(make_trajectory), Time())
    message.disturbance_bounds_n_m = float_array(change(np.asarray(message.disturbance_bounds_n_m)))
    with pytest.raises(PlanError, match=reason):
        trajectory_from_message(message)
