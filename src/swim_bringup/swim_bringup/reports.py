"""The reports of runs as typed values, and their JSON forms: report.json (swim-demo, swim-analyze --output) and
experiments.json (swim-experiments).

A field's name is its JSON key and carries its unit (SI; the error two-norms sqrt(int e^2 dt) in m s^0.5).
``to_json`` gives the JSON form (dicts, lists, numbers, strings, None); ``from_json`` reads one back and refuses an
object whose keys are not the report's (ReportError names the keys missing and unexpected).
"""
from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any, Generic, Mapping, Optional, TypeVar

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
    energy_used_j: float
    sliding_mode_enabled: bool
    periods: int


@dataclasses.dataclass(frozen=True)
class BridgeMeasures:
    """What a bridge_node's /diagnostics tell of a run (analysis.bridge_measures)."""
    bridge_faults: str          # the faults latched during the run, joined by "|"; "NONE" if none
    bridge_overruns: int        # the bridge's count of overrun periods at its last report


@dataclasses.dataclass(frozen=True)
class RunAnalysis:
    """The measures of a recorded run (analysis.analyze): the bridge's only for a run on the bridge. Its JSON form
    is one flat object, the bridge's keys after the measures'."""
    measures: RunMeasures
    bridge: Optional[BridgeMeasures]

    def measure_values(self) -> JsonObject:
        """Every measure by its name, in report order."""
        values = dataclasses.asdict(self.measures)
        if self.bridge is not None:
            values.update(dataclasses.asdict(self.bridge))
        return values

    def to_json(self) -> JsonObject:
        return self.measure_values()

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> RunAnalysis:
        return RunAnalysis(*_analysis_from_json(data, []))


def _analysis_from_json(data: Mapping[str, Any], other_keys: list[str]) -> tuple[RunMeasures, Optional[BridgeMeasures]]:
    """The measures and bridge measures of a flat report object that also holds other_keys."""
    measure_keys, bridge_keys = _field_names(RunMeasures), _field_names(BridgeMeasures)
    has_bridge = any(key in data for key in bridge_keys)
    _checked_keys(data, measure_keys + (bridge_keys if has_bridge else []) + other_keys, "a run's report")
    return (RunMeasures(**{key: data[key] for key in measure_keys}),
            BridgeMeasures(**{key: data[key] for key in bridge_keys}) if has_bridge else None)


@dataclasses.dataclass(frozen=True)
class TrackerResult:
    """How the tracker's ExecutePlan goal ended (its action result)."""
    error_code: int             # 0: the plan was completed (swim_interfaces/action/ExecutePlan)
    error_string: str
    final_alpha_error_rad: float
    duration_s: float           # plan time tracked

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> TrackerResult:
        _checked_keys(data, _field_names(cls), "a tracker result")
        return cls(**data)


@dataclasses.dataclass(frozen=True)
class RunReport(RunAnalysis):
    """One closed-loop run (report.json): the analysis of its bag, the tracker's result and the wall time of the
    whole run (bring-up, maneuver, shutdown, analysis)."""
    result: TrackerResult
    wall_time_s: float

    def to_json(self) -> JsonObject:
        return {**self.measure_values(), "result": dataclasses.asdict(self.result), "wall_time_s": self.wall_time_s}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> RunReport:
        measures, bridge = _analysis_from_json(data, ["result", "wall_time_s"])
        return RunReport(measures, bridge, TrackerResult.from_json(data["result"]), data["wall_time_s"])

    def write(self, path: Path) -> None:
        path.write_text(json.dumps(self.to_json(), indent=2))

    @classmethod
    def load(cls, path: Path) -> RunReport:
        return cls.from_json(json.loads(path.read_text()))


@dataclasses.dataclass(frozen=True)
class SlidingModePair(Generic[T]):
    """One quantity of an experiment's two runs, with and without the sliding-mode term."""
    sliding_on: T
    sliding_off: T


@dataclasses.dataclass(frozen=True)
class NormComparison:
    """A two-norm with and without sliding mode, m s^0.5, and the relative change sliding mode brought, here and
    in the paper (None: not computable, or not reported there)."""
    sliding_on: float
    sliding_off: float
    change: Optional[float]          # (on - off) / off: negative where sliding mode lowers the error
    paper_change: Optional[float]


@dataclasses.dataclass(frozen=True)
class ExperimentRow:
    """One experiment's runs set beside the paper's (experiments.compare)."""
    experiment: str
    time_scale: float
    duration_s: float                # of the run with sliding mode
    paper_duration_s: float          # nominal / lambda (Sec. 4.3)
    final_lateral_offset_m: SlidingModePair[float]
    final_alpha_error_rad: SlidingModePair[float]
    saturated_fraction: SlidingModePair[float]
    two_norms: dict[str, NormComparison]
    succeeded: bool                  # both runs
    outcome: SlidingModePair[str]    # "ok", or why a run failed

    def to_json(self) -> JsonObject:
        return dataclasses.asdict(self)

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> ExperimentRow:
        _checked_keys(data, _field_names(cls), "an experiment's row")

        def pair(value: Mapping[str, Any]) -> SlidingModePair[Any]:
            _checked_keys(value, _field_names(SlidingModePair), "a pair of runs")
            return SlidingModePair(**value)

        def norm(value: Mapping[str, Any]) -> NormComparison:
            _checked_keys(value, _field_names(NormComparison), "a two-norm comparison")
            return NormComparison(**value)
        return cls(data["experiment"], data["time_scale"], data["duration_s"], data["paper_duration_s"],
                   pair(data["final_lateral_offset_m"]), pair(data["final_alpha_error_rad"]),
                   pair(data["saturated_fraction"]), {name: norm(v) for name, v in data["two_norms"].items()},
                   data["succeeded"], pair(data["outcome"]))


@dataclasses.dataclass(frozen=True)
class StoppedRun:
    """The run that stopped swim-experiments, and why."""
    run: str             # <experiment>/sliding_<on|off>
    reason: str


@dataclasses.dataclass(frozen=True)
class ExperimentsSummary:
    """swim-experiments' results (experiments.json): the experiments done, the wall time, and the run that stopped
    the rest if one did (the key "stopped" only then)."""
    experiments: list[ExperimentRow]
    wall_time_s: float
    stopped: Optional[StoppedRun] = None

    def to_json(self) -> JsonObject:
        data: JsonObject = {"experiments": [row.to_json() for row in self.experiments],
                            "wall_time_s": self.wall_time_s}
        if self.stopped is not None:
            data["stopped"] = dataclasses.asdict(self.stopped)
        return data

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> ExperimentsSummary:
        _checked_keys(data, ["experiments", "wall_time_s"] + (["stopped"] if "stopped" in data else []),
                      "experiments' results")
        stopped = None
        if "stopped" in data:
            _checked_keys(data["stopped"], _field_names(StoppedRun), "a stopped run")
            stopped = StoppedRun(**data["stopped"])
        return cls([ExperimentRow.from_json(row) for row in data["experiments"]], data["wall_time_s"], stopped)

    def write(self, path: Path) -> None:
        path.write_text(json.dumps(self.to_json(), indent=2))

    @classmethod
    def load(cls, path: Path) -> ExperimentsSummary:
        return cls.from_json(json.loads(path.read_text()))
