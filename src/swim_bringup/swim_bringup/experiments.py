"""swim-experiments: the paper's experiments in closed loop over DDS, in simulation
(Sec. 7; docs/model_and_method.md section 6).

Every experiment runs twice, with and without the sliding-mode term, each run in a fresh bring-up (sim_node in
lock-step with the same seed and the default disturbances, planner_node, tracker_node), recorded and analysed
like the demo. Experiments:

- constrained {accelerate1, cruise1 x2, cruise-to-cruise(1,2), cruise2 x2, decelerate2}, lambda 1, 1.2, 1.67, 0.8
  (Sec. 7.1: 30 s nominal);
- free lane keeping {accelerate, 14 x cruise, decelerate} at R = 0.43 m, lambda 1 and 1.1 (Sec. 7.2: 20 s);
- free lane change {accelerate, 5 x cruise, lane change 0.43 -> 0.48 m, 10 x cruise, decelerate}, lambda 1 and
  1.25 (Sec. 7.3: 23 s).

The results (experiments.json, results.md) set our numbers beside the paper's: the scaled maneuver's duration
(nominal / lambda), the final lane offset (paper: within 0.5 cm) and the change in the error two-norms that
sliding mode brings (paper: 5-14 % lower).
"""
from __future__ import annotations

import argparse
import dataclasses
import datetime
import sys
import time
from pathlib import Path
from typing import Optional

from swim_bringup.recorded_run import (PAPER_CONSTRAINED, PAPER_LANE_KEEPING, RUN_TOLERANCES,
                                       parse_with_tolerances, run_failures, run_recorded)
from swim_bringup.reports import (ExperimentRow, ExperimentsSummary, NormComparison, RunReport, SlidingModePair,
                                  StoppedRun)
from swim_bringup.system import closed_loop_specs, config_dir
from swim_controller.supervisor import Tolerances

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


def run_one(experiment: Experiment, sliding_mode: bool, run_dir: Path, config: Path, timeout_s: float,
            tolerances: Tolerances = RUN_TOLERANCES) -> RunReport:
    """One closed-loop run in a fresh bring-up; its report (analysis measures, the action's result, wall time)."""
    run_dir.mkdir(parents=True, exist_ok=True)
    specs = closed_loop_specs(config, sim_overrides=(f"constrained:={str(experiment.constrained).lower()}",),
                              tracker_overrides=(f"sliding_mode_enabled:={str(sliding_mode).lower()}",))
    return run_recorded(specs, run_dir, list(experiment.primitive_ids), list(experiment.repeat_counts),
                        experiment.time_scale, timeout_s, tolerances)


def relative_change(with_sliding: float, without_sliding: float) -> Optional[float]:
    """(with - without) / without: negative where sliding mode lowers the error."""
    return None if without_sliding == 0.0 else (with_sliding - without_sliding) / without_sliding


def compare(experiment: Experiment, on: RunReport, off: RunReport) -> ExperimentRow:
    """One experiment's row: its runs with (on) and without (off) sliding mode beside the paper's."""
    def norm(name: str) -> NormComparison:   # name: one of NORMS, a field of RunMeasures
        with_sliding, without_sliding = getattr(on.measures, name), getattr(off.measures, name)
        return NormComparison(with_sliding, without_sliding, relative_change(with_sliding, without_sliding),
                              experiment.paper_sliding_change.get(name))
    failures = SlidingModePair(run_failures(on), run_failures(off))
    return ExperimentRow(
        experiment=experiment.name,
        time_scale=experiment.time_scale,
        duration_s=on.measures.duration_s,
        paper_duration_s=experiment.expected_duration_s(),
        final_lateral_offset_m=SlidingModePair(on.measures.final_lateral_offset_m,
                                               off.measures.final_lateral_offset_m),
        final_alpha_error_rad=SlidingModePair(on.measures.final_alpha_error_rad, off.measures.final_alpha_error_rad),
        saturated_fraction=SlidingModePair(on.measures.saturated_fraction, off.measures.saturated_fraction),
        two_norms={name: norm(name) for name in NORMS},
        succeeded=not failures.sliding_on and not failures.sliding_off,
        outcome=SlidingModePair("; ".join(failures.sliding_on) or "ok", "; ".join(failures.sliding_off) or "ok"),
    )


def results_table(rows: list[ExperimentRow]) -> str:
    """A Markdown table of the rows (README's results section is this table)."""
    def percent(value: Optional[float]) -> str:
        return "" if value is None else f"{100 * value:+.0f} %"
    lines = ["| experiment | outcome (on/off) | duration s (paper) | final lateral offset cm (on/off) "
             "| final alpha error mrad (on/off) | longitudinal two-norm (on/off, change; paper) | lateral "
             "| Cartesian |",
             "|---|---|---|---|---|---|---|---|"]
    for row in rows:
        norms = []
        for norm in NORMS:
            entry = row.two_norms[norm]
            paper = f"; {percent(entry.paper_change)}" if entry.paper_change is not None else ""
            norms.append(f"{entry.sliding_on:.4f}/{entry.sliding_off:.4f}, {percent(entry.change)}{paper}")
        offset, alpha = row.final_lateral_offset_m, row.final_alpha_error_rad
        lines.append(f"| {row.experiment} | {row.outcome.sliding_on}/{row.outcome.sliding_off} "
                     f"| {row.duration_s:.2f} ({row.paper_duration_s:.2f}) "
                     f"| {100 * offset.sliding_on:+.2f}/{100 * offset.sliding_off:+.2f} "
                     f"| {1000 * alpha.sliding_on:+.1f}/{1000 * alpha.sliding_off:+.1f} | "
                     + " | ".join(norms) + " |")
    return "\n".join(lines)


def parse_arguments(argv: Optional[list[str]]) -> argparse.Namespace:
    names = [e.name for e in paper_experiments()]
    parser = argparse.ArgumentParser(prog="swim-experiments", description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="+", choices=names, default=None, help="these experiments (default: all)")
    parser.add_argument("--run-dir", type=Path, default=None, help="output folder (default runs/experiments-<time>)")
    parser.add_argument("--config", type=Path, default=None, help="folder of sim/planner/tracker YAML files")
    parser.add_argument("--timeout", type=float, default=600.0, help="wall-time limit of one run, s")
    return parse_with_tolerances(parser, argv)


def main(argv: Optional[list[str]] = None) -> int:
    args = parse_arguments(argv)
    run_dir = args.run_dir or Path("runs") / datetime.datetime.now().strftime("experiments-%Y%m%d-%H%M%S")
    if (run_dir / "experiments.json").exists():
        print(f"swim-experiments: {run_dir} holds results already; choose another --run-dir", file=sys.stderr)
        return 2
    from swim_ros.domains import run_domain
    run_domain()   # a domain of our own unless the user chose one: never another session's nodes
    from tqdm import tqdm
    experiments = [e for e in paper_experiments() if args.only is None or e.name in args.only]
    rows: list[ExperimentRow] = []
    started, stopped = time.monotonic(), None
    with tqdm(total=2 * len(experiments), unit="run", file=sys.stderr) as bar:
        for experiment in experiments:
            reports: dict[bool, RunReport] = {}
            for sliding_mode in (True, False):
                label = f"{experiment.name}/sliding_{'on' if sliding_mode else 'off'}"
                bar.set_description(label)
                try:
                    reports[sliding_mode] = run_one(experiment, sliding_mode, run_dir / label,
                                                    args.config or config_dir(), args.timeout, args.tolerances)
                except Exception as err:   # noqa: BLE001 - whatever stops a run is named, and what was done kept
                    stopped = StoppedRun(run=label, reason=f"{type(err).__name__}: {err}")
                    break
                bar.update(1)
            if stopped is not None:
                break
            rows.append(compare(experiment, reports[True], reports[False]))
    summary = ExperimentsSummary(rows, time.monotonic() - started, stopped)
    run_dir.mkdir(parents=True, exist_ok=True)
    summary.write(run_dir / "experiments.json")
    if stopped is not None:
        print(f"swim-experiments: stopped at {stopped.run}: {stopped.reason}; the {len(rows)} experiments "
              f"done are in {run_dir / 'experiments.json'}", file=sys.stderr)
        return 1
    table = results_table(rows)
    (run_dir / "results.md").write_text(table + "\n")
    print(table)
    print(f"swim-experiments: {len(rows)} experiments in {summary.wall_time_s:.0f} s; results in {run_dir}")
    return 0 if all(row.succeeded for row in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
