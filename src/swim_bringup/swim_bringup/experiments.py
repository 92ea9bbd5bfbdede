"""The paper's experiments and the comparison of their runs over seeds with the paper's.

The paper's experiments (Sec. 7; docs/model_and_method.md section 6) and the comparison of their runs over seeds
with the paper's (no ROS, no files written, no figures: experiments_cli is swim-experiments, figures draws).

Every experiment runs with and without the sliding-mode term for each seed 1..N (sim_node's ``seed``: its
disturbances' and sensors' noise). Experiments:

- constrained {accelerate1, cruise1 x2, cruise-to-cruise(1,2), cruise2 x2, decelerate2}, lambda 1, 1.2, 1.67, 0.8
  (Sec. 7.1: 30 s nominal);
- free lane keeping {accelerate, 14 x cruise, decelerate} at R = 0.43 m, lambda 1 and 1.1 (Sec. 7.2: 20 s);
- free lane change {accelerate, 5 x cruise, lane change 0.43 -> 0.48 m, 10 x cruise, decelerate}, lambda 1 and
  1.25 (Sec. 7.3: 23 s).

compare sets our numbers beside the paper's: the scaled maneuver's duration (nominal / lambda), the final lane
offset (paper: within 0.5 cm), and the change in the error two-norms that sliding mode brings (paper: 5-14 % lower)
with its paired 95 % interval over the seeds (statistics.py); results_table gives them as results.md's Markdown.
"""
from __future__ import annotations

import dataclasses
from typing import Any, Mapping, Optional, Sequence, Union

from swim_bringup.reports import (
    ExperimentRow,
    FailedRun,
    NormComparison,
    RunReport,
    SeedRuns,
    SlidingModePair,
    run_failures,
)
from swim_bringup.statistics import NormStatistics, PairedChange, largest_magnitude
from swim_planner.catalog import PAPER_CONSTRAINED, PAPER_LANE_CHANGE, PAPER_LANE_KEEPING

NORMS = ("longitudinal_error_two_norm_m_s05", "lateral_error_two_norm_m_s05", "cartesian_error_two_norm_m_s05")


@dataclasses.dataclass(frozen=True)
class Experiment:
    """One of the paper's experiments: a maneuver at a time scale, and the paper's results for it."""

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


def run_label(experiment: str, seed: int, sliding_mode: bool) -> str:
    """A run's name, also its folder under the results folder: <experiment>/seed<k>/sliding_<on|off>."""
    return f"{experiment}/seed{seed}/sliding_{'on' if sliding_mode else 'off'}"


#: what a run gave: its report, or why it gave none
SeedRun = Union[RunReport, FailedRun]


def run_outcome(run: SeedRun) -> str:
    """"ok", or why the run failed (the tracker's result, the bridge's faults) or gave no report."""
    if isinstance(run, FailedRun):
        return f"no report: {run.reason}"
    return "; ".join(run_failures(run)) or "ok"


def compare(experiment: Experiment, runs: Mapping[int, SlidingModePair[SeedRun]]) -> Optional[ExperimentRow]:
    """One experiment's row from its runs by seed, beside the paper's.

    One experiment's row from its runs by seed, with (on) and without (off) sliding mode, beside the paper's;
    None if no seed has both runs reported. Each quantity of today's row is the seed value of largest magnitude
    over the seeds reported, the outcome "ok" only if every run's is; the statistics are over the paired seeds.
    """
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
    """The results of the pipeline's runs as Markdown (results.md).

    Markdown: the pipeline's runs (outcome, duration, the largest final offsets over seeds), then each two-norm's
    statistics over seeds beside the paper's change (results.md).
    """
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
