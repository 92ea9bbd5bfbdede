"""The trajectory type: checked when made, sampled, and time-scaled in one place (P3, Theorem 1)."""
import dataclasses
import math

import numpy as np
import pytest

from swim_control.errors import PlanError
from swim_control.riccati import LqrWeights
from swim_control.time_scaling import lqr_gain_from, scaling_diagonal
from swim_control.trajectory import Segment, Trajectory

LIMITS_N_M = np.array([1.25, 0.524])   # the (heave, pitch) limits the scaling tests check against


def test_sample_interpolates_a_cubic_exactly_and_clamps(make_trajectory):
    t = np.linspace(0.0, 1.0, 5)
    f = lambda s: 2 * s ** 3 - s ** 2 + 0.5 * s   # noqa: E731
    df = lambda s: 6 * s ** 2 - 2 * s + 0.5         # noqa: E731
    trajectory = make_trajectory(t, np.column_stack([f(t)] * 3), np.column_stack([df(t)] * 3))
    for s in (0.1, 0.37, 0.9):
        assert trajectory.sample(s).q[0] == pytest.approx(f(s), abs=1e-12)
    assert trajectory.sample(-1.0).q[0] == pytest.approx(f(0.0))
    assert trajectory.sample(5.0).q[0] == pytest.approx(f(1.0))


@pytest.mark.parametrize("bad, message", [
    ("nan", "non-finite"), ("inf", "non-finite"), ("order", "strictly increasing"), ("shape", r"\(N, 3\) or \(N, 4\)"),
    ("gain shape", "lqr_gain must have shape"), ("no segment", "at least one segment"),
    ("gap", "tile the samples"), ("short", "cover 3 samples"), ("lane", "lane radius"), ("segment scale", "time scale"),
])
def test_malformed_trajectories_are_refused(make_trajectory, bad, message):
    t = np.linspace(0.0, 1.0, 4)
    q = np.zeros((4, 3))
    trajectory = make_trajectory(t, q, np.zeros((4, 3)))
    fields = {field.name: getattr(trajectory, field.name) for field in dataclasses.fields(Trajectory)
              if field.init}
    segment = trajectory.segments[0]
    changes = {
        "nan": {"q": np.where(np.arange(12).reshape(4, 3) == 7, np.nan, q)},
        "inf": {"riccati_input_gain": np.full((4, 2, 7), np.inf)},
        "order": {"time_s": np.array([0.0, 0.5, 0.5, 1.0])},
        "shape": {"q": np.zeros((4, 5))},
        "gain shape": {"lqr_gain": np.zeros((4, 2, 10))},
        "no segment": {"segments": ()},
        "gap": {"segments": (dataclasses.replace(segment, sample_count=2),
                             dataclasses.replace(segment, first_sample=3, sample_count=1))},
        "short": {"segments": (dataclasses.replace(segment, sample_count=3),)},
        "lane": {"lane_radius_m": math.nan},
        "segment scale": {"segments": (dataclasses.replace(segment, time_scale=0.0),)},
    }[bad]
    with pytest.raises(PlanError, match=message):
        Trajectory(**{**fields, **changes})


def _stroke_trajectory(stroke, torque_peak_fraction):
    """A stroke's samples and gains as a two-segment trajectory at lambda = 1, with a feed-forward torque whose
    largest |tau| / limit is torque_peak_fraction (on the pitch motor)."""
    samples = len(stroke.time_s)
    torque = np.column_stack([0.25 * LIMITS_N_M[0] * np.sin(stroke.time_s),
                              torque_peak_fraction * LIMITS_N_M[1] * np.cos(stroke.time_s)])
    input_weights = np.array([LqrWeights().heave_input_weight, LqrWeights().pitch_input_weight])
    middle = samples // 2
    segments = (Segment("a", "cruise", 0, 0.0, float(stroke.time_s[middle - 1]), 1.0, 0.0, 0, middle),
                Segment("b", "cruise", 0, float(stroke.time_s[middle - 1]),
                        float(stroke.time_s[-1] - stroke.time_s[middle - 1]), 1.0, 0.0, middle, samples - middle))
    riccati_input_gain = stroke.gains.riccati_input_gain
    return Trajectory(stroke.time_s, stroke.q, stroke.qdot, stroke.foil_acceleration, torque,
                      lqr_gain_from(riccati_input_gain, input_weights), riccati_input_gain, segments,
                      lane_radius_m=stroke.spec.lane_radius_m)


@pytest.mark.parametrize("kind", ["constrained", "free"])
def test_time_scalings_compose_to_the_closed_forms(strokes, kind):
    """lambda2 after lambda1 is lambda = lambda1 lambda2: t / lambda, q, lambda qdot, lambda^2 u, lambda^2 tau,
    K = lambda R^-1 (G'P) Gamma(lambda), G_l'P_l = (G'P) Gamma(lambda) (eq. 33), each segment's lambda and times."""
    nominal = _stroke_trajectory(strokes[kind], 0.5)
    first, second = 1.15, 0.9
    both = first * second
    composed = nominal.time_scaled(first, LIMITS_N_M).time_scaled(second, LIMITS_N_M)
    np.testing.assert_allclose(composed.time_s, nominal.time_s / both, rtol=1e-15, atol=0.0)
    np.testing.assert_array_equal(composed.q, nominal.q)
    np.testing.assert_allclose(composed.qdot, both * nominal.qdot, rtol=1e-15)
    np.testing.assert_allclose(composed.foil_acceleration, both ** 2 * nominal.foil_acceleration, rtol=1e-15)
    np.testing.assert_allclose(composed.torque, both ** 2 * nominal.torque, rtol=1e-15)
    gamma = scaling_diagonal(both, nominal.ny, nominal.nq)
    np.testing.assert_allclose(composed.riccati_input_gain, nominal.riccati_input_gain * gamma, rtol=1e-14)
    np.testing.assert_allclose(composed.lqr_gain, both * nominal.lqr_gain * gamma, rtol=1e-14)
    for scaled, segment in zip(composed.segments, nominal.segments):
        assert scaled.time_scale == pytest.approx(both, rel=1e-15)
        assert scaled.start_time_s == pytest.approx(segment.start_time_s / both, rel=1e-15)
        assert scaled.duration_s == pytest.approx(segment.duration_s / both, rel=1e-15)
        assert (scaled.first_sample, scaled.sample_count) == (segment.first_sample, segment.sample_count)
    assert composed.time_scale_at(composed.duration_s) == pytest.approx(both, rel=1e-15)
    assert composed.lane_radius_m == nominal.lane_radius_m and composed.joint_names == nominal.joint_names


def test_a_time_scale_past_the_motor_limits_is_refused_with_the_largest_feasible_named(strokes):
    """Peak |tau| / limit 0.5 at lambda = 1: lambda^2 tau reaches the limits at lambda = sqrt(2); after lambda1, at
    sqrt(2) / lambda1 more."""
    nominal = _stroke_trajectory(strokes["constrained"], 0.5)
    largest = math.sqrt(2.0)
    nominal.time_scaled(largest * (1.0 - 1e-9), LIMITS_N_M)   # just inside: accepted
    with pytest.raises(PlanError, match=rf"needs 101% of the motor torque limits; the largest feasible time scale "
                                        rf"for this plan is {largest:.3f}"):
        nominal.time_scaled(largest * 1.003, LIMITS_N_M)
    faster = nominal.time_scaled(1.2, LIMITS_N_M)
    with pytest.raises(PlanError, match=f"largest feasible time scale for this plan is {largest / 1.2:.3f}"):
        faster.time_scaled(1.2, LIMITS_N_M)
    for bad in (0.0, -1.0, math.nan, math.inf):
        with pytest.raises(PlanError, match="positive finite"):
            nominal.time_scaled(bad, LIMITS_N_M)
    with pytest.raises(PlanError, match="torque limits"):
        nominal.time_scaled(1.0, np.array([1.0, 0.0]))
