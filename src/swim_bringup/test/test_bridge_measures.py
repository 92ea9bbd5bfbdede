"""The bridge's measures of a run (run_record.read_bag, its bridge) from /diagnostics written to a real bag (no ROS)."""
from conftest import diagnostics_cdr

from swim_bringup.bag import BagWriter
from swim_bringup.reports import BridgeMeasures
from swim_bringup.run_record import read_bag


def bridge_measures(bag_path):
    return read_bag(bag_path).bridge


def write_bag(path, statuses):
    bag = BagWriter(path, {"/diagnostics": "diagnostic_msgs/msg/DiagnosticArray"})
    for sec, (name, faults, overruns) in enumerate(statuses, start=1):
        bag.write("/diagnostics", sec * 1_000_000_000, diagnostics_cdr(bag.store, name, faults, overruns, sec))
    bag.close()


def test_faults_latched_at_any_time_are_reported_with_the_last_overrun_count(tmp_path):
    write_bag(tmp_path / "bag", [("bridge_node", "NONE", 0), ("bridge_node", "OVERRUN", 3),
                                 ("other_node", "HARD_LIMIT", 9),              # not a bridge: ignored
                                 ("bridge_node", "HARD_LIMIT|OVERRUN", 4), ("bridge_node", "NONE", 4)])
    assert bridge_measures(tmp_path / "bag") == BridgeMeasures(bridge_faults="HARD_LIMIT|OVERRUN", bridge_overruns=4)


def test_a_clean_run_and_a_run_without_a_bridge(tmp_path):
    write_bag(tmp_path / "clean", [("bridge_node", "NONE", 0), ("bridge_node", "NONE", 1)])
    assert bridge_measures(tmp_path / "clean") == BridgeMeasures(bridge_faults="NONE", bridge_overruns=1)
    write_bag(tmp_path / "none", [])
    assert bridge_measures(tmp_path / "none") is None


def test_the_loops_timing_is_its_last_report(tmp_path):
    """The timing keys of the bridge's last status that has them; "nan" (an empty histogram) reads as None."""
    bag = BagWriter(tmp_path / "bag", {"/diagnostics": "diagnostic_msgs/msg/DiagnosticArray"})
    first = {"worst_lateness_ms": "1.000", "worst_lateness_cause": "SLOW_READ", "wake_lateness_p99_ms": "0.1",
             "command_latency_p50_ms": "2.0", "command_latency_p99_ms": "3.0", "command_jitter_p50_ms": "0.1",
             "command_jitter_p99_ms": "0.9", "state_interval_max_ms": "8.5", "state_publish_max_ms": "0.2"}
    last = {**first, "worst_lateness_ms": "12.500", "worst_lateness_cause": "LATE_WAKEUP",
            "command_jitter_p99_ms": "nan", "state_interval_max_ms": "331.000"}
    for sec, timing in enumerate((first, last, None), start=1):   # the last status: a bridge without timing
        bag.write("/diagnostics", sec * 1_000_000_000,
                  diagnostics_cdr(bag.store, "bridge_node", "NONE", 1, sec, timing))
    bag.close()
    assert bridge_measures(tmp_path / "bag") == BridgeMeasures(
        bridge_faults="NONE", bridge_overruns=1, bridge_worst_lateness_ms=12.5, bridge_overrun_cause="LATE_WAKEUP",
        bridge_wake_lateness_p99_ms=0.1, bridge_command_latency_p50_ms=2.0, bridge_command_latency_p99_ms=3.0,
        bridge_command_jitter_p50_ms=0.1, bridge_command_jitter_p99_ms=None, bridge_state_interval_max_ms=331.0,
        bridge_state_publish_max_ms=0.2)
