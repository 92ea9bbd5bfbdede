"""A plan made with the circulatory flow model: its lag states checked when made, sampled, and time-scaled."""
import dataclasses

import numpy as np
import pytest

from swim_control.errors import PlanError
from swim_control.riccati import error_state_size
from swim_control.time_scaling import scaling_diagonal
from swim_control.trajectory import Segment, Trajectory

LIMITS_N_M = np.array([1.25, 0.524])
N_LAG = 2


def _plan(samples=5, nq=3, flow_model="circulatory", lag="default", n_lag=N_LAG):
    """A one-segment plan with distinct values in every array (so that a mixed-up column shows)."""
    rng = np.random.default_rng(4)
    time_s = np.linspace(0.0, 1.0, samples)
    n = error_state_size(nq, nq - 2, n_lag)
    lag_states = rng.normal(scale=0.1, size=(samples, N_LAG)) if isinstance(lag, str) else lag
    segment = Segment("test/segment", "cruise", 0, 0.0, 1.0, 1.0, 0.0, 0, samples)
    return Trajectory(time_s, rng.normal(size=(samples, nq)), rng.normal(size=(samples, nq)),
                      rng.normal(size=(samples, 2)), 0.1 * rng.normal(size=(samples, 2)),
                      rng.normal(size=(samples, 2, n)), rng.normal(size=(samples, 2, n)), (segment,),
                      lane_radius_m=0.43, flow_model=flow_model, lag=lag_states)


def test_the_ideal_default_has_no_lag_states(make_trajectory):
    plan = make_trajectory(np.linspace(0.0, 1.0, 4), np.zeros((4, 3)), np.zeros((4, 3)))
    assert (plan.flow_model, plan.lag, plan.n_lag) == ("ideal", None, 0)
    assert plan.sample(0.3).lag.shape == (0,)


@pytest.mark.parametrize("nq", [3, 4])
def test_a_circulatory_plan_has_the_extended_gains_and_samples_its_lag_linearly(nq):
    plan = _plan(nq=nq)
    assert plan.n_lag == N_LAG and plan.lqr_gain.shape[2] == nq - 2 + 2 * nq + N_LAG
    t = 0.6   # between samples 2 (0.5 s) and 3 (0.75 s)
    w = (t - 0.5) / 0.25
    point = plan.sample(t)
    np.testing.assert_allclose(point.lag, (1 - w) * plan.lag[2] + w * plan.lag[3], rtol=1e-13)
    np.testing.assert_allclose(point.lqr_gain, (1 - w) * plan.lqr_gain[2] + w * plan.lqr_gain[3], rtol=1e-12)
    np.testing.assert_allclose(point.riccati_input_gain,
                               (1 - w) * plan.riccati_input_gain[2] + w * plan.riccati_input_gain[3], rtol=1e-12)
    np.testing.assert_allclose(point.torque, (1 - w) * plan.torque[2] + w * plan.torque[3], rtol=1e-12)
    np.testing.assert_array_equal(plan.sample(plan.time_s[4]).lag, plan.lag[4])


@pytest.mark.parametrize("changes, message", [
    ({"lag": None}, "needs its lag states"),
    ({"flow_model": "ideal"}, "has no lag states"),
    ({"flow_model": "viscous"}, "flow model must be one of"),
    ({"lag": np.zeros((5, 3))}, r"lag must have shape \(5, 2\)"),
    ({"lag": np.zeros((4, 2))}, r"lag must have shape \(5, 2\)"),
    ({"lag": np.where(np.eye(5, 2) > 0, np.nan, 0.0)}, "lag has non-finite"),
    ({"lag": np.full((5, 2), np.inf)}, "lag has non-finite"),
    ({"n_lag": 0}, "lqr_gain must have shape"),   # gains of the ideal state size
])
def test_malformed_lag_states_are_refused(changes, message):
    with pytest.raises(PlanError, match=message):
        _plan(**changes)


def test_time_scaling_scales_the_lag_states_and_composes():
    """z -> lambda z (lag states are velocities), the gains by Theorem 1 with Gamma's lag block I; lambda2 after
    lambda1 is lambda1 lambda2."""
    nominal = _plan()
    first, second = 1.15, 0.9
    both = first * second
    composed = nominal.time_scaled(first, LIMITS_N_M).time_scaled(second, LIMITS_N_M)
    assert composed.flow_model == "circulatory"
    np.testing.assert_allclose(composed.lag, both * nominal.lag, rtol=1e-15)
    np.testing.assert_allclose(composed.qdot, both * nominal.qdot, rtol=1e-15)
    gamma = scaling_diagonal(both, nominal.ny, nominal.nq, N_LAG)
    np.testing.assert_array_equal(gamma[-N_LAG:], 1.0)
    np.testing.assert_allclose(composed.riccati_input_gain, nominal.riccati_input_gain * gamma, rtol=1e-14)
    np.testing.assert_allclose(composed.lqr_gain, both * nominal.lqr_gain * gamma, rtol=1e-14)
    np.testing.assert_allclose(composed.sample(0.3 / both).lag, both * nominal.sample(0.3).lag, rtol=1e-13)


def test_replace_keeps_a_circulatory_plan_checked():
    plan = _plan()
    with pytest.raises(PlanError, match="lag has non-finite"):
        dataclasses.replace(plan, lag=np.full_like(plan.lag, np.nan))
