"""Concatenation and time scaling of the shipped library's primitives."""
import numpy as np
import pytest

from swim_planner.catalog import PAPER_CONSTRAINED
from swim_planner.errors import ManeuverError
from swim_planner.maneuver import concatenate, expand_sequence, vary_time_scale

TRAJECTORY_ARRAYS = ("time_s", "q", "qdot", "foil_acceleration", "torque", "lqr_gain", "riccati_input_gain")


def paper_plan(library, rig, time_scale=1.0, start_alpha=0.0):
    return concatenate(library, rig, expand_sequence(*PAPER_CONSTRAINED), time_scale, start_alpha)


def test_paper_constrained_maneuver_lasts_30_s(library, rig):
    """Sec. 7.1: {accelerate1, cruise1 x2, cruise-to-cruise(1,2), cruise2 x2, decelerate2}, 30 s nominal."""
    plan = paper_plan(library, rig)
    assert plan.duration_s == pytest.approx(4 + 2 * 5 + 2 + 2 * 5 + 4)
    assert [s.primitive_id for s in plan.segments][1:3] == ["constrained/cruise/E0.05"] * 2
    assert np.all(np.diff(plan.time_s) > 0)
    # alpha continues across junctions and the vehicle ends at rest
    for segment in plan.segments[1:]:
        k = segment.first_sample
        assert abs(plan.q[k, 0] - plan.q[k - 1, 0]) < 0.05
    np.testing.assert_allclose(plan.qdot[-1], 0.0, atol=1e-6)
    assert plan.q[-1, 0] > 1.0


@pytest.mark.parametrize("time_scale", [0.8, 1.2])
def test_time_scaling(library, rig, time_scale):
    """lambda = 1.2 lasts 1/1.2 as long and needs 1.44x the torque (P3, Sec. 4.3)."""
    nominal, scaled = paper_plan(library, rig), paper_plan(library, rig, time_scale)
    assert scaled.duration_s == pytest.approx(nominal.duration_s / time_scale, rel=1e-12)
    np.testing.assert_allclose(scaled.torque, nominal.torque * time_scale ** 2, rtol=1e-12)
    np.testing.assert_allclose(scaled.q, nominal.q, atol=1e-12)
    np.testing.assert_allclose(scaled.qdot, nominal.qdot * time_scale, rtol=1e-12)
    assert np.abs(scaled.torque).max() == pytest.approx(time_scale ** 2 * np.abs(nominal.torque).max())


def test_start_alpha_translates_the_plan(library, rig):
    plan, moved = paper_plan(library, rig), paper_plan(library, rig, start_alpha=1.5)
    np.testing.assert_allclose(moved.q[:, 0], plan.q[:, 0] + 1.5, atol=1e-12)


@pytest.mark.parametrize("ids, counts, scale, message", [
    (["constrained/accelerate/E0.05", "constrained/cruise/E0.10"], [1, 1], 1.0, "does not end where"),
    (["constrained/cruise/E0.05", "no/such/primitive"], [1, 1], 1.0, "unknown primitives: no/such/primitive"),
    (PAPER_CONSTRAINED[0], PAPER_CONSTRAINED[1], 3.0, "largest feasible time scale"),
    (PAPER_CONSTRAINED[0], PAPER_CONSTRAINED[1], -1.0, "positive finite"),
    (PAPER_CONSTRAINED[0], PAPER_CONSTRAINED[1], float("nan"), "positive finite"),
    (PAPER_CONSTRAINED[0], [1, 2], 1.0, "repeat counts"),
    (PAPER_CONSTRAINED[0], [1, 0, 1, 1, 1], 1.0, "at least 1"),
    (["constrained/accelerate/E0.05", "free/cruise/R0.43/E0.05"], [1, 1], 1.0, "mix constrained and free"),
])
def test_impossible_requests_say_why(library, rig, ids, counts, scale, message):
    with pytest.raises(ManeuverError, match=message):
        concatenate(library, rig, expand_sequence(ids, counts), scale)


def test_constant_varying_scale_equals_constant_scaling(library, rig):
    """A constant lambda(s) is the one time scaling (Trajectory.time_scaled), as concatenate's: bit for bit."""
    fixed = paper_plan(library, rig, 1.2)
    varied = vary_time_scale(paper_plan(library, rig), lambda s: 1.2, rig)
    for name in TRAJECTORY_ARRAYS:
        np.testing.assert_array_equal(getattr(varied, name), getattr(fixed, name), err_msg=name)
    assert varied.segments == fixed.segments


def test_a_plan_travels_through_its_message_bit_for_bit(library, rig):
    """planner_node's encoder and tracker_node's decoder (swim_ros.trajectory_messages) on a concatenated plan."""
    from builtin_interfaces.msg import Time

    from swim_ros.trajectory_messages import trajectory_from_message, trajectory_to_message
    for plan in (paper_plan(library, rig, 1.2, start_alpha=0.3),
                 concatenate(library, rig, expand_sequence(["free/accelerate/R0.43/E0.05"], []), 0.9)):
        decoded = trajectory_from_message(trajectory_to_message(plan, Time()))
        for name in TRAJECTORY_ARRAYS:
            np.testing.assert_array_equal(getattr(decoded, name), getattr(plan, name), err_msg=name)
        assert decoded.segments == plan.segments and decoded.joint_names == plan.joint_names
        assert (decoded.lane_radius_m, decoded.library_digest) == (plan.lane_radius_m, plan.library_digest)


def test_ramped_scale_lasts_the_closed_form_time(library, rig):
    """lambda(s) = 1 + c s gives t(S) = ln(1 + c S) / c."""
    nominal = paper_plan(library, rig)
    c = 0.2 / nominal.duration_s  # from 1.0 to 1.2 over the maneuver
    varied = vary_time_scale(nominal, lambda s: 1.0 + c * s, rig)
    assert varied.duration_s == pytest.approx(np.log(1.0 + c * nominal.duration_s) / c, rel=1e-6)
    np.testing.assert_allclose(varied.q, nominal.q)
    assert varied.segments[0].time_scale < varied.segments[-1].time_scale
    with pytest.raises(ManeuverError, match="positive and finite"):
        vary_time_scale(nominal, lambda s: 1.0 - s, rig)
    with pytest.raises(ManeuverError, match="torque limits"):
        vary_time_scale(nominal, lambda s: 3.0, rig)


def test_plan_bounds_refuse_by_the_specs_alone_and_admit_a_thousand_cruises(library):
    """The 1000-cruise request (5008 s, 0.8 M samples) is within the default bounds; 100,000 cruises are not,
    and are refused without reading more than the three primitives' specs and sample counts."""
    from swim_planner.maneuver import PlanBounds, check_plan_size
    ids = ["constrained/accelerate/E0.05", "constrained/cruise/E0.05", "constrained/decelerate/E0.05"]
    check_plan_size(library, ids, [1, 1000, 1], 1.0)
    with pytest.raises(ManeuverError, match="longer than the longest plan served"):
        check_plan_size(library, ids, [1, 100_000, 1], 1.0)
    with pytest.raises(ManeuverError, match="more than the largest plan served"):
        check_plan_size(library, ids, [1, 1000, 1], 1.0, PlanBounds(max_samples=100_000))
    samples = sum(library.sample_count(i) * n for i, n in zip(ids, [1, 1000, 1]))
    check_plan_size(library, ids, [1, 1000, 1], 1.0, PlanBounds(max_samples=samples))   # the bound itself passes
    with pytest.raises(ValueError, match="max_duration_s"):
        PlanBounds(max_duration_s=float("nan")).validate()
    # an unknown id is refused before its repeats are expanded: 4.3e9 of them would fill the memory
    with pytest.raises(ManeuverError, match="unknown primitives: no/such"):
        check_plan_size(library, [ids[0], "no/such"], [1, 2**32 - 1], 1.0)
