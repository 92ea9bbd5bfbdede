"""The cascade law's parts: saturation, the sliding-mode term, velocity estimates, modes."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swim_controller.sliding_mode import SlidingMode
from swim_controller.supervisor import Mode, Outcome, Supervisor, Tolerances
from swim_controller.tracker import CascadeTracker, saturate


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(allow_nan=True, allow_infinity=True, width=64), min_size=2, max_size=2))
def test_saturation_never_exceeds_the_limits(values):
    limits = np.array([1.25, 0.524])
    command, flags = saturate(np.array(values), limits)
    assert np.all(np.abs(command) <= limits)
    if not all(math.isfinite(v) for v in values):
        assert np.all(command == 0.0) and all(flags)


@settings(max_examples=200, deadline=None)
@given(st.floats(-50, 50), st.floats(-50, 50), st.floats(0, 2 * math.pi), st.floats(0, 1))
def test_sliding_term_makes_the_lyapunov_derivative_nonpositive(s0, s1, angle, fraction):
    """Outside the boundary layer, 2 s'(eps + d) <= 0 for every ||d|| <= D (module docstring)."""
    mode = SlidingMode(disturbance_bound_n_m=0.3, boundary_layer=1.0)
    s = np.array([s0, s1])
    eps = mode.term(s)
    d = 0.3 * fraction * np.array([math.cos(angle), math.sin(angle)])
    norm = float(np.linalg.norm(s))
    if norm >= 1.0:
        assert np.linalg.norm(eps) == pytest.approx(0.3)
        assert s @ (eps + d) <= 1e-12
    else:   # inside the layer: linear in s, never larger than D
        np.testing.assert_allclose(eps, -0.3 * s, atol=1e-15)


def _static_io(q, qdot, lag):
    return np.diag([2.0, 0.5]), np.zeros(2)


def test_supervisor_reports_tolerances_and_holds_after_the_plan(make_trajectory):
    t = np.linspace(0.0, 1.0, 11)
    q = np.zeros((11, 3))
    q[:, 0] = t                           # alpha from 0 to 1 rad
    qdot = np.zeros((11, 3))
    qdot[:, 0] = 1.0
    limits = np.array([100.0, 100.0])
    supervisor = Supervisor(CascadeTracker(_static_io, limits, sliding_mode_enabled=False))
    supervisor.begin(make_trajectory(t, q, qdot), Tolerances(path_alpha_rad=0.1))
    assert supervisor.on_state(100.0, np.zeros(3), np.zeros(3)).outcome is None
    step = supervisor.on_state(100.5, np.zeros(3), np.zeros(3))   # 0.5 rad behind
    assert step.outcome is Outcome.PATH_TOLERANCE_VIOLATED and supervisor.mode is Mode.HOLDING
    supervisor.begin(make_trajectory(t, q, qdot), Tolerances(goal_alpha_rad=0.05))
    supervisor.on_state(0.0, np.zeros(3), np.zeros(3))
    assert supervisor.on_state(1.2, np.array([0.9, 0.0, 0.0]), np.zeros(3)).outcome is \
        Outcome.GOAL_TOLERANCE_VIOLATED
    supervisor.begin(make_trajectory(t, q, qdot), Tolerances(goal_alpha_rad=0.05))
    supervisor.on_state(0.0, np.zeros(3), np.zeros(3))
    assert supervisor.on_state(1.2, np.array([0.98, 0.0, 0.0]), np.zeros(3)).outcome is Outcome.SUCCEEDED
    # holding: a foil displaced from the plan's last psi is pushed back (u = -kp e through Mio)
    held = supervisor.on_state(1.3, np.array([0.98, 0.1, -0.2]), np.zeros(3))
    np.testing.assert_allclose(held.torque, np.diag([2.0, 0.5]) @ (-100.0 * np.array([0.1, -0.2])))
    supervisor.state_lost()
    assert np.all(supervisor.on_state(1.4, np.zeros(3), np.zeros(3)).torque == 0.0)


def test_stale_state_watch_judges_on_time_checks_and_skips_one_late_check():
    from swim_controller.supervisor import StaleStateWatch
    period, limit = 0.008, 0.096
    watch = StaleStateWatch(0.0, period)
    # on-time checks: stale exactly once the newest state is older than the limit
    checks = [k * period for k in range(1, 20)]
    verdicts = [watch.stale(t, limit) for t in checks]
    assert verdicts == [t > limit for t in checks]
    # the asker was held up 0.2 s: the first check after the stall does not judge (a state may wait unread) ...
    watch = StaleStateWatch(0.0, period)
    watch.state_arrived(0.0)
    assert not watch.stale(0.2, limit)
    watch.state_arrived(0.2001)             # ... and the queued state is then read
    assert not watch.stale(0.208, limit)
    # ... but with no state at all, the next check judges even if it is late too
    watch = StaleStateWatch(0.0, period)
    assert not watch.stale(0.2, limit) and watch.check_gap_s == pytest.approx(0.2)
    assert watch.stale(0.4, limit) and watch.check_gap_s == pytest.approx(0.2)
    # on a host where every check is late, a dead plant is still caught within one extra check
    watch = StaleStateWatch(0.0, period)
    late = [0.05 * k for k in range(1, 8)]
    verdicts = [watch.stale(t, limit) for t in late]
    first = late[verdicts.index(True)]
    assert limit < first <= limit + 2 * 0.05
