"""The swim-experiments command: the paper's experiments in closed loop over seeds.

swim-experiments: the paper's experiments in closed loop over DDS, in simulation, over seeds
(Sec. 7; docs/model_and_method.md section 6).

Every experiment (experiments.paper_experiments) runs with and without the sliding-mode term for each seed 1..N,
each run in a fresh bring-up (sim_node in lock-step, planner_node, tracker_node) with the parameter files of a
pipeline (system.config_dir: "realistic", the physical plant, or "paper", the paper's ideal flow), recorded and
analysed like the demo. Runs go side by side, each in a process and ROS domain of its own (swim_bringup.parallel),
on this host or a Dask cluster. The results (experiments.json, results.md, errors.png) set our numbers beside the
paper's (experiments.compare, experiments.results_table, figures.write_errors_figure).
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
from typing import Optional

from swim_bringup.experiments import Experiment, SeedRun, compare, paper_experiments, results_table, run_label
from swim_bringup.figures import write_errors_figure
from swim_bringup.parallel import Outcome, run_all
from swim_bringup.recorded_run import RUN_TOLERANCES, parse_with_tolerances, run_recorded
from swim_bringup.reports import ExperimentsSummary, FailedRun, RunReport, SlidingModePair
from swim_bringup.run_client import DRAIN_TIMEOUT_S, STARTUP_TIMEOUT_S
from swim_bringup.system import PIPELINES, closed_loop_specs, config_dir
from swim_controller.supervisor import Tolerances
from swim_ros.processes import STOP_GRACE_S, interrupt_on_sigterm

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


def run_one(task: RunTask) -> RunReport:
    """One closed-loop run in a fresh bring-up; its report.

    One closed-loop run in a fresh bring-up on the current ROS domain; its report (analysis measures, the
    action's result, wall time).
    """
    task.run_dir.mkdir(parents=True, exist_ok=True)
    specs = closed_loop_specs(
        task.config, sim_overrides=(f"constrained:={str(task.experiment.constrained).lower()}", f"seed:={task.seed}"),
        tracker_overrides=(f"sliding_mode_enabled:={str(task.sliding_mode).lower()}",))
    return run_recorded(specs, task.run_dir, list(task.experiment.primitive_ids),
                        list(task.experiment.repeat_counts), task.experiment.time_scale, task.timeout_s,
                        task.tolerances)


def parse_arguments(argv: Optional[list[str]]) -> argparse.Namespace:
    """The command line of swim-experiments, parsed."""
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
    """The swim-experiments command; its exit status."""
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
