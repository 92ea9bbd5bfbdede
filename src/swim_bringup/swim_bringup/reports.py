"""The reports of runs as typed values, and their JSON forms.

report.json (swim-demo, swim-analyze --output) and experiments.json (swim-experiments).

A field's name is its JSON key and carries its unit (SI; the error two-norms sqrt(int e^2 dt) in m s^0.5).
``to_json`` gives the JSON form (dicts, lists, numbers, strings, None); ``from_json`` reads one back and refuses an
object whose keys are not the report's (ReportError names the keys missing and unexpected).
"""
from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any, Generic, Mapping, Optional, TypeVar

from swim_bringup.statistics import NormStatistics, PairedChange, Spread

JsonObject = dict[str, Any]
T = TypeVar("T")


class ReportError(ValueError):
    """A JSON object that is not the report it should be."""


def _checked_keys(data: Mapping[str, Any], keys: list[str], what: str) -> None:
    missing, unexpected = [k for k in keys if k not in data], sorted(set(data) - set(keys))
    if missing or unexpected:
        raise ReportError(f"not {what}: keys missing {missing}, unexpected {unexpected}")


def _field_names(cls: type) -> list[str]:
    return [field.name for field in dataclasses.fields(cls)]


def _record(cls: type[T], data: Mapping[str, Any], what: str) -> T:
    """The dataclass cls of a JSON object that holds exactly its fields (ReportError otherwise, naming what)."""
    _checked_keys(data, _field_names(cls), what)
    return cls(**data)


@dataclasses.dataclass(frozen=True)
class RunMeasures:
    """The paper's measures of one tracked plan (analysis.measures)."""

    duration_s: float
    longitudinal_error_two_norm_m_s05: float      # R_d (alpha - alpha_d)
    lateral_error_two_norm_m_s05: float           # R - R_d (0 for the constrained vehicle)
    cartesian_error_two_norm_m_s05: float         # |p - p_d|, p = R (cos alpha, sin alpha)
    final_alpha_error_rad: float
    final_lateral_offset_m: float
    peak_heave_torque_n_m: float
    peak_pitch_torque_n_m: float
    saturated_fraction: float                     # of the periods, with either motor saturated
    hard_stop_periods: int                        # periods with the heave or the pitch at a hard limit (its stop)
    energy_used_j: float
    sliding_mode_enabled: bool
    periods: int


@dataclasses.dataclass(frozen=True)
class BridgeMeasures:
    """What a bridge_node's /diagnostics tell of a run.

    They are made by analysis.bridge_measures. The loop's timing, from its last report: None where the bridge did not
    report it.
    """

    bridge_faults: str          # the faults latched during the run, joined by "|"; "NONE" if none
    bridge_overruns: int        # the bridge's count of overrun periods at its last report
    bridge_worst_lateness_ms: Optional[float] = None  # the latest end of a period past its deadline
    bridge_overrun_cause: Optional[str] = None     # that period's cause: LATE_WAKEUP, SLOW_READ, SLOW_WRITE, ...
    bridge_wake_lateness_p99_ms: Optional[float] = None  # the periods' start past their place on the grid
    bridge_command_latency_p50_ms: Optional[float] = None   # a command's receipt past the sample of its state
    bridge_command_latency_p99_ms: Optional[float] = None
    bridge_command_jitter_p50_ms: Optional[float] = None    # |interval between two commands' receipts - period|
    bridge_command_jitter_p99_ms: Optional[float] = None
    bridge_state_interval_max_ms: Optional[float] = None   # the longest time between two states it published
    bridge_state_publish_max_ms: Optional[float] = None    # the longest publish of a state (a blocked middleware)


@dataclasses.dataclass(frozen=True)
class RunAnalysis:
    """The measures of a recorded run.

    They are made by analysis.analyze, the bridge's only for a run on the bridge. Its JSON form
    is one flat object, the bridge's keys after the measures'.
    """

    measures: RunMeasures
    bridge: Optional[BridgeMeasures]

    def measure_values(self) -> JsonObject:
        """Every measure by its name, in report order."""
        values = dataclasses.asdict(self.measures)
        if self.bridge is not None:
            values.update(dataclasses.asdict(self.bridge))
        return values

    def to_json(self) -> JsonObject:
        """The JSON form: every measure by its name."""
        return self.measure_values()

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> RunAnalysis:
        """The analysis of its JSON form."""
        return RunAnalysis(*_analysis_from_json(data, []))


def _analysis_from_json(data: Mapping[str, Any], other_keys: list[str]) -> tuple[RunMeasures, Optional[BridgeMeasures]]:
    """The measures and bridge measures of a flat report object that also holds other_keys."""
    measure_keys, bridge_keys = _field_names(RunMeasures), _field_names(BridgeMeasures)
    has_bridge = any(key in data for key in bridge_keys)
    # a report from a bridge that did not report its timing lacks those keys (they have defaults)
    bridge_present = [field.name for field in dataclasses.fields(BridgeMeasures)
                      if field.name in data or field.default is dataclasses.MISSING] if has_bridge else []
    _checked_keys(data, measure_keys + bridge_present + other_keys, "a run's report")
    return (RunMeasures(**{key: data[key] for key in measure_keys}),
            BridgeMeasures(**{key: data[key] for key in bridge_present}) if has_bridge else None)


@dataclasses.dataclass(frozen=True)
class TrackerResult:
    """How the tracker's ExecutePlan goal ended (its action result)."""

    error_code: int             # 0: the plan was completed (swim_interfaces/action/ExecutePlan)
    error_string: str
    final_alpha_error_rad: float
    duration_s: float           # plan time tracked

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> TrackerResult:
        """The tracker result of its JSON form."""
        return _record(cls, data, "a tracker result")


@dataclasses.dataclass(frozen=True)
class RunReport(RunAnalysis):
    """One closed-loop run's report (report.json).

    One closed-loop run (report.json): the analysis of its bag, the tracker's result and the wall time of the
    whole run (bring-up, maneuver, shutdown, analysis).
    """

    result: TrackerResult
    wall_time_s: float

    def to_json(self) -> JsonObject:
        """The JSON form: the measures, the tracker's result and the wall time."""
        return {**self.measure_values(), "result": dataclasses.asdict(self.result), "wall_time_s": self.wall_time_s}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> RunReport:
        """The report of its JSON form."""
        measures, bridge = _analysis_from_json(data, ["result", "wall_time_s"])
        return RunReport(measures, bridge, TrackerResult.from_json(data["result"]), data["wall_time_s"])

    def write(self, path: Path) -> None:
        """Write the JSON form to path."""
        path.write_text(json.dumps(self.to_json(), indent=2))

    @classmethod
    def load(cls, path: Path) -> RunReport:
        """The report of the JSON file at path."""
        return cls.from_json(json.loads(path.read_text()))


@dataclasses.dataclass(frozen=True)
class SlidingModePair(Generic[T]):
    """One quantity of an experiment's two runs, with and without the sliding-mode term."""

    sliding_on: T
    sliding_off: T


@dataclasses.dataclass(frozen=True)
class NormComparison:
    """A two-norm with and without sliding mode, and the change sliding mode brought.

    A two-norm with and without sliding mode, m s^0.5 (over seeds: the seed's of largest magnitude), and the
    relative change sliding mode brought, here (over seeds: the mean of each seed's change) and in the paper (None:
    not computable, or not reported there).
    """

    sliding_on: float
    sliding_off: float
    change: Optional[float]          # (on - off) / off: negative where sliding mode lowers the error
    paper_change: Optional[float]


@dataclasses.dataclass(frozen=True)
class SeedRuns:
    """An experiment's runs seed by seed: each list in the order of seeds, None where a run gave no report."""

    seeds: list[int]
    outcome: SlidingModePair[list[str]]          # "ok", or why the run failed or gave no report
    duration_s: SlidingModePair[list[Optional[float]]]
    final_lateral_offset_m: SlidingModePair[list[Optional[float]]]
    final_alpha_error_rad: SlidingModePair[list[Optional[float]]]
    saturated_fraction: SlidingModePair[list[Optional[float]]]
    hard_stop_periods: SlidingModePair[list[Optional[int]]]
    two_norms: dict[str, SlidingModePair[list[Optional[float]]]]   # m s^0.5, by measure

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> SeedRuns:
        """The runs by seed of their JSON form."""
        _checked_keys(data, _field_names(cls), "an experiment's runs by seed")
        return cls(data["seeds"], _pair(data["outcome"]), _pair(data["duration_s"]),
                   _pair(data["final_lateral_offset_m"]), _pair(data["final_alpha_error_rad"]),
                   _pair(data["saturated_fraction"]), _pair(data["hard_stop_periods"]),
                   {name: _pair(value) for name, value in data["two_norms"].items()})


def _pair(value: Mapping[str, Any]) -> SlidingModePair[Any]:
    return _record(SlidingModePair, value, "a pair of runs")


def _norm_statistics(data: Mapping[str, Any]) -> NormStatistics:
    _checked_keys(data, _field_names(NormStatistics), "a two-norm's statistics")
    change = data["change"]
    if change is not None:
        _checked_keys(change, _field_names(PairedChange), "a paired change")
        interval = None if change["interval"] is None else tuple(change["interval"])
        change = PairedChange(change["per_seed"], change["mean"], interval, change["excludes_zero"])
    on, off = (_record(Spread, data[side], "a mean and standard deviation") for side in ("sliding_on", "sliding_off"))
    return NormStatistics(on, off, change, data["paper_change"])


@dataclasses.dataclass(frozen=True)
class ExperimentRow:
    """One experiment's runs over seeds set beside the paper's.

    It is made by experiments.compare. Each of the quantities of a pair of runs is the seed's value of largest magnitude
    (sign kept; outcome "ok" only when every seed's is); per_seed holds them all, statistics the two-norms' over the
    paired_seeds (those with both runs reported).
    """

    experiment: str
    time_scale: float
    duration_s: float                # of the runs with sliding mode
    paper_duration_s: float          # nominal / lambda (Sec. 4.3)
    final_lateral_offset_m: SlidingModePair[float]
    final_alpha_error_rad: SlidingModePair[float]
    saturated_fraction: SlidingModePair[float]
    hard_stop_periods: SlidingModePair[int]   # periods with the heave or the pitch at its stop
    two_norms: dict[str, NormComparison]
    succeeded: bool                  # every run of every seed
    outcome: SlidingModePair[str]    # "ok", or why runs failed ("seed k: why; ...")
    per_seed: SeedRuns
    paired_seeds: list[int]
    statistics: dict[str, NormStatistics]   # by two-norm measure

    def to_json(self) -> JsonObject:
        """The JSON form: every field."""
        return dataclasses.asdict(self)

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> ExperimentRow:
        """The row of its JSON form."""
        _checked_keys(data, _field_names(cls), "an experiment's row")
        return cls(data["experiment"], data["time_scale"], data["duration_s"], data["paper_duration_s"],
                   _pair(data["final_lateral_offset_m"]), _pair(data["final_alpha_error_rad"]),
                   _pair(data["saturated_fraction"]), _pair(data["hard_stop_periods"]),
                   {name: _record(NormComparison, value, "a two-norm comparison")
                    for name, value in data["two_norms"].items()},
                   data["succeeded"], _pair(data["outcome"]), SeedRuns.from_json(data["per_seed"]),
                   data["paired_seeds"], {name: _norm_statistics(v) for name, v in data["statistics"].items()})


@dataclasses.dataclass(frozen=True)
class FailedRun:
    """A run of swim-experiments that gave no report, and why."""

    run: str             # <experiment>/seed<k>/sliding_<on|off>
    reason: str


@dataclasses.dataclass(frozen=True)
class ExperimentsSummary:
    """The results of swim-experiments (experiments.json).

    swim-experiments' results (experiments.json): the pipeline (config/ folder) and seeds run, the experiments
    with at least one seed run with and without sliding mode, the wall time, and the runs that gave no report.
    """

    pipeline: str
    seeds: list[int]
    experiments: list[ExperimentRow]
    wall_time_s: float
    failed_runs: list[FailedRun]

    def to_json(self) -> JsonObject:
        """The JSON form: every field, the rows and failed runs as theirs."""
        return {"pipeline": self.pipeline, "seeds": self.seeds,
                "experiments": [row.to_json() for row in self.experiments], "wall_time_s": self.wall_time_s,
                "failed_runs": [dataclasses.asdict(failed) for failed in self.failed_runs]}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> ExperimentsSummary:
        """The results of their JSON form."""
        _checked_keys(data, _field_names(cls), "experiments' results")
        return cls(data["pipeline"], data["seeds"], [ExperimentRow.from_json(row) for row in data["experiments"]],
                   data["wall_time_s"], [_record(FailedRun, value, "a failed run") for value in data["failed_runs"]])

    def write(self, path: Path) -> None:
        """Write the JSON form to path (experiments.json)."""
        path.write_text(json.dumps(self.to_json(), indent=2))

    @classmethod
    def load(cls, path: Path) -> ExperimentsSummary:
        """The results of the JSON file at path."""
        return cls.from_json(json.loads(path.read_text()))


def run_failures(report: RunReport) -> list[str]:
    """Why a run's report is not a success (empty if it is): the tracker's result, the bridge's latched faults."""
    failures = []
    if report.result.error_code != 0:
        failures.append(f"the tracker ended with {report.result.error_string or report.result.error_code}")
    if report.bridge is not None and report.bridge.bridge_faults != "NONE":
        failures.append(f"the bridge latched {report.bridge.bridge_faults}: the motors were off from then on")
    return failures
