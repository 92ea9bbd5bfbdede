"""The bridge's measures of a run (analysis.bridge_measures) from /diagnostics written to a real bag (no ROS)."""
from conftest import diagnostics_cdr

from swim_bringup.analysis import bridge_measures
from swim_bringup.bag import BagWriter
from swim_bringup.reports import BridgeMeasures


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
