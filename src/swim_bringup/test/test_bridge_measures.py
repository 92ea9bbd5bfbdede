"""The bridge's measures of a run (analysis.bridge_measures) from /diagnostics written to a real bag (no ROS)."""
from swim_bringup.analysis import bridge_measures
from swim_bringup.bag import BagWriter


def diagnostics_cdr(store, name: str, faults: str, overruns: int, sec: int) -> bytes:
    """A diagnostic_msgs/DiagnosticArray as bridge_node publishes it, serialized by rosbags."""
    types = store.types
    Array, Status, KeyValue = (types[f"diagnostic_msgs/msg/{t}"] for t in ("DiagnosticArray", "DiagnosticStatus",
                                                                            "KeyValue"))
    Header, Time = types["std_msgs/msg/Header"], types["builtin_interfaces/msg/Time"]
    values = [KeyValue(key="faults", value=faults), KeyValue(key="overruns", value=str(overruns))]
    status = Status(level=0, name=f"/{name}: I/O loop", message="", hardware_id="emulated", values=values)
    array = Array(header=Header(stamp=Time(sec=sec, nanosec=0), frame_id=""), status=[status])
    return bytes(store.serialize_cdr(array, "diagnostic_msgs/msg/DiagnosticArray"))


def write_bag(path, statuses):
    bag = BagWriter(path, {"/diagnostics": "diagnostic_msgs/msg/DiagnosticArray"})
    for sec, (name, faults, overruns) in enumerate(statuses, start=1):
        bag.write("/diagnostics", sec * 1_000_000_000, diagnostics_cdr(bag.store, name, faults, overruns, sec))
    bag.close()


def test_faults_latched_at_any_time_are_reported_with_the_last_overrun_count(tmp_path):
    write_bag(tmp_path / "bag", [("bridge_node", "NONE", 0), ("bridge_node", "OVERRUN", 3),
                                 ("other_node", "HARD_LIMIT", 9),              # not a bridge: ignored
                                 ("bridge_node", "HARD_LIMIT|OVERRUN", 4), ("bridge_node", "NONE", 4)])
    assert bridge_measures(tmp_path / "bag") == {"bridge_faults": "HARD_LIMIT|OVERRUN", "bridge_overruns": 4}


def test_a_clean_run_and_a_run_without_a_bridge(tmp_path):
    write_bag(tmp_path / "clean", [("bridge_node", "NONE", 0), ("bridge_node", "NONE", 1)])
    assert bridge_measures(tmp_path / "clean") == {"bridge_faults": "NONE", "bridge_overruns": 1}
    write_bag(tmp_path / "none", [])
    assert bridge_measures(tmp_path / "none") == {}
