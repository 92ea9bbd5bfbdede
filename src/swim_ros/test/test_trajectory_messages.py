"""PlannedTrajectory <-> Trajectory: the encoder and decoder agree, and a bad plan is refused with its reason."""
import numpy as np
import pytest
from builtin_interfaces.msg import Time
from swim_interfaces.msg import PlannedTrajectory

from swim_control.errors import PlanError
from swim_control.trajectory import MAX_TRACKED_SAMPLES, Trajectory
from swim_ros.codecs import float_array
from swim_ros.trajectory_messages import SUPPORTED_INTERFACE_VERSION, trajectory_from_message, trajectory_to_message

ARRAYS = ("time_s", "q", "qdot", "foil_acceleration", "torque", "lqr_gain", "riccati_input_gain")


def assert_same_trajectory(got: Trajectory, sent: Trajectory) -> None:
    """Bit for bit: every array, every segment, the lane and the library digest."""
    for name in ARRAYS:
        np.testing.assert_array_equal(getattr(got, name), getattr(sent, name), err_msg=name)
    assert got.segments == sent.segments
    assert (got.lane_radius_m, got.library_digest, got.joint_names) == \
        (sent.lane_radius_m, sent.library_digest, sent.joint_names)


@pytest.fixture()
def trajectory(make_trajectory):
    """A free-vehicle trajectory with every array distinct, so a field put in the wrong place shows."""
    t = np.linspace(0.0, 2.0, 9) ** 1.5
    rng = np.random.default_rng(3)
    samples = len(t)
    return make_trajectory(t, rng.normal(size=(samples, 4)), rng.normal(size=(samples, 4)),
                           rng.normal(size=(samples, 2)), rng.normal(size=(samples, 2)),
                           lqr_gain=rng.normal(size=(samples, 2, 10)),
                           riccati_input_gain=rng.normal(size=(samples, 2, 10)), time_scale=1.3)


def test_the_version_written_is_the_interface_version():
    assert SUPPORTED_INTERFACE_VERSION == PlannedTrajectory.INTERFACE_VERSION


def test_a_version_4_plan_reads_as_this_version(trajectory):
    """Version 5 added the maneuver action and the primitive list, no plan field: a v4 plan is read as it is."""
    message = trajectory_to_message(trajectory, Time(sec=5))
    message.interface_version = 4
    assert_same_trajectory(trajectory_from_message(message), trajectory)


def test_round_trip_is_bit_for_bit(trajectory):
    message = trajectory_to_message(trajectory, Time(sec=5))
    assert message.header.stamp.sec == 5 and not message.constrained
    assert list(message.joint_names) == ["alpha", "R", "phi", "theta"]
    assert_same_trajectory(trajectory_from_message(message), trajectory)


def _corrupt(message, bad):  # noqa: C901 - one branch per kind of corruption
    if bad == "version":
        message.interface_version = SUPPORTED_INTERFACE_VERSION + 1
    elif bad == "joint names":
        message.joint_names = ["alpha", "R", "phi", "psi"]
    elif bad == "constrained flag":
        message.constrained = True
    elif bad == "nan":
        positions = np.asarray(message.positions)
        positions[5] = np.nan
        message.positions = float_array(positions)
    elif bad == "inf":
        message.sliding_gains = float_array(np.where(np.arange(len(message.sliding_gains)) == 3, np.inf,
                                                     np.asarray(message.sliding_gains)))
    elif bad == "short":
        message.velocities = float_array(np.asarray(message.velocities)[:-1])
    elif bad == "long gains":
        message.lqr_gains = float_array(np.zeros(len(message.lqr_gains) + 20))
    elif bad == "times":
        message.time_from_start_s = float_array(np.asarray(message.time_from_start_s)[::-1])
    elif bad == "segments":
        message.segments[0].sample_count -= 1
    elif bad == "too many samples":
        message.time_from_start_s = float_array(np.arange(MAX_TRACKED_SAMPLES + 1, dtype=float))


@pytest.mark.parametrize("bad, reason", [
    ("version", f"interface version {SUPPORTED_INTERFACE_VERSION + 1}, this tracker reads versions 4 and "
                f"{SUPPORTED_INTERFACE_VERSION}"),
    ("joint names", r"plan joints \['alpha', 'R', 'phi', 'psi'\] are not the free vehicle's"),
    ("constrained flag", "are not the constrained vehicle's"),
    ("nan", "plan q has non-finite values"),
    ("inf", "plan riccati_input_gain has non-finite values"),
    ("short", "velocities has 35 values, expected 36 for 9 samples"),
    ("long gains", "lqr_gains has 200 values, expected 180"),
    ("times", "strictly increasing"),
    ("segments", "the segments cover 8 samples, the plan has 9"),
    ("too many samples", f"{MAX_TRACKED_SAMPLES + 1} samples, more than the largest plan this tracker accepts "
                         f"\\({MAX_TRACKED_SAMPLES}"),
])
def test_a_bad_plan_is_refused_with_its_reason(trajectory, bad, reason):
    message = trajectory_to_message(trajectory, Time())
    _corrupt(message, bad)
    with pytest.raises(PlanError, match=reason):
        trajectory_from_message(message)
