"""The pure layer under swim-analyze without a bag on disk: a run, the joint motion and the bridge's measures made
from decoded messages (plain objects with the messages' fields), the platform's position and the joint motion's
summary, each against an independent computation; and read_topics' one read, whose errors stay with their topic."""
import math
from types import SimpleNamespace

import numpy as np
import pytest
from conftest import tracking_state_cdr

from swim_bringup.analysis import joint_states_summary, platform_xy_m
from swim_bringup.bag import BagError, BagWriter, read_topics
from swim_bringup.reports import BridgeMeasures
from swim_bringup.run_record import MissingTopic, Run, bridge_measures_of, joint_series, run_of

BAG = "bag"   # the bag path the errors name; nothing is read from it


def tracking_state(plan_time_s, q, q_reference, joint_names=("alpha", "phi", "theta"), torque=(0.0, 0.0),
                   saturated=(False, False), sliding_mode_enabled=True):
    """A swim_interfaces/TrackingState's fields that a run reads."""
    return SimpleNamespace(plan_time_s=plan_time_s, joint_names=list(joint_names),
                           feedback=SimpleNamespace(positions=list(q), velocities=[0.1 * v for v in q]),
                           reference=SimpleNamespace(positions=list(q_reference)), output_torques=list(torque),
                           torque_saturated=list(saturated), sliding_mode_enabled=sliding_mode_enabled)


def test_a_run_is_the_last_plan_tracked_with_the_last_plans_lane():
    first = [tracking_state(t, (t, 0.0, 0.0), (t, 0.0, 0.0)) for t in (0.0, 0.008, 0.016)]
    second = [tracking_state(t, (1.0 + t, 0.2, -0.1), (1.0 + 2 * t, 0.0, 0.0), torque=(0.5, -0.25),
                             saturated=(True, False), sliding_mode_enabled=False) for t in (0.0, 0.008)]
    plans = [SimpleNamespace(lane_radius_m=0.40), SimpleNamespace(lane_radius_m=0.45)]
    run = run_of(BAG, "/tracking_state", first + second, plans)
    np.testing.assert_array_equal(run.time_s, [0.0, 0.008])
    np.testing.assert_array_equal(run.q, [[1.0, 0.2, -0.1], [1.008, 0.2, -0.1]])
    np.testing.assert_array_equal(run.q_reference[:, 0], [1.0, 1.016])
    np.testing.assert_allclose(run.qdot, 0.1 * run.q)
    np.testing.assert_array_equal(run.torque, [[0.5, -0.25]] * 2)
    assert run.saturated.dtype == bool and run.saturated.tolist() == [[True, False]] * 2
    assert run.lane_radius_m == 0.45 and not run.sliding_mode_enabled
    assert run.joint_names == ["alpha", "phi", "theta"]


def test_what_does_not_make_a_run_is_named():
    with pytest.raises(MissingTopic, match="no message of /ns/tracking_state could be read"):
        run_of(BAG, "/ns/tracking_state", [], [])
    no_alpha = [tracking_state(0.0, (0.0, 0.0), (0.0, 0.0), joint_names=("phi", "theta"))]
    with pytest.raises(MissingTopic, match="have no alpha"):
        run_of(BAG, "/tracking_state", no_alpha, [SimpleNamespace(lane_radius_m=0.43)])
    constrained = [tracking_state(0.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))]
    with pytest.raises(MissingTopic, match=r"no plan message \(not in the bag\)") as missing:
        run_of(BAG, "/tracking_state", constrained, [], "not in the bag")
    assert missing.value.topic == "/plan"
    free = [tracking_state(0.0, (0.0, 0.43, 0.0, 0.0), (0.0, 0.43, 0.0, 0.0), ("alpha", "R", "phi", "theta"))]
    assert run_of(BAG, "/tracking_state", free, []).lane_radius_m == 0.0   # R is a joint: no plan needed


def test_the_platforms_position_has_the_runs_radius_and_alpha():
    alpha = np.linspace(-3.0, 3.0, 7)
    radius = np.linspace(0.40, 0.48, 7)
    q = np.column_stack([alpha, radius, np.zeros(7), np.zeros(7)])
    free = Run(np.arange(7.0), q, q, q, np.zeros((7, 2)), np.zeros((7, 2), bool), ["alpha", "R", "phi", "theta"],
               0.0, True)
    xy = platform_xy_m(free, q)
    np.testing.assert_allclose(np.hypot(xy[:, 0], xy[:, 1]), radius)
    np.testing.assert_allclose(np.arctan2(xy[:, 1], xy[:, 0]), alpha)
    constrained = Run(free.time_s, q[:, [0, 2, 3]], q[:, [0, 2, 3]], q[:, [0, 2, 3]], free.torque, free.saturated,
                      ["alpha", "phi", "theta"], 0.43, True)
    np.testing.assert_allclose(np.hypot(*platform_xy_m(constrained, constrained.q).T), 0.43)


def joint_state(names, positions, velocities=()):
    return SimpleNamespace(name=list(names), position=list(positions), velocity=list(velocities))


def test_joint_motion_from_messages_with_short_lists():
    """R's position is missing from the second message and phi's velocity from the last: R has two samples, phi
    no velocities (a joint's velocities are kept only when every sample has one)."""
    start_ns = 5_000_000_000
    messages = [(start_ns, joint_state(["alpha", "R", "phi"], [0.0, 0.43, 0.1], [1.0, 0.0, -2.0])),
                (start_ns + 8_000_000, joint_state(["alpha", "R", "phi"], [0.01, ], [1.0])),
                (start_ns + 40_000_000, joint_state(["alpha", "R", "phi"], [0.02, 0.44, -0.3], [-3.0, 0.1]))]
    states = joint_series("/joint_states", messages)
    np.testing.assert_allclose(states.message_time_s, [0.0, 0.008, 0.040])
    assert list(states.joints) == ["alpha", "R", "phi"]
    np.testing.assert_allclose(states.joints["R"].time_s, [0.0, 0.040])
    np.testing.assert_array_equal(states.joints["R"].position, [0.43, 0.44])
    assert len(states.joints["phi"].velocity) == 0 and len(states.joints["R"].velocity) == 2
    summary = joint_states_summary(states)
    assert summary.messages == 3 and summary.duration_s == pytest.approx(0.040)
    assert summary.mean_rate_hz == pytest.approx(2 / 0.040) and summary.longest_gap_s == pytest.approx(0.032)
    alpha, r, phi = summary.joints
    assert (alpha.samples, alpha.min_position, alpha.max_position, alpha.peak_speed) == (3, 0.0, 0.02, 3.0)
    assert (r.samples, r.peak_speed) == (2, 0.1)
    assert (phi.min_position, phi.max_position, phi.peak_speed) == (-0.3, 0.1, None)


def diagnostic_array(name, values):
    return SimpleNamespace(status=[SimpleNamespace(name=name, values=[SimpleNamespace(key=k, value=v)
                                                                      for k, v in values.items()])])


def test_the_bridges_measures_from_its_reports():
    timing = {"worst_lateness_ms": "2.5", "worst_lateness_cause": "SLOW_WRITE", "wake_lateness_p99_ms": "inf",
              "command_latency_p50_ms": "1.5", "command_latency_p99_ms": "x"}
    arrays = [diagnostic_array("/bridge_node: I/O loop", {"faults": "NONE", "overruns": "0"}),
              diagnostic_array("/bridge_node: watchdog", {"faults": "WATCHDOG", "overruns": "7"}),   # not the loop
              diagnostic_array("/bridge_node: I/O loop", {"faults": "OVERRUN|HARD_LIMIT", "overruns": "2", **timing}),
              diagnostic_array("/bridge_node: I/O loop", {"faults": "NONE"})]   # no count: the last one stays
    assert bridge_measures_of(arrays) == BridgeMeasures(
        bridge_faults="HARD_LIMIT|OVERRUN", bridge_overruns=2, bridge_worst_lateness_ms=2.5,
        bridge_overrun_cause="SLOW_WRITE", bridge_wake_lateness_p99_ms=None, bridge_command_latency_p50_ms=1.5)
    assert bridge_measures_of(arrays[1:2]) is None and bridge_measures_of([]) is None


def test_one_read_keeps_each_topics_error_with_it(tmp_path):
    """A topic whose bytes do not decode gets its BagError; the others read in full, in log-time order."""
    writer = BagWriter(tmp_path / "bag")
    for k in range(4):
        writer.write("/tracking_state", 10 + 2 * k,
                     tracking_state_cdr(writer.store, ["alpha", "phi", "theta"], 0, 0.008 * k,
                                        feedback=[0.1 * k, 0.0, 0.0], reference=[0.0] * 3))
        writer.write("/diagnostics", 11 + 2 * k, b"\x00\x01\x00\x00\xff")   # a CDR header, then nothing valid
    writer.close()
    read = read_topics(tmp_path / "bag", ("/tracking_state", "/diagnostics", "/joint_states"))
    assert isinstance(read["/diagnostics"], BagError) and "does not decode" in str(read["/diagnostics"])
    assert read["/joint_states"] == []
    tracking = read["/tracking_state"]
    assert [stamp for stamp, _ in tracking] == [10, 12, 14, 16]
    assert [message.feedback.positions[0] for _, message in tracking] == pytest.approx([0.0, 0.1, 0.2, 0.3])
    assert math.isclose(tracking[-1][1].plan_time_s, 0.024)
