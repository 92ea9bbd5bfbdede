"""swim-experiments end to end over DDS at a reduced size: one experiment with and without sliding mode for two
seeds, two runs at once (each in its own process and ROS domain): the runs the flake hunter repeats
(scripts/repeat_tests.sh N tests/test_experiments_run.py). Every run succeeds, experiments.json reads back with
every key, each seed reached its simulator, and the row agrees with the analyses of the four recorded runs."""
import pytest
from conftest import DEMO_TIMEOUT_S, WORKSPACE

from swim_ros.processes import run_child

#: the shortest of the paper's experiments: the constrained maneuver at lambda = 1.67 (30 s / 1.67 = 18 s)
EXPERIMENT = "constrained_lambda1.67"
SEEDS = [1, 2]
#: four swim-demo-sized runs, two at a time: each bring-up, maneuver, recording and analysis
EXPERIMENTS_TIMEOUT_S = 2 * DEMO_TIMEOUT_S


def test_one_experiment_runs_over_two_seeds_two_runs_at_once(ros_domain, tmp_path):
    from swim_bringup.experiments import NORMS, paper_experiments, run_label
    from swim_bringup.reports import ExperimentsSummary, RunReport
    run_dir = tmp_path / "experiments"
    command = (f"source scripts/env.sh && exec ros2 run swim_bringup swim-experiments --only {EXPERIMENT} "
               f"--seeds {len(SEEDS)} --jobs 2 --pipeline paper --run-dir {run_dir}")
    result = run_child(["bash", "-c", command], cwd=WORKSPACE, capture_output=True, text=True,
                       timeout_s=EXPERIMENTS_TIMEOUT_S)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    summary = ExperimentsSummary.load(run_dir / "experiments.json")
    assert summary.failed_runs == [] and summary.seeds == SEEDS and summary.pipeline == "paper"
    assert [row.experiment for row in summary.experiments] == [EXPERIMENT]
    row = summary.experiments[0]
    assert row.succeeded and row.outcome.sliding_on == row.outcome.sliding_off == "ok"
    assert row.paired_seeds == SEEDS
    expected = next(e for e in paper_experiments() if e.name == EXPERIMENT)
    assert row.paper_duration_s == pytest.approx(30.0 / 1.67)
    assert row.duration_s == pytest.approx(expected.expected_duration_s(), rel=0.01)
    runs = {(seed, sliding_mode): RunReport.load(run_dir / run_label(EXPERIMENT, seed, sliding_mode) / "report.json")
            for seed in SEEDS for sliding_mode in (True, False)}
    assert all(runs[seed, on].measures.sliding_mode_enabled == on for seed, on in runs)
    for name in NORMS:
        for sliding_mode, per_seed in ((True, row.per_seed.two_norms[name].sliding_on),
                                       (False, row.per_seed.two_norms[name].sliding_off)):
            assert per_seed == [getattr(runs[seed, sliding_mode].measures, name) for seed in SEEDS]
            assert getattr(row.two_norms[name], "sliding_on" if sliding_mode else "sliding_off") \
                == max(per_seed, key=abs)
    # each seed's disturbances and noise reached its simulator: the seeds' runs differ
    longitudinal = row.per_seed.two_norms["longitudinal_error_two_norm_m_s05"]
    assert longitudinal.sliding_on[0] != longitudinal.sliding_on[1]
    assert row.statistics["longitudinal_error_two_norm_m_s05"].change is not None
    assert (run_dir / "results.md").exists() and (run_dir / "errors.png").stat().st_size > 0
