"""The run measures against closed forms, on synthetic runs (no ROS)."""
import math

import numpy as np
import pytest
from conftest import tracking_state_cdr

from swim_bringup.analysis import HARD_STOP_TOLERANCE_RAD, measures, summary_table
from swim_bringup.reports import RunAnalysis
from swim_bringup.run_record import Run
from swim_ros.processes import NodeSpec


def synthetic_run(alpha_offset_rad=0.0, radius_offset_m=0.0, constrained=False):
    time_s = np.linspace(0.0, 4.0, 4001)
    alpha = 0.3 * time_s
    names = ["alpha", "phi", "theta"] if constrained else ["alpha", "R", "phi", "theta"]
    reference = np.column_stack([alpha] + ([] if constrained else [np.full_like(time_s, 0.43)])
                                + [np.sin(time_s), np.cos(time_s)])
    measured = reference.copy()
    measured[:, 0] += alpha_offset_rad
    if not constrained:
        measured[:, 1] += radius_offset_m
    qdot = np.gradient(measured, time_s, axis=0)
    torque = np.column_stack([0.5 * np.ones_like(time_s), np.zeros_like(time_s)])
    return Run(time_s, measured, qdot, reference, torque, np.zeros((len(time_s), 2), bool), names, 0.43, True)


def test_an_alpha_offset_is_a_chord_of_the_lane():
    report = measures(synthetic_run(alpha_offset_rad=0.1, constrained=True))
    assert report.longitudinal_error_two_norm_m_s05 == pytest.approx(0.43 * 0.1 * 2.0)
    assert report.cartesian_error_two_norm_m_s05 == pytest.approx(2 * 0.43 * math.sin(0.05) * 2.0)
    assert report.lateral_error_two_norm_m_s05 == 0.0 and report.final_alpha_error_rad == pytest.approx(0.1)


def test_a_heave_held_at_its_stop_counts_the_periods_there():
    """A heave 1.2 sin t clamped at the shipped stops (+-60 degrees, the rig file's) sits at one where
    |sin t| >= (pi / 3) / 1.2: over [0, 4] s, pi - 2 asin((pi / 3) / 1.2) s of the 1 ms periods."""
    run = synthetic_run(constrained=True)
    assert measures(run).hard_stop_periods == 0          # sin t and cos t stay inside both joints' stops
    limit_rad = math.pi / 3
    run.q[:, 1] = np.clip(1.2 * np.sin(run.time_s), -limit_rad, limit_rad)
    expected_s = math.pi - 2.0 * math.asin(limit_rad / 1.2)
    assert measures(run).hard_stop_periods == pytest.approx(expected_s / 1e-3, abs=2)


def test_the_stops_are_the_limits_given_to_within_the_encoders_count():
    run = synthetic_run()                                # free: (alpha, R, phi = sin t, theta = cos t)
    # phi = sin t with stops at +-0.5 rad: from pi/6 to 5 pi/6 and from 7 pi/6 to the run's end, 4 s
    narrow = ((-0.5, 0.5), (-2.0, 2.0))
    expected_s = 2.0 * math.pi / 3.0 + (4.0 - 7.0 * math.pi / 6.0)
    assert measures(run, narrow).hard_stop_periods == pytest.approx(expected_s / 1e-3, abs=2)
    # a joint within HARD_STOP_TOLERANCE_RAD of its limit is at its stop, twice that inside is not; past it is
    run.q[:, 2:] = 0.0
    run.q[10, 2] = 0.5 - 0.5 * HARD_STOP_TOLERANCE_RAD
    run.q[20, 2] = 0.5 - 2.0 * HARD_STOP_TOLERANCE_RAD
    run.q[30, 3] = -2.1
    assert measures(run, narrow).hard_stop_periods == 2


def test_a_lateral_offset_and_the_energy_used():
    report = measures(synthetic_run(radius_offset_m=0.01))
    assert report.lateral_error_two_norm_m_s05 == pytest.approx(0.01 * 2.0)
    assert report.final_lateral_offset_m == pytest.approx(0.01)
    # int_0^4 |0.5 N m * d(sin t)/dt| dt = 0.5 int_0^4 |cos t| dt: |cos| integrates to 1 over [0, pi/2] and to
    # 1 - sin(4) over [pi/2, 4] (4 < 3 pi / 2)
    expected = 0.5 * (1.0 + (1.0 - math.sin(4.0)))
    assert report.energy_used_j == pytest.approx(expected, rel=1e-3)
    assert report.duration_s == 4.0 and report.peak_heave_torque_n_m == 0.5


def test_table_puts_runs_side_by_side():
    table = summary_table({"with": RunAnalysis(measures(synthetic_run(0.1)), None),
                           "without": RunAnalysis(measures(synthetic_run(0.2)), None)})
    header, *rows = table.splitlines()
    assert header.split() == ["with", "without"]
    row = next(r for r in rows if r.startswith("final_alpha_error_rad"))
    assert [float(v) for v in row.split()[1:]] == pytest.approx([0.1, 0.2])


def test_node_command_is_what_ros2_run_takes():
    spec = NodeSpec("swim_sim", "sim_node", params_file=None, parameters=("seed:=3",),
                    ros_arguments=("-r", "__ns:=/test"))
    assert spec.command() == ["ros2", "run", "swim_sim", "sim_node", "--ros-args", "-p", "seed:=3",
                              "-r", "__ns:=/test"]


def test_a_constrained_run_without_its_plan_is_refused_not_measured_at_radius_zero(tmp_path):
    """The constrained vehicle's lane radius comes only with the plan: a bag that lacks it (a recorder stopped
    before the plan's fragments arrived) must not give two-norms of zero."""
    from swim_bringup.bag import BagWriter
    from swim_bringup.run_record import read_bag
    writer = BagWriter(tmp_path / "bag")
    for k in range(3):
        writer.write("/tracking_state", k + 1,
                     tracking_state_cdr(writer.store, ["alpha", "phi", "theta"], 1_000_000_000 + 8_000_000 * k,
                                        0.008 * k, feedback=[0.01 * k, 0.0, 0.0], reference=[0.0] * 3))
    writer.close()
    record = read_bag(tmp_path / "bag")
    assert record.run is None
    with pytest.raises(ValueError, match="no plan message"):
        raise record.run_error
