"""Each safety rule on its own, then hypothesis-fuzzed commands against the current limits."""
import dataclasses
import math

import pytest
from conftest import PERIOD_S, READ_FAILURE_LIMIT, STALE_READ_LIMIT, WATCHDOG_PERIODS
from hypothesis import given, settings
from hypothesis import strategies as st

from swim_hw_bridge.safety import (
    Command,
    FaultCode,
    Motion,
    SafetyLayer,
    WatchdogState,
    braking_speed_limit,
    soft_limit_scale,
)
from swim_ros.codecs import MessageError, torque_from_command

T0 = 100.0


def command(heave=0.1, pitch=0.05, at=T0):
    return Command(heave, pitch, at)


def currents(safety, cmd, now=T0, phi=0.0, theta=0.0):
    return safety.output(now, cmd, phi, theta)


def test_a_command_within_limits_passes_as_current(safety, config):
    heave_a, pitch_a, heave_n_m, pitch_n_m = currents(safety, command(0.5, -0.2))
    assert heave_a == pytest.approx(0.5 / (43 * 0.0335))
    assert pitch_a == pytest.approx(-0.2 / (25 * 0.030))
    assert (heave_n_m, pitch_n_m) == pytest.approx((0.5, -0.2))
    assert safety.watchdog is WatchdogState.OK and safety.saturation_count == 0


def test_watchdog_zeroes_after_n_periods_and_a_new_command_resumes(safety):
    timeout = WATCHDOG_PERIODS * PERIOD_S
    cmd = command(at=T0)
    assert currents(safety, cmd, now=T0 + timeout - 1e-6)[0] != 0.0
    assert currents(safety, cmd, now=T0 + timeout + 1e-6)[:2] == (0.0, 0.0)
    assert safety.watchdog is WatchdogState.EXPIRED
    later = T0 + timeout + 0.001
    assert currents(safety, command(at=later), now=later)[0] != 0.0
    assert safety.watchdog is WatchdogState.OK


def test_no_command_means_zero(safety):
    assert currents(safety, None) == (0.0, 0.0, 0.0, 0.0)
    assert safety.watchdog is WatchdogState.WAITING


def test_torque_saturates_at_the_papers_limit_and_is_counted(safety, config):
    heave_a, pitch_a, heave_n_m, pitch_n_m = currents(safety, command(100.0, -100.0))
    assert (heave_n_m, pitch_n_m) == pytest.approx((config.rig.torque_limits_n_m[0], -config.rig.torque_limits_n_m[1]))
    assert safety.saturation_count == 1
    currents(safety, command(0.1, 0.1))
    assert safety.saturation_count == 1


def test_current_saturates_when_the_current_limit_binds_first(config):
    from swim_hw_bridge.safety import SafetyLimits
    limits = SafetyLimits.from_config(config, PERIOD_S, WATCHDOG_PERIODS, 3, 3)
    tight = SafetyLayer(limits.__class__(**{**limits.__dict__, "current_limits_a": (0.1, 0.1)}))
    heave_a, pitch_a, heave_n_m, _ = currents(tight, command(1.0, -0.5))
    assert (heave_a, pitch_a) == (0.1, -0.1)
    assert heave_n_m == pytest.approx(0.1 * 43 * 0.0335)
    assert tight.saturation_count == 1


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_torque_gives_zero_and_a_latched_fault(safety, bad):
    assert currents(safety, command(bad, 0.1)) == (0.0, 0.0, 0.0, 0.0)
    assert safety.faults & FaultCode.NONFINITE_OUTPUT
    assert currents(safety, command(0.1, 0.1, at=T0 + 0.001), now=T0 + 0.001)[:2] == (0.0, 0.0)   # latched


def test_soft_limit_scales_outward_torque_linearly(config):
    upper, lower = config.rig.hard_limits_rad[0][1], config.rig.hard_limits_rad[0][0]
    margin = config.rig.limits.heave.soft_margin_rad
    assert soft_limit_scale(upper - 2 * margin, 1.0, lower, upper, margin) == 1.0
    assert soft_limit_scale(upper - 0.25 * margin, 1.0, lower, upper, margin) == pytest.approx(0.25)
    assert soft_limit_scale(upper - 0.25 * margin, -1.0, lower, upper, margin) == 1.0   # inward: untouched
    assert soft_limit_scale(lower + 0.5 * margin, -1.0, lower, upper, margin) == pytest.approx(0.5)
    assert soft_limit_scale(lower + 0.5 * margin, 1.0, lower, upper, margin) == 1.0
    assert soft_limit_scale(upper, 1.0, lower, upper, margin) == 0.0


def test_soft_limit_applies_in_the_output(safety, config):
    phi = config.rig.hard_limits_rad[0][1] - 0.5 * config.rig.limits.heave.soft_margin_rad
    theta = config.rig.hard_limits_rad[1][0] + 0.1 * config.rig.limits.pitch.soft_margin_rad
    _, _, heave_n_m, pitch_n_m = currents(safety, command(0.4, -0.2), phi=phi, theta=theta)
    assert heave_n_m == pytest.approx(0.2)
    assert pitch_n_m == pytest.approx(-0.02)
    _, _, heave_n_m, pitch_n_m = currents(safety, command(-0.4, 0.2), phi=phi, theta=theta)
    assert (heave_n_m, pitch_n_m) == pytest.approx((-0.4, 0.2))   # back toward the middle: full torque


@pytest.mark.parametrize("phi, theta", [(1.2, 0.0), (-1.2, 0.0), (0.0, 1.5), (0.0, -1.5), (math.nan, 0.0)])
def test_past_a_hard_limit_latches_zero(safety, phi, theta):
    safety.check_positions(phi, theta)
    assert safety.faults & FaultCode.HARD_LIMIT
    assert currents(safety, command(-0.1, -0.1), phi=0.0, theta=0.0)[:2] == (0.0, 0.0)
    safety.check_positions(0.0, 0.0)   # back inside: still latched until reset
    assert safety.faults & FaultCode.HARD_LIMIT


def test_emergency_stop_latches_until_reset_and_resumes_only_on_a_fresh_command(safety):
    old = command(at=T0)
    assert currents(safety, old)[0] != 0.0
    safety.emergency_stop()
    assert currents(safety, old, now=T0 + 0.001)[:2] == (0.0, 0.0)
    assert currents(safety, command(at=T0 + 0.002), now=T0 + 0.003)[:2] == (0.0, 0.0)   # latched
    safety.reset(T0 + 0.004)
    assert not safety.faults
    assert currents(safety, command(at=T0 + 0.002), now=T0 + 0.005)[:2] == (0.0, 0.0)   # older than the reset
    assert safety.watchdog is WatchdogState.WAITING
    assert currents(safety, command(at=T0 + 0.006), now=T0 + 0.007)[0] != 0.0


def braking_layer(limits, velocity_terms=None):
    """A layer with a braking bound: 10 rad/s^2 of deceleration, 20 of drive, for both joints."""
    from swim_hw_bridge.safety import JointDynamicsBounds
    dynamics = JointDynamicsBounds((10.0, 10.0), (20.0, 20.0), velocity_terms)
    return SafetyLayer(dataclasses.replace(limits, dynamics=dynamics, latency_s=PERIOD_S))


def fast_toward_upper(theta_rate, upper, distance=0.1):
    """The pitch link distance below its upper limit, moving toward it at theta_rate (mean rate over a period)."""
    return Motion((0.0, 0.43, 0.0, upper - distance), (0.0, 0.0, 0.0, theta_rate), PERIOD_S)


def test_braking_follows_the_bound_and_holds_while_the_watchdog_zeroes_but_not_with_a_fault(limits, config):
    upper, pitch_limit = config.rig.hard_limits_rad[1][1], config.rig.torque_limits_n_m[1]
    bound = braking_speed_limit(0.1, 10.0, PERIOD_S, 20.0)
    slow, fast = fast_toward_upper(0.9 * bound, upper), fast_toward_upper(1.1 * bound, upper)
    safety = braking_layer(limits)
    assert safety.output(T0, command(0.0, 0.05), 0.0, upper - 0.1, slow)[3] == pytest.approx(0.05)
    assert safety.output(T0, command(0.0, 0.05), 0.0, upper - 0.1, fast)[3] == pytest.approx(-pitch_limit)
    expired = T0 + WATCHDOG_PERIODS * PERIOD_S + 0.001
    safety = braking_layer(limits)
    assert safety.output(expired, command(0.0, 0.05), 0.0, upper - 0.1, fast)[3] == pytest.approx(-pitch_limit)
    assert safety.watchdog is WatchdogState.EXPIRED                   # zero asked, the link braked all the same
    assert braking_layer(limits).output(T0, None, 0.0, upper - 0.1, fast)[3] == pytest.approx(-pitch_limit)
    safety = braking_layer(limits)
    safety.emergency_stop()
    assert safety.output(T0, command(0.0, 0.05), 0.0, upper - 0.1, fast) == (0.0, 0.0, 0.0, 0.0)


def test_velocity_terms_toward_a_limit_tighten_the_bound_and_away_do_not(limits, config):
    upper = config.rig.hard_limits_rad[1][1]
    rate = 0.9 * braking_speed_limit(0.1, 10.0, PERIOD_S, 20.0)   # within the bound without velocity terms
    for push, braked in ((5.0, True), (-5.0, False)):
        safety = braking_layer(limits, lambda positions, rates, push=push: (0.0, push))
        assert (safety.output(T0, command(0.0, 0.05), 0.0, upper - 0.1, fast_toward_upper(rate, upper))[3] < 0) \
            is braked


def test_stale_reads_latch_after_the_limit(safety):
    safety.check_read(1)
    for repeat in range(STALE_READ_LIMIT - 1):
        safety.check_read(1)
        assert not safety.faults
    safety.check_read(2)   # a fresh sample restarts the count
    for _ in range(STALE_READ_LIMIT):
        safety.check_read(2)
    assert safety.faults == FaultCode.STALE_READ


def test_failing_reads_latch_after_the_limit(safety):
    for _ in range(READ_FAILURE_LIMIT - 1):
        safety.check_read(None)
    safety.check_read(7)
    for _ in range(READ_FAILURE_LIMIT - 1):
        safety.check_read(None)
    assert not safety.faults
    safety.check_read(None)
    assert safety.faults == FaultCode.READ_FAILED


any_float = st.floats(allow_nan=True, allow_infinity=True)


@settings(max_examples=400, deadline=None)
@given(names=st.lists(st.sampled_from(["phi", "theta", "alpha", "R", "", "PHI"]), max_size=5),
       efforts=st.lists(any_float, max_size=5), phi=any_float, theta=any_float, dt=st.floats(0.0, 1.0))
def test_fuzzed_commands_never_exceed_a_current_limit(limits, names, efforts, phi, theta, dt):
    safety = SafetyLayer(limits)
    try:
        torques = torque_from_command(names, efforts)
    except MessageError:
        torques = (efforts + [0.0, 0.0])[:2]   # push the refused values straight into the layer anyway
    safety.check_positions(phi, theta)
    output = safety.output(T0 + dt, Command(torques[0], torques[1], T0), phi, theta)
    for current, limit in zip(output[:2], limits.current_limits_a):
        assert math.isfinite(current) and abs(current) <= limit
    for torque, limit in zip(output[2:], limits.torque_limits_n_m):
        assert math.isfinite(torque) and abs(torque) <= limit * (1 + 1e-12)
