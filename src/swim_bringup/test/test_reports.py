"""The typed reports keep the JSON forms of report.json and experiments.json: every key, its nesting and order, for
reports made by the real analysis of recorded bags (no ROS); and a JSON object that is not a report is refused."""
import json
import math

import pytest
from conftest import diagnostics_cdr, tracking_state_cdr

from swim_bringup.analysis import analyze
from swim_bringup.bag import BagWriter
from swim_bringup.experiments import compare, paper_experiments
from swim_bringup.reports import (
    ExperimentsSummary,
    FailedRun,
    ReportError,
    RunAnalysis,
    RunReport,
    SlidingModePair,
    TrackerResult,
    run_failures,
)

#: report.json's keys, in order, as swim-demo writes them (the file's readers and the docs rely on them)
MEASURE_KEYS = ["duration_s", "longitudinal_error_two_norm_m_s05", "lateral_error_two_norm_m_s05",
                "cartesian_error_two_norm_m_s05", "final_alpha_error_rad", "final_lateral_offset_m",
                "peak_heave_torque_n_m", "peak_pitch_torque_n_m", "saturated_fraction", "hard_stop_periods",
                "energy_used_j", "sliding_mode_enabled", "periods"]
BRIDGE_KEYS = ["bridge_faults", "bridge_overruns", "bridge_worst_lateness_ms", "bridge_overrun_cause",
               "bridge_wake_lateness_p99_ms", "bridge_command_latency_p50_ms", "bridge_command_latency_p99_ms",
               "bridge_command_jitter_p50_ms", "bridge_command_jitter_p99_ms", "bridge_state_interval_max_ms",
               "bridge_state_publish_max_ms"]
RESULT_KEYS = ["error_code", "error_string", "final_alpha_error_rad", "duration_s"]
#: experiments.json's keys: a row (the keys of one seed's row, then the seeds'), its pairs of runs, its two-norm
#: comparisons, its runs by seed and its statistics
ROW_KEYS = ["experiment", "time_scale", "duration_s", "paper_duration_s", "final_lateral_offset_m",
            "final_alpha_error_rad", "saturated_fraction", "hard_stop_periods", "two_norms", "succeeded", "outcome",
            "per_seed", "paired_seeds", "statistics"]
PAIR_KEYS = ["sliding_on", "sliding_off"]
NORM_KEYS = ["sliding_on", "sliding_off", "change", "paper_change"]
SEED_KEYS = ["seeds", "outcome", "duration_s", "final_lateral_offset_m", "final_alpha_error_rad",
             "saturated_fraction", "hard_stop_periods", "two_norms"]
STATISTICS_KEYS = ["sliding_on", "sliding_off", "change", "paper_change"]
SPREAD_KEYS = ["mean", "std"]
CHANGE_KEYS = ["per_seed", "mean", "interval", "excludes_zero"]
NORMS = ["longitudinal_error_two_norm_m_s05", "lateral_error_two_norm_m_s05", "cartesian_error_two_norm_m_s05"]
PERIOD_S, PERIODS = 0.008, 251                 # 2 s of tracking
LANE_M, OFFSET_M = 0.43, 0.01


def record_free_run(path, bridge_faults=None):
    """A bag of the free vehicle held OFFSET_M outside its lane for 2 s, and bridge_node's /diagnostics if
    bridge_faults is given."""
    writer = BagWriter(path)
    for k in range(PERIODS):
        time_s = k * PERIOD_S
        reference = [0.3 * time_s, LANE_M, math.sin(time_s), math.cos(time_s)]
        feedback = [reference[0], LANE_M + OFFSET_M, *reference[2:]]
        writer.write("/tracking_state", k + 1,
                     tracking_state_cdr(writer.store, ["alpha", "R", "phi", "theta"], 1_000_000_000 + 8_000_000 * k,
                                        time_s, feedback, reference, output_torques=(0.5, 0.0)))
    if bridge_faults is not None:
        writer.write("/diagnostics", PERIODS + 1, diagnostics_cdr(writer.store, "bridge_node", bridge_faults, 2, 3))
    writer.close()
    return path


def report_of(bag, error_code=0, error_string="succeeded"):
    analysis = analyze(bag)
    return RunReport(analysis.measures, analysis.bridge, TrackerResult(error_code, error_string, 0.0, 2.0), 9.5)


def test_report_json_keeps_its_keys_and_reads_back(tmp_path):
    report = report_of(record_free_run(tmp_path / "bag"))
    # the analysis measured the bag: a constant lateral offset e over T has the two-norm e sqrt(T)
    assert report.measures.lateral_error_two_norm_m_s05 == pytest.approx(OFFSET_M * math.sqrt(2.0))
    assert report.measures.periods == PERIODS and report.bridge is None
    data = json.loads(json.dumps(report.to_json()))
    assert list(data) == MEASURE_KEYS + ["result", "wall_time_s"]
    assert list(data["result"]) == RESULT_KEYS
    report.write(tmp_path / "report.json")
    assert RunReport.load(tmp_path / "report.json") == report
    assert list(RunAnalysis(report.measures, report.bridge).to_json()) == MEASURE_KEYS   # swim-analyze --output


def test_a_run_on_the_bridge_adds_the_bridges_keys(tmp_path):
    report = report_of(record_free_run(tmp_path / "bag", bridge_faults="OVERRUN"))
    data = report.to_json()
    assert list(data) == MEASURE_KEYS + BRIDGE_KEYS + ["result", "wall_time_s"]
    assert (data["bridge_faults"], data["bridge_overruns"]) == ("OVERRUN", 2)
    assert RunReport.from_json(data) == report
    assert run_failures(report) == ["the bridge latched OVERRUN: the motors were off from then on"]
    # a report from a bridge that did not report its loop's timing reads back without those keys
    older = {key: value for key, value in data.items() if key in ("bridge_faults", "bridge_overruns")
             or not key.startswith("bridge_")}
    assert RunReport.from_json(older) == report


def test_an_object_that_is_not_a_report_is_refused(tmp_path):
    data = report_of(record_free_run(tmp_path / "bag")).to_json()
    missing = {key: value for key, value in data.items() if key != "periods"}
    with pytest.raises(ReportError, match=r"missing \['periods'\], unexpected \[\]"):
        RunReport.from_json(missing)
    with pytest.raises(ReportError, match=r"unexpected \['speed'\]"):
        RunReport.from_json({**data, "speed": 1.0})
    with pytest.raises(ReportError, match="tracker result"):
        RunReport.from_json({**data, "result": {"error_code": 0}})


def test_experiments_json_keeps_its_keys_and_reads_back(tmp_path):
    """compare() of analysed runs over two seeds, one run without a report, written as swim-experiments writes
    experiments.json."""
    on = report_of(record_free_run(tmp_path / "on"))
    off = report_of(record_free_run(tmp_path / "off", bridge_faults="NONE"), -4, "path tolerance violated")
    failed = FailedRun("lane_keeping_lambda1.10/seed3/sliding_on", "RuntimeError: x")
    row = compare(paper_experiments()[4], {1: SlidingModePair(on, off), 2: SlidingModePair(on, on),
                                           3: SlidingModePair(failed, on)})
    summary = ExperimentsSummary("paper", [1, 2, 3], [row], 20.0, [failed])
    summary.write(tmp_path / "experiments.json")
    data = json.loads((tmp_path / "experiments.json").read_text())
    assert list(data) == ["pipeline", "seeds", "experiments", "wall_time_s", "failed_runs"]
    assert [list(failure) for failure in data["failed_runs"]] == [["run", "reason"]]
    (written,) = data["experiments"]
    assert list(written) == ROW_KEYS
    for key in ("final_lateral_offset_m", "final_alpha_error_rad", "saturated_fraction", "hard_stop_periods",
                "outcome"):
        assert list(written[key]) == PAIR_KEYS, key
        assert list(written["per_seed"][key]) == PAIR_KEYS, key
    assert list(written["two_norms"]) == NORMS and list(written["statistics"]) == NORMS
    assert list(written["per_seed"]) == SEED_KEYS and list(written["per_seed"]["two_norms"]) == NORMS
    for comparison in written["two_norms"].values():
        assert list(comparison) == NORM_KEYS
    for statistics in written["statistics"].values():
        assert list(statistics) == STATISTICS_KEYS
        assert list(statistics["sliding_on"]) == list(statistics["sliding_off"]) == SPREAD_KEYS
    # the bag's vehicle is on its plan along the lane: a zero longitudinal two-norm has no relative change
    assert written["statistics"][NORMS[0]]["change"] is None
    for name in NORMS[1:]:
        assert list(written["statistics"][name]["change"]) == CHANGE_KEYS
    assert written["outcome"] == {"sliding_on": "seed 3: no report: RuntimeError: x",
                                  "sliding_off": "seed 1: the tracker ended with path tolerance violated"}
    assert written["paired_seeds"] == [1, 2]
    lateral = written["statistics"]["lateral_error_two_norm_m_s05"]
    assert lateral["change"]["per_seed"] == [0.0, 0.0]        # the same bag's offset, with and without
    assert lateral["change"]["interval"] == [0.0, 0.0] and not lateral["change"]["excludes_zero"]
    assert written["two_norms"]["lateral_error_two_norm_m_s05"]["change"] == 0.0
    offsets = written["per_seed"]["final_lateral_offset_m"]["sliding_on"]
    assert offsets[:2] == pytest.approx([OFFSET_M, OFFSET_M]) and offsets[2] is None
    assert ExperimentsSummary.load(tmp_path / "experiments.json") == summary
    with pytest.raises(ReportError, match="missing \\['failed_runs'\\]"):
        ExperimentsSummary.from_json({key: value for key, value in data.items() if key != "failed_runs"})
