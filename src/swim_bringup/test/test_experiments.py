"""swim-experiments: the paper's experiment list and how our runs are set beside its results."""
import pytest

from swim_bringup.experiments import NORMS, compare, paper_experiments, relative_change, results_table
from swim_bringup.reports import BridgeMeasures, ExperimentsSummary, RunMeasures, RunReport, StoppedRun, TrackerResult
from swim_model import load_rig
from swim_planner.library import PrimitiveLibrary
from swim_planner.paths import default_library_path


def test_the_list_is_the_papers():
    """Sec. 7: constrained at lambda 1, 1.2, 1.67, 0.8; lane keeping at 1, 1.1; lane change at 1, 1.25."""
    scales = {}
    for experiment in paper_experiments():
        scales.setdefault(experiment.name.rsplit("_lambda", 1)[0], []).append(experiment.time_scale)
    assert scales == {"constrained": [1.0, 1.2, 1.67, 0.8], "lane_keeping": [1.0, 1.1], "lane_change": [1.0, 1.25]}


def test_every_experiment_lasts_the_papers_nominal_time():
    """The primitive durations in the shipped library add up to the paper's 30 s, 20 s and 23 s (Sec. 7)."""
    library = PrimitiveLibrary.load(default_library_path(), load_rig())
    for experiment in paper_experiments():
        total = sum(library.spec(i).duration_s * n for i, n in zip(experiment.primitive_ids, experiment.repeat_counts))
        assert total == pytest.approx(experiment.nominal_duration_s), experiment.name
        assert experiment.expected_duration_s() == pytest.approx(total / experiment.time_scale)


def _report(scale: float, offset_m: float, error_code: int = 0, error_string: str = "plan completed",
            bridge_faults: str | None = None) -> RunReport:
    """A run of 25 s whose two-norms are scale, 2 scale and 3 scale m s^0.5."""
    norms = {norm: scale * (i + 1) for i, norm in enumerate(NORMS)}
    measures = RunMeasures(duration_s=25.0, final_lateral_offset_m=offset_m, final_alpha_error_rad=0.01,
                           peak_heave_torque_n_m=1.0, peak_pitch_torque_n_m=0.2, saturated_fraction=0.0,
                           energy_used_j=10.0, sliding_mode_enabled=True, periods=3126, **norms)
    bridge = None if bridge_faults is None else BridgeMeasures(bridge_faults=bridge_faults, bridge_overruns=0)
    return RunReport(measures, bridge, TrackerResult(error_code, error_string, 0.01, 25.0), 10.0)


def test_sliding_modes_change_is_relative_to_the_run_without_it():
    experiment = paper_experiments()[1]      # constrained, lambda = 1.2
    row = compare(experiment, _report(0.9, 0.001), _report(1.0, 0.002))
    for norm in NORMS:
        assert row.two_norms[norm].change == pytest.approx(-0.1)
    assert row.two_norms["longitudinal_error_two_norm_m_s05"].paper_change == -0.12
    assert row.paper_duration_s == pytest.approx(25.0)
    assert row.succeeded
    assert relative_change(1.0, 0.0) is None
    table = results_table([row])
    assert "-10 %; -12 %" in table and "+0.10/+0.20" in table and "| ok/ok |" in table


def test_a_run_the_tracker_aborted_is_not_a_success():
    lost = _report(1.0, 0.3, -4, "path tolerance violated: alpha error 1.2 rad")
    row = compare(paper_experiments()[4], lost, _report(1.0, 0.001))
    assert not row.succeeded
    assert row.outcome.sliding_on == "the tracker ended with path tolerance violated: alpha error 1.2 rad"
    assert row.outcome.sliding_off == "ok"
    faulted = _report(1.0, 0.001, bridge_faults="OVERRUN")
    assert not compare(paper_experiments()[4], faulted, _report(1.0, 0.001, bridge_faults="NONE")).succeeded


def test_whatever_stops_a_run_is_named_and_the_experiments_done_are_kept(tmp_path, monkeypatch, capsys):
    """A run that raises (a node died, a bug) stops swim-experiments with exit 1, the run and the reason on
    stderr and in experiments.json beside the experiments completed before it."""
    import swim_bringup.experiments as experiments
    names = [e.name for e in paper_experiments()[:2]]
    done = []

    def run_one(experiment, sliding_mode, run_dir, *_):
        if len(done) == 3:
            raise RuntimeError("sim_node died (exit -9)")
        done.append((experiment.name, sliding_mode))
        return _report(1.0, 0.001)
    monkeypatch.setattr(experiments, "run_one", run_one)
    assert experiments.main(["--only", *names, "--run-dir", str(tmp_path)]) == 1
    summary = ExperimentsSummary.load(tmp_path / "experiments.json")
    assert [row.experiment for row in summary.experiments] == names[:1]
    assert summary.stopped == StoppedRun(run=f"{names[1]}/sliding_off", reason="RuntimeError: sim_node died (exit -9)")
    assert f"stopped at {names[1]}/sliding_off: RuntimeError: sim_node died" in capsys.readouterr().err
