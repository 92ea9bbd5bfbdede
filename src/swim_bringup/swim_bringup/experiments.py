"""swim-experiments: the paper's experiments in closed loop over DDS, in simulation, over seeds
(Sec. 7; docs/model_and_method.md section 6).

Every experiment runs with and without the sliding-mode term for each seed 1..N (sim_node's ``seed``: its
disturbances' and sensors' noise), each run in a fresh bring-up (sim_node in lock-step, planner_node,
tracker_node) with the parameter files of a pipeline (system.config_dir: "realistic", the physical plant, or
"paper", the paper's ideal flow), recorded and analysed like the demo. Runs go side by side, each in a process
and ROS domain of its own (swim_bringup.parallel), on this host or a Dask cluster. Experiments:

- constrained {accelerate1, cruise1 x2, cruise-to-cruise(1,2), cruise2 x2, decelerate2}, lambda 1, 1.2, 1.67, 0.8
  (Sec. 7.1: 30 s nominal);
- free lane keeping {accelerate, 14 x cruise, decelerate} at R = 0.43 m, lambda 1 and 1.1 (Sec. 7.2: 20 s);
- free lane change {accelerate, 5 x cruise, lane change 0.43 -> 0.48 m, 10 x cruise, decelerate}, lambda 1 and
  1.25 (Sec. 7.3: 23 s).

The results (experiments.json, results.md, errors.png) set our numbers beside the paper's: the scaled maneuver's
duration (nominal / lambda), the final lane offset (paper: within 0.5 cm), and the change in the error two-norms
that sliding mode brings (paper: 5-14 % lower) with its paired 95 % interval over the seeds (statistics.py).
"""
from __future__ import annotations

import argparse
import concurrent.futures
import dataclasses
import datetime
import os
import sys
import time
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence, Union

from swim_bringup.parallel import Outcome, run_all
from swim_bringup.recorded_run import (PAPER_CONSTRAINED, PAPER_LANE_KEEPING, RUN_TOLERANCES,
                                       parse_with_tolerances, run_failures, run_recorded)
from swim_bringup.reports import (ExperimentRow, ExperimentsSummary, FailedRun, NormComparison, RunReport, SeedRuns,
                                  SlidingModePair)
from swim_bringup.run_client import DRAIN_TIMEOUT_S, STARTUP_TIMEOUT_S
from swim_bringup.statistics import NormStatistics, PairedChange, largest_magnitude
from swim_bringup.system import PIPELINES, closed_loop_specs, config_dir
from swim_controller.supervisor import Tolerances
from swim_ros.processes import STOP_GRACE_S, interrupt_on_sigterm

NORMS = ("longitudinal_error_two_norm_m_s05", "lateral_error_two_norm_m_s05", "cartesian_error_two_norm_m_s05")
#: the paper's lane change (Sec. 7.3) at E = 0.05: accelerate, 5 cruises in lane 1, the change, 10 in lane 2, stop
PAPER_LANE_CHANGE = (["free/accelerate/R0.43/E0.05", "free/cruise/R0.43/E0.05", "free/lane_change/R0.43-R0.48/E0.05",
                      "free/cruise/R0.48/E0.05", "free/decelerate/R0.48/E0.05"], [1, 5, 1, 10, 1])


@dataclasses.dataclass(frozen=True)
class Experiment:
    name: str
    primitive_ids: tuple[str, ...]
    repeat_counts: tuple[int, ...]
    time_scale: float
    constrained: bool
    nominal_duration_s: float                     # the paper's duration at lambda = 1 (Sec. 7)
    paper_sliding_change: dict[str, float]        # the paper's relative change of a two-norm with sliding mode

    def expected_duration_s(self) -> float:
        """Time scaling by lambda (Sec. 4.3): the maneuver takes nominal / lambda."""
        return self.nominal_duration_s / self.time_scale


def paper_experiments() -> list[Experiment]:
    """The experiments of Sec. 7 with the changes sliding mode brought there (docs/model_and_method.md section 6)."""
    constrained = {1.0: {"longitudinal_error_two_norm_m_s05": -0.14},      # Sec. 7.1, nominal: ~14 % lower
                   1.2: {"longitudinal_error_two_norm_m_s05": -0.12}}      # lambda = 1.2: ~12 % lower
    keeping = {1.0: {"cartesian_error_two_norm_m_s05": -0.12, "longitudinal_error_two_norm_m_s05": -0.12,
                     "lateral_error_two_norm_m_s05": -0.05},               # Sec. 7.2
               1.1: {"cartesian_error_two_norm_m_s05": -0.10, "lateral_error_two_norm_m_s05": -0.10}}
    experiments = [Experiment(f"constrained_lambda{scale:.2f}", tuple(PAPER_CONSTRAINED[0]),
                              tuple(PAPER_CONSTRAINED[1]), scale, True, 30.0, constrained.get(scale, {}))
                   for scale in (1.0, 1.2, 1.67, 0.8)]
    experiments += [Experiment(f"lane_keeping_lambda{scale:.2f}", tuple(PAPER_LANE_KEEPING[0]),
                               tuple(PAPER_LANE_KEEPING[1]), scale, False, 20.0, keeping[scale])
                    for scale in (1.0, 1.1)]
    experiments += [Experiment(f"lane_change_lambda{scale:.2f}", tuple(PAPER_LANE_CHANGE[0]),
                               tuple(PAPER_LANE_CHANGE[1]), scale, False, 23.0, {})
                    for scale in (1.0, 1.25)]
    return experiments


#: cores one run keeps busy (assumed): the lock-step loop's sim_node and tracker_node take turns on about one, the
#: run's client (recording, then analysis and figures) and the visualization nodes about another
CORES_PER_RUN = 2.0
#: a run's process, beyond its maneuver's --timeout: the bring-up, the bag's drain, the nodes' stop and the
#: analysis with its figures (assumed: 60 s for the analysis of the longest run on a loaded host)
RUN_OVERHEAD_S = STARTUP_TIMEOUT_S + DRAIN_TIMEOUT_S + STOP_GRACE_S + 60.0


def default_jobs() -> int:
    """The runs this host's cores (those this process may use) take at once: at least one."""
    return max(1, int(len(os.sched_getaffinity(0)) // CORES_PER_RUN))


@dataclasses.dataclass(frozen=True)
class RunTask:
    """One run of an experiment (picklable: it goes to the run's process, on this host or a Dask worker)."""
    experiment: Experiment
    sliding_mode: bool
    seed: int                        # sim_node's seed
    run_dir: Path                    # the run's own folder: logs, bag, report.json, figures
    config: Path                     # the folder of sim/planner/tracker YAML files
    timeout_s: float                 # wall-time limit of the maneuver
    tolerances: Tolerances = RUN_TOLERANCES


def run_label(experiment: str, seed: int, sliding_mode: bool) -> str:
    """A run's name, also its folder under the results folder: <experiment>/seed<k>/sliding_<on|off>."""
    return f"{experiment}/seed{seed}/sliding_{'on' if sliding_mode else 'off'}"


def run_one(task: RunTask) -> RunReport:
    """One closed-loop run in a fresh bring-up on the current ROS domain; its report (analysis measures, the
    action's result, wall time)."""
    task.run_dir.mkdir(parents=True, exist_ok=True)
    specs = closed_loop_specs(
        task.config, sim_overrides=(f"constrained:={str(task.experiment.constrained).lower()}", f"seed:={task.seed}"),
        tracker_overrides=(f"sliding_mode_enabled:={str(task.sliding_mode).lower()}",))
    return run_recorded(specs, task.run_dir, list(task.experiment.primitive_ids),
                        list(task.experiment.repeat_counts), task.experiment.time_scale, task.timeout_s,
                        task.tolerances)


#: what a run gave: its report, or why it gave none
SeedRun = Union[RunReport, FailedRun]


def run_outcome(run: SeedRun) -> str:
    """"ok", or why the run failed (the tracker's result, the bridge's faults) or gave no report."""
    if isinstance(run, FailedRun):
        return f"no report: {run.reason}"
    return "; ".join(run_failures(run)) or "ok"


def compare(experiment: Experiment, runs: Mapping[int, SlidingModePair[SeedRun]]) -> Optional[ExperimentRow]:
    """One experiment's row from its runs by seed, with (on) and without (off) sliding mode, beside the paper's;
    None if no seed has both runs reported. Each quantity of today's row is the seed value of largest magnitude
    over the seeds reported, the outcome "ok" only if every run's is; the statistics are over the paired seeds."""
    seeds = sorted(runs)
    paired = [seed for seed in seeds if all(isinstance(run, RunReport)
                                            for run in (runs[seed].sliding_on, runs[seed].sliding_off))]
    if not paired:
        return None

    # value: a field of RunMeasures, a float or (hard_stop_periods) an int
    def per_seed(value: str, sliding_mode: bool) -> list[Optional[Any]]:
        reports = [runs[seed].sliding_on if sliding_mode else runs[seed].sliding_off for seed in seeds]
        return [getattr(r.measures, value) if isinstance(r, RunReport) else None for r in reports]

    def values(value: str) -> SlidingModePair[list[Optional[Any]]]:
        return SlidingModePair(per_seed(value, True), per_seed(value, False))

    def largest(pair: SlidingModePair[list[Optional[Any]]]) -> SlidingModePair[Any]:
        return SlidingModePair(*(largest_magnitude([v for v in side if v is not None])
                                 for side in (pair.sliding_on, pair.sliding_off)))

    def paired_values(pair: SlidingModePair[list[Optional[float]]], sliding_mode: bool) -> list[float]:
        side = pair.sliding_on if sliding_mode else pair.sliding_off
        return [float(value) for seed, value in zip(seeds, side) if seed in paired and value is not None]

    outcomes = SlidingModePair([run_outcome(runs[seed].sliding_on) for seed in seeds],
                               [run_outcome(runs[seed].sliding_off) for seed in seeds])
    by_seed = SeedRuns(seeds, outcomes, values("duration_s"), values("final_lateral_offset_m"),
                       values("final_alpha_error_rad"), values("saturated_fraction"), values("hard_stop_periods"),
                       {name: values(name) for name in NORMS})
    statistics = {name: NormStatistics.of(paired_values(by_seed.two_norms[name], True),
                                          paired_values(by_seed.two_norms[name], False),
                                          experiment.paper_sliding_change.get(name)) for name in NORMS}

    def summary(side: list[str]) -> str:
        failed = [f"seed {seed}: {outcome}" for seed, outcome in zip(seeds, side) if outcome != "ok"]
        return "; ".join(failed) or "ok"

    def norm(name: str) -> NormComparison:
        change, worst = statistics[name].change, largest(by_seed.two_norms[name])
        return NormComparison(worst.sliding_on, worst.sliding_off, None if change is None else change.mean,
                              experiment.paper_sliding_change.get(name))
    outcome = SlidingModePair(summary(outcomes.sliding_on), summary(outcomes.sliding_off))
    return ExperimentRow(
        experiment=experiment.name,
        time_scale=experiment.time_scale,
        duration_s=largest(by_seed.duration_s).sliding_on,
        paper_duration_s=experiment.expected_duration_s(),
        final_lateral_offset_m=largest(by_seed.final_lateral_offset_m),
        final_alpha_error_rad=largest(by_seed.final_alpha_error_rad),
        saturated_fraction=largest(by_seed.saturated_fraction),
        hard_stop_periods=largest(by_seed.hard_stop_periods),
        two_norms={name: norm(name) for name in NORMS},
        succeeded=outcome.sliding_on == outcome.sliding_off == "ok",
        outcome=outcome,
        per_seed=by_seed,
        paired_seeds=paired,
        statistics=statistics,
    )


def _percent(value: Optional[float]) -> str:
    return "" if value is None else f"{100 * value:+.0f} %"


def change_text(change: PairedChange) -> str:
    """A paired change as "-12 % [-20 %, -4 %]" (mean [95 % interval]; the mean alone with one seed)."""
    if change.interval is None:
        return _percent(change.mean)
    return f"{_percent(change.mean)} [{_percent(change.interval[0])}, {_percent(change.interval[1])}]"


def _spread(statistics: NormStatistics, sliding_mode: bool) -> str:
    spread = statistics.sliding_on if sliding_mode else statistics.sliding_off
    return f"{spread.mean:.4f}" + ("" if spread.std is None else f" ± {spread.std:.4f}")


def results_table(rows: Sequence[ExperimentRow], pipeline: str) -> str:
    """Markdown: the pipeline's runs (outcome, duration, the largest final offsets over seeds), then each two-norm's
    statistics over seeds beside the paper's change (results.md)."""
    seeds = sorted({seed for row in rows for seed in row.per_seed.seeds})
    lines = [f"## Pipeline {pipeline}: seeds {', '.join(map(str, seeds))}", "",
             "| experiment | outcome (on/off) | duration s (paper) | final lateral offset cm, largest (on/off) "
             "| final alpha error mrad, largest (on/off) | periods at a hard stop, most (on/off) |",
             "|---|---|---|---|---|---|"]
    for row in rows:
        offset, alpha, stops = row.final_lateral_offset_m, row.final_alpha_error_rad, row.hard_stop_periods
        lines.append(f"| {row.experiment} | {row.outcome.sliding_on}/{row.outcome.sliding_off} "
                     f"| {row.duration_s:.2f} ({row.paper_duration_s:.2f}) "
                     f"| {100 * offset.sliding_on:+.2f}/{100 * offset.sliding_off:+.2f} "
                     f"| {1000 * alpha.sliding_on:+.1f}/{1000 * alpha.sliding_off:+.1f} "
                     f"| {stops.sliding_on}/{stops.sliding_off} |")
    lines += ["", "Two-norms, m s^0.5: mean ± sample standard deviation over the paired seeds; sliding mode's change "
              "(on - off) / off per seed, its mean and the paired 95 % t interval of the mean (n - 1 degrees of "
              "freedom); the paper's change beside it.", "",
              "| experiment | two-norm | seeds | with sliding | without | change per seed "
              "| mean change [95 % interval] | excludes 0 | paper |",
              "|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        for name in NORMS:
            statistics, change = row.statistics[name], row.statistics[name].change
            if change is None:
                per_seed, interval, excludes = "", "not defined (a zero two-norm without sliding mode)", ""
            else:
                per_seed, interval = ", ".join(_percent(c) for c in change.per_seed), change_text(change)
                excludes = "yes" if change.excludes_zero else "no"
            lines.append(f"| {row.experiment} | {name.split('_error')[0]} | {len(row.paired_seeds)} "
                         f"| {_spread(statistics, True)} | {_spread(statistics, False)} | {per_seed} | {interval} "
                         f"| {excludes} | {_percent(statistics.paper_change)} |")
    return "\n".join(lines)


def write_errors_figure(rows: Sequence[ExperimentRow], path: Path) -> Path:
    """The two-norms of every seed with and without sliding mode: one row of panels per experiment, one column per
    two-norm, each seed's pair joined by a line; the panel's title gives the mean change and its interval."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    figure, axes = plt.subplots(max(len(rows), 1), len(NORMS), figsize=(4.0 * len(NORMS), 1.0 + 2.2 * len(rows)),
                                squeeze=False)
    for axis_row, row in zip(axes, rows):
        for axis, name in zip(axis_row, NORMS):
            pair, seeds = row.per_seed.two_norms[name], row.per_seed.seeds
            for seed, on, off in zip(seeds, pair.sliding_on, pair.sliding_off):
                if on is not None and off is not None:
                    axis.plot([seed, seed], [off, on], color="0.7", linewidth=1)
            for side, marker, label in ((pair.sliding_on, "o", "with sliding"), (pair.sliding_off, "x", "without")):
                present = [(seed, value) for seed, value in zip(seeds, side) if value is not None]
                axis.plot([p[0] for p in present], [p[1] for p in present], marker, label=label)
            change = row.statistics[name].change
            title = f"{row.experiment}\n{name.split('_error')[0]}"
            if change is not None:
                title += f": {change_text(change)}"
            axis.set_title(title, fontsize=8)
            axis.set_xticks(seeds)
            axis.set_ylabel("two-norm [m s^0.5]", fontsize=8)
        axis_row[-1].legend(fontsize=7)
    for axis in axes[-1]:
        axis.set_xlabel("seed")
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    plt.close(figure)
    return path


def parse_arguments(argv: Optional[list[str]]) -> argparse.Namespace:
    names = [e.name for e in paper_experiments()]
    parser = argparse.ArgumentParser(prog="swim-experiments", description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="+", choices=names, default=None, help="these experiments (default: all)")
    parser.add_argument("--seeds", type=int, default=5, help="run seeds 1..N of each experiment (default 5)")
    parser.add_argument("--pipeline", choices=PIPELINES, default=PIPELINES[0],
                        help="the parameter files' pipeline (default %(default)s)")
    parser.add_argument("--run-dir", type=Path, default=None, help="output folder (default runs/experiments-<time>)")
    parser.add_argument("--config", type=Path, default=None,
                        help="folder of sim/planner/tracker YAML files (default: the pipeline's)")
    parser.add_argument("--timeout", type=float, default=600.0, help="wall-time limit of one run's maneuver, s")
    parser.add_argument("--jobs", type=int, default=None,
                        help=f"runs at once on this host (default: the cores / {CORES_PER_RUN:g}, at least 1)")
    parser.add_argument("--scheduler", default=None,
                        help="Dask scheduler address (tcp://host:port): the runs go to its workers instead")
    args = parse_with_tolerances(parser, argv)
    if args.seeds < 1:
        parser.error(f"--seeds must be at least 1, got {args.seeds}")
    if args.jobs is not None and args.jobs < 1:
        parser.error(f"--jobs must be at least 1, got {args.jobs}")
    return args


def executor_for(args: argparse.Namespace) -> concurrent.futures.Executor:
    """The Dask cluster's executor with --scheduler, else threads on this host, each waiting on one run's process."""
    if args.scheduler:
        from distributed import Client
        return Client(args.scheduler).get_executor()
    return concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs or default_jobs())


def main(argv: Optional[list[str]] = None) -> int:
    interrupt_on_sigterm()   # SIGTERM stops the runs as Ctrl-C does
    args = parse_arguments(argv)
    run_dir = (args.run_dir or Path("runs") / datetime.datetime.now().strftime("experiments-%Y%m%d-%H%M%S")).resolve()
    if (run_dir / "experiments.json").exists():
        print(f"swim-experiments: {run_dir} holds results already; choose another --run-dir", file=sys.stderr)
        return 2
    config = args.config.resolve() if args.config else config_dir(args.pipeline)
    experiments = [e for e in paper_experiments() if args.only is None or e.name in args.only]
    seeds = list(range(1, args.seeds + 1))
    tasks = {run_label(e.name, seed, on): RunTask(e, on, seed, run_dir / run_label(e.name, seed, on), config,
                                                  args.timeout, args.tolerances)
             for e in experiments for seed in seeds for on in (True, False)}
    from tqdm import tqdm
    started = time.monotonic()
    with tqdm(total=len(tasks), unit="run", file=sys.stderr) as bar, executor_for(args) as executor:
        def done(run: str, outcome: Outcome[RunReport]) -> None:
            bar.update(1)
            if outcome.failure is not None:
                bar.write(f"swim-experiments: {run} gave no report: {outcome.failure.reason}")
        outcomes = run_all(run_one, tasks, executor, args.timeout + RUN_OVERHEAD_S, done)
    failed = {run: FailedRun(run, outcome.failure.reason) for run, outcome in outcomes.items()
              if outcome.failure is not None}

    def seed_run(experiment: Experiment, seed: int, sliding_mode: bool) -> SeedRun:
        label = run_label(experiment.name, seed, sliding_mode)
        result = outcomes[label].result
        return result if result is not None else failed[label]
    rows = [row for row in (compare(e, {seed: SlidingModePair(seed_run(e, seed, True), seed_run(e, seed, False))
                                        for seed in seeds}) for e in experiments) if row is not None]
    summary = ExperimentsSummary(args.pipeline, seeds, rows, time.monotonic() - started, list(failed.values()))
    run_dir.mkdir(parents=True, exist_ok=True)
    summary.write(run_dir / "experiments.json")
    table = results_table(rows, args.pipeline)
    (run_dir / "results.md").write_text(table + "\n")
    if rows:
        write_errors_figure(rows, run_dir / "errors.png")
    print(table)
    for failure in failed.values():
        print(f"swim-experiments: {failure.run} gave no report: {failure.reason}", file=sys.stderr)
    print(f"swim-experiments: {len(tasks)} runs of {len(experiments)} experiments ({args.pipeline} pipeline, seeds "
          f"1-{args.seeds}) in {summary.wall_time_s:.0f} s, {len(failed)} without a report; results in {run_dir}")
    return 0 if not failed and len(rows) == len(experiments) and all(row.succeeded for row in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
