"""PlannedTrajectory v4 <-> Trajectory with the flow model: the lag states travel bit for bit, and what an older or
broken message says about the flow is refused with its reason."""
import numpy as np
import pytest
from builtin_interfaces.msg import Time
from swim_interfaces.msg import PlannedTrajectory

from swim_control.errors import PlanError
from swim_control.riccati import error_state_size
from swim_control.trajectory import Segment, Trajectory
from swim_ros.codecs import float_array
from swim_ros.trajectory_messages import (
    MAX_PLAN_MAGNITUDE,
    SUPPORTED_INTERFACE_VERSION,
    trajectory_from_message,
    trajectory_to_message,
)

ARRAYS = ("time_s", "q", "qdot", "foil_acceleration", "torque", "lqr_gain", "riccati_input_gain", "lag")
SAMPLES = 9


def circulatory_trajectory(nq: int, seed: int = 5) -> Trajectory:
    """Every array distinct and random, so a field put in the wrong place shows."""
    rng = np.random.default_rng(seed)
    n = error_state_size(nq, nq - 2, 2)
    time_s = np.linspace(0.0, 2.0, SAMPLES) ** 1.5
    segment = Segment("test/circulatory", "cruise", 0, 0.0, float(time_s[-1]), 1.3, 0.0, 0, SAMPLES)
    q = rng.normal(size=(SAMPLES, nq))
    if nq == 4:
        q[:, 1] = 0.43 + 0.01 * q[:, 1]
    return Trajectory(time_s, q, rng.normal(size=(SAMPLES, nq)), rng.normal(size=(SAMPLES, 2)),
                      rng.normal(size=(SAMPLES, 2)), rng.normal(size=(SAMPLES, 2, n)),
                      rng.normal(size=(SAMPLES, 2, n)), (segment,), lane_radius_m=0.43, library_digest="digest",
                      flow_model="circulatory", lag=rng.normal(scale=0.1, size=(SAMPLES, 2)))


@pytest.mark.parametrize("nq", [3, 4], ids=["constrained", "free"])
def test_a_circulatory_plan_round_trips_bit_for_bit(nq):
    sent = circulatory_trajectory(nq)
    message = trajectory_to_message(sent, Time(sec=2))
    assert message.interface_version == PlannedTrajectory.INTERFACE_VERSION == SUPPORTED_INTERFACE_VERSION == 5
    assert message.flow_model == "circulatory"
    np.testing.assert_array_equal(np.asarray(message.lag_states), sent.lag.ravel())   # row-major N x n_lag
    got = trajectory_from_message(message)
    for name in ARRAYS:
        np.testing.assert_array_equal(getattr(got, name), getattr(sent, name), err_msg=name)
    assert (got.flow_model, got.n_lag, got.segments, got.library_digest) == ("circulatory", 2, sent.segments,
                                                                              "digest")
    np.testing.assert_array_equal(got.sample(0.7).lag, sent.sample(0.7).lag)


def test_an_ideal_plan_says_so_and_carries_no_lag_states(make_trajectory):
    t = np.linspace(0.0, 1.0, 5)
    sent = make_trajectory(t, np.zeros((5, 3)), np.zeros((5, 3)), gain=0.5)
    message = trajectory_to_message(sent, Time())
    assert message.flow_model == "ideal" and len(message.lag_states) == 0
    got = trajectory_from_message(message)
    assert got.flow_model == "ideal" and got.lag is None and got.lqr_gain.shape == (5, 2, 7)


def broken(bad: str) -> PlannedTrajectory:
    message = trajectory_to_message(circulatory_trajectory(3), Time())
    if bad in ("version 2", "version 3"):
        message.interface_version = int(bad[-1])
    elif bad == "flow model":
        message.flow_model = "potential"
    elif bad == "no flow model":
        message.flow_model = ""
    elif bad == "short lag":
        message.lag_states = float_array(np.asarray(message.lag_states)[:-1])
    elif bad == "ideal with lag":
        message.flow_model = "ideal"
        n = error_state_size(3, 1)
        message.lqr_gains = float_array(np.zeros(SAMPLES * 2 * n))
        message.sliding_gains = float_array(np.zeros(SAMPLES * 2 * n))
    elif bad == "ideal-size gains":
        n = error_state_size(3, 1)
        message.lqr_gains = float_array(np.zeros(SAMPLES * 2 * n))
    elif bad == "lag not finite":
        lag = np.asarray(message.lag_states)
        lag[3] = np.nan
        message.lag_states = float_array(lag)
    elif bad == "lag past the bound":
        lag = np.asarray(message.lag_states)
        lag[4] = 10 * MAX_PLAN_MAGNITUDE
        message.lag_states = float_array(lag)
    elif bad == "lag rate past the bound":
        message.time_from_start_s = float_array(np.asarray(message.time_from_start_s) * 1e-152)
        message.positions = float_array(np.zeros(len(message.positions)))
        message.velocities = float_array(np.zeros(len(message.velocities)))
        message.foil_accelerations = float_array(np.zeros(len(message.foil_accelerations)))
        message.feedforward_torques = float_array(np.zeros(len(message.feedforward_torques)))
        message.lqr_gains = float_array(np.zeros(len(message.lqr_gains)))
        message.sliding_gains = float_array(np.zeros(len(message.sliding_gains)))
        message.segments[0].duration_s *= 1e-152
    return message


@pytest.mark.parametrize("bad, reason", [
    ("version 2", "plan interface version 2, this tracker reads versions 4 and 5 \\(a version 2 plan does not say "
                  "which flow model"),
    ("version 3", "plan interface version 3, this tracker reads versions 4 and 5 \\(a version 3 plan does not "
                  "carry the sliding mode's disturbance bound"),
    ("flow model", "plan flow model 'potential' is not one of ideal, circulatory"),
    ("no flow model", "plan flow model '' is not one of ideal, circulatory"),
    ("short lag", f"plan lag_states has {2 * SAMPLES - 1} values, expected {2 * SAMPLES} for {SAMPLES} samples"),
    ("ideal with lag", f"plan lag_states has {2 * SAMPLES} values, expected 0 for {SAMPLES} samples"),
    ("ideal-size gains", f"plan lqr_gains has {SAMPLES * 2 * 7} values, expected {SAMPLES * 2 * 9}"),
    ("lag not finite", "plan lag has non-finite values"),
    ("lag past the bound", "plan lag has values or changes per second past"),
    ("lag rate past the bound", "plan lag has values or changes per second past"),
])
def test_a_bad_circulatory_plan_is_refused_with_its_reason(bad, reason):
    with pytest.raises(PlanError, match=reason):
        trajectory_from_message(broken(bad))
