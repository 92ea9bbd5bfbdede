"""swim-experiments: the paper's experiment list, how our runs over seeds are set beside its results (the seed
value of largest magnitude, the outcome over every seed, the statistics), and the whole command with stand-in
runs in real processes (no DDS): every run's seed and sliding mode reach it, a failed run is named and the others
kept."""
import json

import pytest

from swim_bringup.experiments import NORMS, compare, paper_experiments, results_table, run_label
from swim_bringup.experiments_cli import RunTask
from swim_bringup.reports import (
    BridgeMeasures,
    ExperimentsSummary,
    FailedRun,
    RunMeasures,
    RunReport,
    SlidingModePair,
    TrackerResult,
)
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
            bridge_faults: str | None = None, hard_stop_periods: int = 0) -> RunReport:
    """A run of 25 s whose two-norms are scale, 2 scale and 3 scale m s^0.5, ending offset_m off its lane."""
    norms = {norm: scale * (i + 1) for i, norm in enumerate(NORMS)}
    measures = RunMeasures(duration_s=25.0, final_lateral_offset_m=offset_m, final_alpha_error_rad=0.01,
                           peak_heave_torque_n_m=1.0, peak_pitch_torque_n_m=0.2, saturated_fraction=0.0,
                           hard_stop_periods=hard_stop_periods, energy_used_j=10.0, sliding_mode_enabled=True,
                           periods=3126, **norms)
    bridge = None if bridge_faults is None else BridgeMeasures(bridge_faults=bridge_faults, bridge_overruns=0)
    return RunReport(measures, bridge, TrackerResult(error_code, error_string, 0.01, 25.0), 10.0)


def _pair(on, off):
    return SlidingModePair(on, off)


def test_sliding_modes_change_is_relative_to_the_run_without_it_seed_by_seed():
    """Seed k's change is (on_k - off_k) / off_k; the row's change is their mean; the pair of two-norms is the
    seed value of largest magnitude."""
    experiment = paper_experiments()[1]      # constrained, lambda = 1.2
    scales = {1: (0.9, 1.0), 2: (1.9, 2.0), 3: (2.4, 3.0)}     # -10 %, -5 %, -20 %
    row = compare(experiment, {seed: _pair(_report(on, 0.001), _report(off, 0.002))
                               for seed, (on, off) in scales.items()})
    assert row is not None and row.succeeded and row.paired_seeds == [1, 2, 3]
    expected = [-0.10, -0.05, -0.20]
    for i, norm in enumerate(NORMS):
        statistics = row.statistics[norm]
        assert statistics.change.per_seed == pytest.approx(expected)
        assert row.two_norms[norm].change == pytest.approx(sum(expected) / 3)
        assert row.two_norms[norm].sliding_on == pytest.approx(2.4 * (i + 1))
        assert row.two_norms[norm].sliding_off == pytest.approx(3.0 * (i + 1))
        assert statistics.sliding_off.mean == pytest.approx(2.0 * (i + 1))
    assert row.two_norms["longitudinal_error_two_norm_m_s05"].paper_change == -0.12
    assert row.statistics["longitudinal_error_two_norm_m_s05"].paper_change == -0.12
    assert row.paper_duration_s == pytest.approx(25.0)
    table = results_table([row], "paper")
    assert "## Pipeline paper: seeds 1, 2, 3" in table and "| ok/ok |" in table and "+0.10/+0.20" in table
    assert "-10 %, -5 %, -20 %" in table and "| -12 % |" in table


def test_each_value_is_the_seeds_of_largest_magnitude_with_its_sign():
    experiment = paper_experiments()[4]      # lane keeping, lambda = 1
    offsets = {1: (0.002, -0.001), 2: (-0.004, 0.003), 3: (0.001, -0.005)}
    row = compare(experiment, {seed: _pair(_report(1.0, on), _report(1.0, off)) for seed, (on, off) in offsets.items()})
    assert row.final_lateral_offset_m == SlidingModePair(-0.004, -0.005)
    assert row.per_seed.final_lateral_offset_m == SlidingModePair([0.002, -0.004, 0.001], [-0.001, 0.003, -0.005])
    assert row.per_seed.seeds == [1, 2, 3]


def test_the_hard_stop_periods_are_the_seeds_most_and_shown():
    experiment = paper_experiments()[0]
    stops = {1: (0, 12), 2: (3, 0), 3: (0, 0)}
    row = compare(experiment, {seed: _pair(_report(1.0, 0.0, hard_stop_periods=on),
                                           _report(1.0, 0.0, hard_stop_periods=off))
                               for seed, (on, off) in stops.items()})
    assert row.hard_stop_periods == SlidingModePair(3, 12)
    assert row.per_seed.hard_stop_periods == SlidingModePair([0, 3, 0], [12, 0, 0])
    header, _, line = results_table([row], "paper").splitlines()[2:5]
    assert header.endswith("| periods at a hard stop, most (on/off) |") and line.endswith("| 3/12 |")


def test_the_outcome_is_ok_only_when_every_seeds_is():
    experiment = paper_experiments()[4]
    lost = _report(1.0, 0.3, -4, "path tolerance violated: alpha error 1.2 rad")
    row = compare(experiment, {1: _pair(_report(1.0, 0.001), _report(1.0, 0.001)),
                               2: _pair(lost, _report(1.0, 0.001)),
                               3: _pair(_report(1.0, 0.001), _report(1.0, 0.001, bridge_faults="OVERRUN"))})
    assert not row.succeeded
    assert row.outcome.sliding_on == "seed 2: the tracker ended with path tolerance violated: alpha error 1.2 rad"
    assert row.outcome.sliding_off == "seed 3: the bridge latched OVERRUN: the motors were off from then on"
    assert row.per_seed.outcome.sliding_on[0] == "ok" and row.paired_seeds == [1, 2, 3]
    assert compare(experiment, {1: _pair(_report(1.0, 0.001), _report(1.0, 0.001, bridge_faults="NONE"))}).succeeded


def test_a_seed_without_a_report_is_named_and_left_out_of_the_pairs():
    experiment = paper_experiments()[0]
    failed = FailedRun(run_label(experiment.name, 2, False), "RunError: sim_node died")
    row = compare(experiment, {1: _pair(_report(0.9, 0.0), _report(1.0, 0.0)),
                               2: _pair(_report(5.0, 0.0), failed),
                               3: _pair(_report(1.6, 0.0), _report(2.0, 0.0))})
    assert row.paired_seeds == [1, 3] and not row.succeeded
    assert row.outcome == SlidingModePair("ok", "seed 2: no report: RunError: sim_node died")
    assert row.per_seed.two_norms[NORMS[0]] == SlidingModePair([0.9, 5.0, 1.6], [1.0, None, 2.0])
    assert row.statistics[NORMS[0]].change.per_seed == pytest.approx([-0.1, -0.2])
    assert row.two_norms[NORMS[0]].sliding_on == 5.0        # the largest of the runs reported
    assert compare(experiment, {1: _pair(failed, _report(1.0, 0.0))}) is None   # no pair: no row


def fake_run(task: RunTask) -> RunReport:
    """A stand-in run in its own process: two-norms seed + (0.5 without sliding mode), ending 1 mm x seed off its
    lane; lane_keeping_lambda1.00's seed 2 without sliding mode dies."""
    if task.experiment.name == "lane_keeping_lambda1.00" and task.seed == 2 and not task.sliding_mode:
        raise RuntimeError("sim_node died (exit -9)")
    assert task.run_dir.name == f"sliding_{'on' if task.sliding_mode else 'off'}"
    return _report(task.seed + (0.0 if task.sliding_mode else 0.5), 0.001 * task.seed)


def test_whatever_stops_a_run_is_named_and_the_others_are_kept(tmp_path, monkeypatch, capsys):
    """A run that raises (a node died, a bug) is named on stderr and in experiments.json's failed_runs; every
    other run is in the experiment's row, with its seed and sliding mode; exit 1."""
    import swim_bringup.experiments_cli as cli
    monkeypatch.setattr(cli, "run_one", fake_run)
    assert cli.main(["--only", "lane_keeping_lambda1.00", "--seeds", "2", "--jobs", "2", "--pipeline", "paper",
                     "--config", str(tmp_path), "--run-dir", str(tmp_path / "out")]) == 1
    summary = ExperimentsSummary.load(tmp_path / "out" / "experiments.json")
    assert (summary.pipeline, summary.seeds) == ("paper", [1, 2])
    assert summary.failed_runs == [FailedRun("lane_keeping_lambda1.00/seed2/sliding_off",
                                             "RuntimeError: sim_node died (exit -9)")]
    assert "lane_keeping_lambda1.00/seed2/sliding_off gave no report: RuntimeError: sim_node died" \
        in capsys.readouterr().err
    (row,) = summary.experiments
    assert row.experiment == "lane_keeping_lambda1.00" and not row.succeeded
    assert row.per_seed.two_norms[NORMS[0]] == SlidingModePair([1.0, 2.0], [1.5, None])
    assert row.final_lateral_offset_m == SlidingModePair(0.002, 0.001)
    assert row.paired_seeds == [1] and row.outcome.sliding_off.startswith("seed 2: no report")
    assert row.outcome.sliding_on == "ok"
    assert (tmp_path / "out" / "results.md").read_text().startswith("## Pipeline paper")
    assert (tmp_path / "out" / "errors.png").stat().st_size > 0
    data = json.loads((tmp_path / "out" / "experiments.json").read_text())
    assert list(data) == ["pipeline", "seeds", "experiments", "wall_time_s", "failed_runs"]


@pytest.mark.parametrize("arguments, message", [(["--seeds", "0"], "--seeds must be at least 1"),
                                                (["--jobs", "0"], "--jobs must be at least 1"),
                                                (["--pipeline", "wet"], "invalid choice: 'wet'")])
def test_bad_options_are_refused_before_anything_runs(tmp_path, capsys, arguments, message):
    from swim_bringup.experiments_cli import main
    with pytest.raises(SystemExit) as stopped:
        main([*arguments, "--run-dir", str(tmp_path / "out")])
    assert stopped.value.code == 2 and message in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
