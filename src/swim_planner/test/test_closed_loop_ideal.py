"""The cascade tracker in closed loop on the ideal model (no ROS): convergence, sliding mode, limits.

Plans are concatenated from the shipped library with their stored, time-scaled gains; the plant is
swim_model's vehicle integrated with RK4 substeps, the torque held over each 8 ms period
(swim_controller.testing.closed_loop).
"""
import math

import numpy as np
import pytest

from swim_controller.sliding_mode import SlidingMode
from swim_controller.testing.closed_loop import simulate
from swim_controller.tracker import CascadeTracker, model_io_linearization

CONSTRAINED = ["constrained/accelerate/E0.05", "constrained/cruise/E0.05", "constrained/cruise_to_cruise/E0.05-E0.10",
               "constrained/cruise/E0.10", "constrained/decelerate/E0.10"]
LANE_CHANGE = ["free/accelerate/R0.43/E0.10", "free/cruise/R0.43/E0.10", "free/lane_change/R0.43-R0.48/E0.10",
               "free/cruise/R0.48/E0.10", "free/decelerate/R0.48/E0.10"]
FINAL_ALPHA_ERROR_BOUND_RAD = 0.01   # 4 mm of hub travel at R = 0.43 m
# the paper's rig stopped within 0.5 cm of the lane (Sec. 7.2); on the ideal model ours ends 0.1 mm from it
FINAL_R_ERROR_BOUND_M = 0.005
LANE_CHANGE_ALPHA_BOUND_RAD = FINAL_ALPHA_ERROR_BOUND_RAD


def _plan(library, rig, ids, time_scale=1.0, repeats=()):
    from swim_planner.maneuver import concatenate, expand_sequence
    return concatenate(library, rig, expand_sequence(ids, list(repeats)), time_scale)


def _tracker(model, sliding: bool, bound=SlidingMode().disturbance_bound_n_m, sample_period_s=0.008):
    return CascadeTracker(model_io_linearization(model), model.torque_limits(),
                          SlidingMode(disturbance_bound_n_m=bound), sliding_mode_enabled=sliding,
                          sample_period_s=sample_period_s)


@pytest.mark.parametrize("time_scale, sample_period_s", [(1.0, 0.008), (1.2, 0.008), (1.0, 0.001)])
def test_constrained_plan_converges_from_a_perturbed_start(library, model_for, rig, time_scale, sample_period_s):
    reference = _plan(library, rig, CONSTRAINED, time_scale)
    model = model_for(library.spec(CONSTRAINED[0]))
    start = reference.q[0] + np.array([0.02, 0.05, -0.05])
    tracker = _tracker(model, sliding=False, sample_period_s=sample_period_s)
    substeps = max(1, round(sample_period_s / 0.001))   # RK4 steps of 1 ms at most
    run = simulate(model, tracker, reference, sample_period_s, substeps, q0=start)
    assert abs(run.error[-1, 0]) < FINAL_ALPHA_ERROR_BOUND_RAD
    assert np.all(np.abs(run.torque) <= model.torque_limits())
    # the start error decays: the last second tracks far better than the first
    second = int(round(1.0 / sample_period_s))
    first, last = np.abs(run.error[:second, 0]).max(), np.abs(run.error[-second:, 0]).max()
    assert last < 0.5 * first


def test_lane_change_ends_in_the_new_lane(library, model_for, rig):
    reference = _plan(library, rig, LANE_CHANGE)
    model = model_for(library.spec(LANE_CHANGE[0]))
    start = reference.q[0] + np.array([0.0, 0.004, 0.03, -0.03])
    run = simulate(model, _tracker(model, sliding=True), reference, q0=start)
    assert abs(run.error[-1, 1]) < FINAL_R_ERROR_BOUND_M
    assert abs(run.q[-1, 1] - 0.48) < FINAL_R_ERROR_BOUND_M
    assert abs(run.error[-1, 0]) < LANE_CHANGE_ALPHA_BOUND_RAD


def test_lane_keeping_with_repeated_cruises_stays_in_its_lane(library, model_for, rig):
    """The paper's lane keeping (Sec. 7.2): 14 one-second cruises in a row. The cruise gains are those of the
    cruise continued (LqrWeights.cruise_lookahead_s); with each cycle's own horizon the vehicle ended 24 mm
    off its lane and 69 mrad behind. Measured with the lookahead: 6 mm and 2 mrad."""
    ids = ["free/accelerate/R0.43/E0.05", "free/cruise/R0.43/E0.05", "free/decelerate/R0.43/E0.05"]
    reference = _plan(library, rig, ids, repeats=(1, 14, 1))
    model = model_for(library.spec(ids[0]))
    run = simulate(model, _tracker(model, sliding=False), reference)
    assert abs(run.error[-1, 1]) < 0.01
    assert abs(run.error[-1, 0]) < FINAL_ALPHA_ERROR_BOUND_RAD


def test_sliding_mode_lowers_the_error_under_a_matched_disturbance(library, model_for, rig):
    """A torque disturbance on the motors of norm <= D (the matched case of sliding_mode's derivation)."""
    reference = _plan(library, rig, CONSTRAINED[:2])
    model = model_for(library.spec(CONSTRAINED[0]))
    bound = 0.05

    def disturbance(t):
        return bound * np.array([math.sin(2 * math.pi * 0.7 * t), math.cos(2 * math.pi * 0.7 * t)])
    without = simulate(model, _tracker(model, False, bound), reference, disturbance=disturbance)
    with_sliding = simulate(model, _tracker(model, True, bound), reference, disturbance=disturbance)
    assert with_sliding.two_norm(0) < 0.95 * without.two_norm(0)
