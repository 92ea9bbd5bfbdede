"""swim-experiments end to end over DDS, one experiment with and without sliding mode: the runs the flake hunter
repeats (scripts/repeat_tests.sh N tests/test_experiments_run.py). Both runs succeed, experiments.json reads back
with every key, and the row agrees with the analyses of the two recorded runs."""
import subprocess

import pytest

from conftest import DEMO_TIMEOUT_S, WORKSPACE

#: the shortest of the paper's experiments: the constrained maneuver at lambda = 1.67 (30 s / 1.67 = 18 s)
EXPERIMENT = "constrained_lambda1.67"
#: two swim-demo-sized runs, each bring-up, maneuver, recording and analysis
EXPERIMENTS_TIMEOUT_S = 2 * DEMO_TIMEOUT_S


def test_one_experiment_runs_with_and_without_sliding_mode(ros_domain, tmp_path):
    from swim_bringup.experiments import paper_experiments
    from swim_bringup.reports import ExperimentsSummary, RunReport
    run_dir = tmp_path / "experiments"
    command = f"source scripts/env.sh && ros2 run swim_bringup swim-experiments --only {EXPERIMENT} --run-dir {run_dir}"
    result = subprocess.run(["bash", "-c", command], cwd=WORKSPACE, capture_output=True, text=True,
                            timeout=EXPERIMENTS_TIMEOUT_S)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    summary = ExperimentsSummary.load(run_dir / "experiments.json")
    assert summary.stopped is None and [row.experiment for row in summary.experiments] == [EXPERIMENT]
    row = summary.experiments[0]
    assert row.succeeded and row.outcome.sliding_on == row.outcome.sliding_off == "ok"
    expected = next(e for e in paper_experiments() if e.name == EXPERIMENT)
    assert row.paper_duration_s == pytest.approx(30.0 / 1.67)
    assert row.duration_s == pytest.approx(expected.expected_duration_s(), rel=0.01)
    reports = sorted(run_dir.rglob("report.json"))
    assert len(reports) == 2, reports
    runs = {RunReport.load(path).measures.sliding_mode_enabled: RunReport.load(path).measures for path in reports}
    assert set(runs) == {True, False}
    for name, comparison in row.two_norms.items():
        assert comparison.sliding_on == getattr(runs[True], name)
        assert comparison.sliding_off == getattr(runs[False], name)
