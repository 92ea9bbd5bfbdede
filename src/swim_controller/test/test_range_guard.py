"""FoilRangeGuard: the bound on the law's foil acceleration near the heave's and the pitch's stops."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swim_controller.tracker import CascadeTracker, FoilRangeGuard

#: the rig's stops (swim_model's rig.yaml limits: heave +-60 deg, pitch +-80 deg), rad
STOPS = ((-math.pi / 3, math.pi / 3), (-math.radians(80.0), math.radians(80.0)))
PERIOD_S = 0.008   # paper Sec. 2


def test_on_the_braking_curve_the_bound_is_braking_at_a():
    """Heave d = 0.3 rad short of its upper stop less the margin, moving toward it at v = sqrt(2 a d) = 6 rad/s
    with a = 60 rad/s^2 (v > a h / 2): the joint must brake at a. At rest there it may be driven at
    (-a h / 2 + sqrt(a^2 h^2 / 4 + 2 a d)) / h, the lower stop being far."""
    guard = FoilRangeGuard(STOPS, braking_acceleration_rad_s2=(60.0, 400.0), margin_rad=0.05)
    heave = math.pi / 3 - 0.05 - 0.3
    bounded, limited = guard.bound([1000.0, 0.0], [heave, 0.0], [6.0, 0.0], PERIOD_S)
    assert bounded[0] == pytest.approx(-60.0, rel=1e-9) and limited == (True, False)
    at_rest = (-0.24 + math.sqrt(0.24 ** 2 + 36.0)) / PERIOD_S
    bounded, _ = guard.bound([1e5, 0.0], [heave, 0.0], [0.0, 0.0], PERIOD_S)
    assert bounded[0] == pytest.approx(at_rest, rel=1e-12)
    assert guard.bound([100.0, 0.0], [heave, 0.0], [0.0, 0.0], PERIOD_S) == ([100.0, 0.0], (False, False))
    # past the margin, moving on at 5 rad/s, or 1 mm short of it at 0.5 rad/s: asked to stop within the period
    bounded, _ = guard.bound([0.0, 0.0], [math.pi / 3, 0.0], [5.0, 0.0], PERIOD_S)
    assert bounded[0] == pytest.approx(-5.0 / PERIOD_S, rel=1e-12)
    bounded, _ = guard.bound([0.0, 0.0], [math.pi / 3 - 0.05 - 0.001, 0.0], [0.5, 0.0], PERIOD_S)
    assert bounded[0] == pytest.approx(-0.5 / PERIOD_S, rel=1e-12)


@settings(max_examples=300, deadline=None)
@given(st.floats(-1.5, 1.5), st.floats(-30.0, 30.0), st.floats(-1e5, 1e5), st.sampled_from([0, 1]))
def test_the_bounds_never_cross_nor_forbid_accelerating_away_from_a_stop(position, rate, acceleration, joint):
    guard = FoilRangeGuard(STOPS)
    psi, psi_rate, u = [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]
    psi[joint], psi_rate[joint], u[joint] = position, rate, acceleration
    lowest = guard.bound([-math.inf, -math.inf], psi, psi_rate, PERIOD_S)[0][joint]
    highest = guard.bound([math.inf, math.inf], psi, psi_rate, PERIOD_S)[0][joint]
    assert lowest <= highest
    bounded, limited = guard.bound(u, psi, psi_rate, PERIOD_S)
    assert lowest <= bounded[joint] <= highest
    assert limited[joint] == (bounded[joint] != acceleration)
    # a joint not moving toward a stop may always be accelerated away from it
    if rate <= 0.0:
        assert highest >= 0.0
    if rate >= 0.0:
        assert lowest <= 0.0


@settings(max_examples=200, deadline=None)
@given(st.floats(-0.8, 0.8), st.floats(-6.0, 6.0), st.sampled_from([1e2, 1e3, 1e5]), st.sampled_from([0, 1]))
def test_a_joint_pushed_at_its_stop_comes_to_rest_at_the_margin(start_rad, start_rate_rad_s, push_rad_s2, joint):
    """A joint that does what it is asked (psi'' = u, held over each 8 ms period) and is asked for push_rad_s2
    toward its upper stop every period, from a state it can still brake from, passes the margin by at most
    a h^2 / 2 and comes to rest there (the bound lets it close in, not stop short, and it does not bounce)."""
    guard = FoilRangeGuard(STOPS)
    braking = guard.braking_acceleration_rad_s2[joint]
    limit = STOPS[joint][1] - guard.margin_rad
    overshoot = 0.5 * braking * PERIOD_S ** 2
    if start_rate_rad_s > 0.0:   # a start it can brake from
        start_rate_rad_s = min(start_rate_rad_s, math.sqrt(2.0 * braking * (limit - start_rad)))
    psi, rate = [0.0, 0.0], [0.0, 0.0]
    psi[joint], rate[joint] = start_rad, start_rate_rad_s
    highest_rad = psi[joint]
    for _ in range(int(4.0 / PERIOD_S)):
        u = guard.bound([push_rad_s2, push_rad_s2], psi, rate, PERIOD_S)[0][joint]
        psi[joint] += rate[joint] * PERIOD_S + 0.5 * u * PERIOD_S ** 2
        rate[joint] += u * PERIOD_S
        highest_rad = max(highest_rad, psi[joint])
    assert highest_rad <= limit + overshoot + 1e-12 < STOPS[joint][1]
    if push_rad_s2 >= 1e3:   # pushed hard enough to close in within the time
        assert limit - 1e-3 <= psi[joint] <= limit + overshoot and rate[joint] == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("arguments", [
    dict(hard_limits_rad=((1.0, -1.0), STOPS[1])),
    dict(hard_limits_rad=(STOPS[0], (-0.05, 0.05))),              # no room between the margins
    dict(hard_limits_rad=((math.nan, 1.0), STOPS[1])),
    dict(hard_limits_rad=STOPS, braking_acceleration_rad_s2=(0.0, 400.0)),
    dict(hard_limits_rad=STOPS, braking_acceleration_rad_s2=(60.0, math.inf)),
    dict(hard_limits_rad=STOPS, margin_rad=-0.01),
    dict(hard_limits_rad=STOPS, margin_rad=math.nan),
])
def test_a_guard_that_cannot_work_is_refused(arguments):
    with pytest.raises(ValueError, match="FoilRangeGuard"):
        FoilRangeGuard(**arguments)


def _static_io(q, qdot, lag):
    return np.diag([2.0, 0.5]), np.zeros(2)


def test_the_hold_law_is_bounded_and_the_torque_follows_the_bound():
    """hold() toward a target past the heave's stop, the heave at 0.9 rad moving up at 4.5 rad/s: the hold law asks
    100 (1.8 - 0.9) - 20 4.5 = 0 rad/s^2 without the guard; with braking at 80 rad/s^2 the heave, 0.097 rad short
    of its margin, must brake, and the torque is the guard's acceleration through Mio (diag(2, 0.5) here)."""
    guard = FoilRangeGuard(STOPS)
    q, qdot = np.array([0.0, 0.9, 0.0]), np.array([0.0, 4.5, 0.0])
    target = np.array([1.8, 0.0])
    (expected_heave, expected_pitch), limited = guard.bound([0.0, 0.0], [0.9, 0.0], [4.5, 0.0], PERIOD_S)
    assert limited == (True, False) and expected_heave < 0.0
    guarded = CascadeTracker(_static_io, np.array([1e6, 1e6]), range_guard=guard, sample_period_s=PERIOD_S)
    torque, _ = guarded.hold(q, qdot, target)
    np.testing.assert_allclose(torque, [2.0 * expected_heave, 0.5 * expected_pitch], rtol=1e-12)
    free_torque, _ = CascadeTracker(_static_io, np.array([1e6, 1e6]), sample_period_s=PERIOD_S).hold(q, qdot, target)
    assert free_torque[0] == pytest.approx(0.0, abs=1e-12)


def test_the_tracking_law_is_bounded_and_says_so(make_trajectory):
    """step() on a plan at rest with no feedback (u = 0) while the heave, 0.9 rad, moves up at 4.5 rad/s: the guard
    brakes it, reports it, and the torque is the guard's acceleration through Mio; without a guard u stays 0."""
    t = np.linspace(0.0, 1.0, 11)
    plan = make_trajectory(t, np.zeros((11, 3)), np.zeros((11, 3)))
    q, qdot = np.array([0.0, 0.9, 0.0]), np.array([0.0, 4.5, 0.0])
    (expected_heave, _), _ = FoilRangeGuard(STOPS).bound([0.0, 0.0], [0.9, 0.0], [4.5, 0.0], PERIOD_S)
    outputs = []
    for guard in (FoilRangeGuard(STOPS), None):
        tracker = CascadeTracker(_static_io, np.array([1e6, 1e6]), sliding_mode_enabled=False,
                                 sample_period_s=PERIOD_S, range_guard=guard)
        tracker.start(plan)
        outputs.append(tracker.step(0.5, q, qdot))
    guarded, free = outputs
    assert guarded.range_guarded == (True, False) and free.range_guarded == (False, False)
    np.testing.assert_allclose(guarded.torque, [2.0 * expected_heave, 0.0], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(free.torque, [0.0, 0.0], atol=1e-12)
