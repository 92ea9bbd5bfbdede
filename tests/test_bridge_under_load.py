"""The rig's loop on a busy host: swim-demo --plant bridge flies the paper's lane keeping (23 s) with the shipped
parameter files, so with the real-time means the bridge and the tracker take by default, while one busy process
(`python -c "while True: pass"`, a core's worth) runs beside it. The run must end tracked with no latched fault,
under the shipped limits (the bridge's 3 overruns in a row, the tracker's 200 ms without a state). The bridge's
/diagnostics, read back from the bag, show the means in effect and how the loop kept its period. A stall witness
(swim_ros.testing.stall_witness) runs beside it: a run lost while the host held every process up for longer than
HOST_STALL_BOUND_S is the host's, and skipped with the stall it saw; any other lost run fails."""
import os
import sys

import pytest
from conftest import log_tails, run_demo

pytestmark = pytest.mark.skipif(os.geteuid() != 0, reason="the real-time means need root here (CI runs as root)")

#: the demo's wall-time limit of the maneuver, s (23 s of plan in real time)
MANEUVER_TIMEOUT_S = 120
#: the I/O loop's wake-up lateness at p99 on a 2-core host with one busy process and the real-time means, ms: half
#: the period. With the means it is 0.13-0.63 ms, and 2.65 ms was seen in an hour when the VM stalled the loop for up
#: to 323 ms; without them 6.1-29 ms (docs/realtime.md). The bound tells the two apart; the figure itself is
#: bench_loop_under_load's
WAKE_LATENESS_P99_BOUND_MS = 4.0
#: a stall of the whole host longer than this, s, can lose the run whatever its means: the emulated rig integrates
#: its plant over the stall with the torques held, a disturbance past what the tolerances allow for (the maneuver
#: CLI test's HOST_STALL_BOUND_MS), and from 200 ms on the tracker has no state
HOST_STALL_BOUND_S = 0.1


@pytest.fixture(scope="module")
def run_beside_a_busy_process(ros_domain, tmp_path_factory):
    from swim_ros.processes import start_child
    from swim_ros.testing.stall_witness import StallWitness
    work = tmp_path_factory.mktemp("bridge_under_load")
    busy = start_child([sys.executable, "-c", "while True: pass"])
    try:
        with StallWitness(work) as witness:
            output = run_demo(work / "run", "--plant", "bridge", "--timeout", str(MANEUVER_TIMEOUT_S),
                              expected_returncode=None)
    finally:
        busy.kill()
        busy.wait()
    return work / "run", output, witness


def tracked_or_lost_to_the_host(run_beside_a_busy_process):
    """The run's report, if it was tracked with no fault; the test skipped if it was lost while the host stalled
    (the witness's worst stall past HOST_STALL_BOUND_S); the test failed with the run's output otherwise."""
    from swim_bringup.reports import RunReport
    run_dir, output, witness = run_beside_a_busy_process
    assert (run_dir / "report.json").is_file(), output[-3000:] + log_tails(run_dir / "logs")
    report = RunReport.load(run_dir / "report.json")
    lost = report.result.error_code != 0 or report.bridge is None or report.bridge.bridge_faults != "NONE"
    worst_stall_s = witness.worst_s   # read from the witnesses' files once
    if lost and witness.refused is None and worst_stall_s > HOST_STALL_BOUND_S:
        pytest.skip(f"lost ({report.result.error_string}) while the host held every process up for "
                    f"{worst_stall_s * 1e3:.0f} ms (the stall witness)")
    assert not lost, (f"stall witness: worst {worst_stall_s * 1e3:.0f} ms, {witness.refused or 'means in effect'}"
                      f"\n{output[-3000:]}{log_tails(run_dir / 'logs')}")
    return report


def test_lane_keeping_ends_tracked_with_no_fault_beside_a_busy_process(run_beside_a_busy_process):
    report = tracked_or_lost_to_the_host(run_beside_a_busy_process)
    assert report.result.error_code == 0, report.result.error_string
    assert report.bridge is not None and report.bridge.bridge_faults == "NONE"
    assert report.measures.duration_s == pytest.approx(23.0, abs=0.05)
    assert report.bridge.bridge_wake_lateness_p99_ms <= WAKE_LATENESS_P99_BOUND_MS


def test_the_bridge_reports_its_real_time_means(run_beside_a_busy_process):
    from swim_bringup.bag import read_messages
    tracked_or_lost_to_the_host(run_beside_a_busy_process)
    run_dir, _, _ = run_beside_a_busy_process
    last, last_stamp_ns, last_period_stamp_ns = None, 0, 0
    for topic, _, message in read_messages(run_dir / "bag", ("/diagnostics", "/tracking_state")):
        stamp_ns = message.header.stamp.sec * 1_000_000_000 + message.header.stamp.nanosec
        if topic == "/tracking_state":
            last_period_stamp_ns = max(last_period_stamp_ns, stamp_ns)
            continue
        for status in message.status:
            if status.name.endswith("bridge_node: I/O loop"):
                last, last_stamp_ns = {pair.key: pair.value for pair in status.values}, stamp_ns
    assert last is not None and last["lifecycle_state"] == "active"
    # the report the run's figures come from follows its last tracked period: they cover the whole run
    assert last_stamp_ns >= last_period_stamp_ns > 0
    assert last["io_loop_scheduling"] == "SCHED_FIFO 80" and last["realtime_refused"] == ""
    assert int(last["memory_locked_kib"]) > 0 and last["gc_longest_ms"] != "off"
    assert float(last["gc_longest_ms"]) < 8.0   # a collection fits in a period's slack
    log = (run_dir / "logs" / "bridge_node.log").read_text()
    assert "real-time means in effect: SCHED_FIFO priority 70, memory locked" in log
    tracker_log = (run_dir / "logs" / "tracker_node.log").read_text()
    assert "real-time means in effect: SCHED_FIFO priority 70, memory locked" in tracker_log
