"""The paper's measures of a recorded run, what a bag holds, and the tables the commands print.

The paper's measures of a recorded run (Sec. 7), what a bag holds, and the tables swim-analyze, swim-demo and
swim-maneuver print (no ROS, no files written, no figures: analysis_cli is swim-analyze, figures draws).

From the tracking_state topic (reference and measured q each control period) and the plan:
- two-norms of the errors, ||e||_2 = sqrt(int e(t)^2 dt): longitudinal R_d (alpha - alpha_d) in m, lateral
  R - R_d in m, Cartesian |p - p_d| of the platform's position p = R (cos alpha, sin alpha) in m;
- the final lateral offset and final alpha error, the duration, peak |torque| per motor, the fraction of
  periods with a saturated motor, the periods with the heave or the pitch at a hard limit (at the rig's stop: by
  default the shipped rig file's limits, which sim_node's stops also take; --rig for another rig's),
  and the energy used, int (|tau_h phidot| + |tau_p thetadot|) dt in J (motors do not take energy back, so
  negative power is counted as spent too).

Of any rosbag2 bag (run_record.read_bag reads it once): its topics with their types and message counts, and those
whose messages cannot be decoded named with why; from joint_states alone, each joint's range and peak speed and the
messages' rate; the measures above when the bag has what they need (tracking_state, and for the constrained
vehicle the plan). What a bag lacks is named, with why.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any, Mapping, Optional

import numpy as np

from swim_bringup.bag import BagError, BagInfo
from swim_bringup.reports import RunAnalysis, RunMeasures
from swim_bringup.run_record import JointStates, MissingTopic, RecordedBag, Run, read_bag
from swim_control.measures import two_norm
from swim_model import load_rig
from swim_model.limits import HardLimits
from swim_ros.typestore import swim_typestore

#: a foil joint within this of a hard limit is at its stop: about one encoder count there (the heave's 512 lines, x4,
#: through 43:1: 7.1e-5 rad; the pitch's through 25:1: 1.2e-4 rad); the simulator's stops hold a joint at the limit
HARD_STOP_TOLERANCE_RAD = 1.0e-4


def rig_hard_limits(rig_path: Optional[Path] = None) -> HardLimits:
    """The rig's hard stops that hard_stop_periods counts, rad.

    The rig's hard stops ((heave lower, upper), (pitch lower, upper), rad) that hard_stop_periods counts: the
    limits record of the rig file at rig_path, by default the shipped one (every node's when its rig_path is
    empty). RigConfigError if the file does not read.
    """
    return load_rig(rig_path).hard_limits_rad


def _radius(run: Run, q: np.ndarray) -> np.ndarray:
    return q[:, run.joint_names.index("R")] if "R" in run.joint_names else np.full(len(q), run.lane_radius_m)


def platform_xy_m(run: Run, q: np.ndarray) -> np.ndarray:
    """The platform's position in the tank's plane, m, shape (n, 2).

    The platform's position p = R (cos alpha, sin alpha) in the tank's plane, m, (n, 2), at the run's joint
    positions q (n, nq): run.q or run.q_reference.
    """
    alpha = q[:, run.joint_names.index("alpha")]
    return _radius(run, q)[:, None] * np.column_stack([np.cos(alpha), np.sin(alpha)])


def hard_stop_periods(run: Run, hard_limits_rad: HardLimits) -> int:
    """The periods in which the heave or the pitch is at or past a hard limit.

    The periods in which the heave or the pitch (the run's last two joints) is at or past one of its hard limits
    ((heave lower, upper), (pitch lower, upper), rad), to within HARD_STOP_TOLERANCE_RAD.
    """
    (heave_lower, heave_upper), (pitch_lower, pitch_upper) = hard_limits_rad
    foil = run.q[:, -2:]
    at_stop = ((foil <= np.array([heave_lower, pitch_lower]) + HARD_STOP_TOLERANCE_RAD)
               | (foil >= np.array([heave_upper, pitch_upper]) - HARD_STOP_TOLERANCE_RAD))
    return int(at_stop.any(axis=1).sum())


def measures(run: Run, hard_limits_rad: Optional[HardLimits] = None) -> RunMeasures:
    """The run's measures; its hard stops are hard_limits_rad's, by default the rig's (rig_hard_limits)."""
    if hard_limits_rad is None:
        hard_limits_rad = rig_hard_limits()
    alpha = run.joint_names.index("alpha")
    radius, radius_reference = _radius(run, run.q), _radius(run, run.q_reference)
    alpha_error = run.q[:, alpha] - run.q_reference[:, alpha]
    position, reference = platform_xy_m(run, run.q), platform_xy_m(run, run.q_reference)
    power = np.abs(run.torque * run.qdot[:, -2:]).sum(axis=1)
    return RunMeasures(
        duration_s=float(run.time_s[-1] - run.time_s[0]),
        longitudinal_error_two_norm_m_s05=two_norm(run.time_s, radius_reference * alpha_error),
        lateral_error_two_norm_m_s05=two_norm(run.time_s, radius - radius_reference),
        cartesian_error_two_norm_m_s05=two_norm(run.time_s, np.linalg.norm(position - reference, axis=1)),
        final_alpha_error_rad=float(alpha_error[-1]),
        final_lateral_offset_m=float(radius[-1] - radius_reference[-1]),
        peak_heave_torque_n_m=float(np.abs(run.torque[:, 0]).max()),
        peak_pitch_torque_n_m=float(np.abs(run.torque[:, 1]).max()),
        saturated_fraction=float(run.saturated.any(axis=1).mean()),
        hard_stop_periods=hard_stop_periods(run, hard_limits_rad),
        energy_used_j=float(np.trapezoid(power, run.time_s)),
        sliding_mode_enabled=run.sliding_mode_enabled,
        periods=int(len(run.time_s)),
    )


def run_analysis(record: RecordedBag, hard_limits_rad: Optional[HardLimits] = None) -> RunAnalysis:
    """The measures of the last plan tracked in the bag read, and the bridge's.

    The measures of the last plan tracked in the bag read (hard_limits_rad: as measures'), and the bridge's if a
    bridge ran. The record's run_error (MissingTopic, BagError, ValueError) if it holds no run, its bridge_error if
    the bridge's reports could not be read.
    """
    if record.run is None:
        assert record.run_error is not None, "a RecordedBag without run has its run_error"
        raise record.run_error
    run_measures = measures(record.run, hard_limits_rad)
    if record.bridge_error is not None:
        raise record.bridge_error
    return RunAnalysis(run_measures, record.bridge)


def analyze(bag_path: Path, hard_limits_rad: Optional[HardLimits] = None) -> RunAnalysis:
    """The run analysis of the bag at bag_path.

    run_analysis of the bag at bag_path. BagError if the bag cannot be read; MissingTopic if it lacks what the
    measures need.
    """
    return run_analysis(read_bag(bag_path), hard_limits_rad)


@dataclasses.dataclass(frozen=True)
class JointMotion:
    """One joint's range and peak speed in a bag's joint_states, in the joint's unit (rad or m, per s)."""

    joint_name: str
    samples: int
    min_position: float
    max_position: float
    peak_speed: Optional[float]      # max |velocity|; None when the messages carry no velocities


@dataclasses.dataclass(frozen=True)
class JointStatesSummary:
    """What a bag's joint_states alone tell, by log time (when the recorder received each message)."""

    topic: str
    messages: int
    duration_s: float                # first to last message
    mean_rate_hz: Optional[float]    # (messages - 1) / duration_s; None under two messages or no duration
    longest_gap_s: Optional[float]   # between consecutive messages; None under two messages
    joints: tuple[JointMotion, ...]


def joint_states_summary(joint_states: JointStates) -> JointStatesSummary:
    """The messages' count, span, rate and longest gap, and each joint's range and peak speed."""
    topic, joints = joint_states.topic, joint_states.joints
    times = np.sort(joint_states.message_time_s)
    duration_s = float(times[-1] - times[0]) if len(times) else 0.0
    return JointStatesSummary(
        topic=topic, messages=len(times), duration_s=duration_s,
        mean_rate_hz=(len(times) - 1) / duration_s if len(times) > 1 and duration_s > 0.0 else None,
        longest_gap_s=float(np.diff(times).max()) if len(times) > 1 else None,
        joints=tuple(JointMotion(name, len(series.position), float(series.position.min()),
                                 float(series.position.max()),
                                 float(np.abs(series.velocity).max()) if len(series.velocity) else None)
                     for name, series in joints.items()))


@dataclasses.dataclass(frozen=True)
class BagAnalysis:
    """What swim-analyze makes of one bag.

    It holds the bag's topics, the joint motion when it has joint_states, the run's measures
    when it has what they need, and what it lacks, each with why.
    """

    info: BagInfo
    unknown_types: tuple[str, ...]           # the bag's message types this environment does not know (ours and
    #                                          ROS 2 Jazzy's); the bag's own definitions may still decode them
    joint_states: Optional[JointStatesSummary]
    run: Optional[RunAnalysis]
    missing: tuple[str, ...]                 # "what: why (what is not reported for it)"
    undecodable: tuple[tuple[str, str], ...] = ()   # (topic, why) for each topic whose messages cannot be decoded

    def to_json(self) -> dict[str, Any]:
        """The JSON form of the analysis, bag_summary.json's.

        bag_summary.json: the bag, its topics (each with whether its type is known here and, when its messages
        cannot be decoded, why), the joint motion, the run's measures (report.json's keys), what is missing.
        """
        undecodable = dict(self.undecodable)
        return {"bag": str(self.info.path), "storage": self.info.storage, "complete": self.info.complete,
                "topics": [{**dataclasses.asdict(topic), "type_known": topic.msgtype not in self.unknown_types,
                            "undecodable": undecodable.get(topic.name)}
                           for topic in self.info.topics],
                "joint_states": dataclasses.asdict(self.joint_states) if self.joint_states else None,
                "run_measures": self.run.to_json() if self.run else None,
                "missing": list(self.missing)}


def bag_analysis(record: RecordedBag, hard_limits_rad: Optional[HardLimits] = None) -> BagAnalysis:
    """All that swim-analyze can tell of the bag read.

    The hard_limits_rad argument is as measures'. What the bag lacks or holds unreadably is named in `missing`.
    """
    known_types = swim_typestore().fielddefs
    missing = []
    joints = None
    if record.joint_states is not None:
        joints = joint_states_summary(record.joint_states)
    elif isinstance(record.joint_states_error, MissingTopic):
        missing.append(f"/joint_states: {record.joint_states_error.reason} (no joint motion)")
    else:
        missing.append(f"/joint_states: {record.joint_states_error} (no joint motion)")
    run = None
    try:
        run = run_analysis(record, hard_limits_rad)
    except MissingTopic as err:
        hint = ": the tracker publishes it while it executes a plan" if err.topic == "/tracking_state" else ""
        missing.append(f"{err.topic}: {err.reason} (no run measures{hint})")
    except (ValueError, BagError) as err:   # ValueError: tracking_state messages that do not make a run
        missing.append(f"run measures: {err}")
    info = record.info
    return BagAnalysis(info, tuple(sorted({t.msgtype for t in info.topics if t.msgtype not in known_types})),
                       joints, run, tuple(missing), record.undecodable)


def analyze_bag(bag_path: Path, hard_limits_rad: Optional[HardLimits] = None) -> BagAnalysis:
    """The bag analysis of the bag at bag_path.

    bag_analysis of the bag at bag_path (a bag folder, or one .mcap or .db3 file). BagError if there is no
    readable bag there.
    """
    return bag_analysis(read_bag(bag_path), hard_limits_rad)


def bag_section(label: str, analysis: BagAnalysis) -> str:
    """The bag's topics, joint motion and what it lacks, as swim-analyze prints them."""
    info = analysis.info
    state = "" if info.complete else ", cut before its close (no metadata.yaml): read up to its last complete chunk"
    lines = [f"{label}: {info.storage} bag, {len(info.topics)} topics, {info.message_count} messages{state}"]
    width = max([len(t.name) for t in info.topics] + [5])
    type_width = max([len(t.msgtype) for t in info.topics] + [4])
    lines.append(f"  {'topic':<{width}}  {'type':<{type_width}}  {'messages':>8}")
    undecodable = dict(analysis.undecodable)
    for topic in info.topics:
        note = ("  not decodable" if topic.name in undecodable else
                "  type unknown here, defined in the bag" if topic.msgtype in analysis.unknown_types else "")
        lines.append(f"  {topic.name:<{width}}  {topic.msgtype:<{type_width}}  {topic.message_count:>8}{note}")
    if undecodable:
        lines.append("not decodable:")
        lines.extend(f"  {topic}: {why}" for topic, why in analysis.undecodable)
    motion = analysis.joint_states
    if motion is not None:
        rate = f"{motion.mean_rate_hz:.4g} Hz mean" if motion.mean_rate_hz is not None else "no rate"
        gap = f", longest gap {motion.longest_gap_s:.4g} s" if motion.longest_gap_s is not None else ""
        lines.append(f"joint motion ({motion.topic}: {motion.messages} messages over {motion.duration_s:.4g} s, "
                     f"{rate}{gap}); rad, or m for a prismatic joint such as R:")
        name_width = max([len(j.joint_name) for j in motion.joints] + [5])
        lines.append(f"  {'joint':<{name_width}}  {'samples':>8}  {'min':>11}  {'max':>11}  {'peak |velocity|':>15}")
        for joint in motion.joints:
            speed = _format(joint.peak_speed) if joint.peak_speed is not None else "-"
            lines.append(f"  {joint.joint_name:<{name_width}}  {joint.samples:>8}  {_format(joint.min_position):>11}"
                         f"  {_format(joint.max_position):>11}  {speed:>15}")
    if analysis.missing:
        lines.append("missing:")
        lines.extend(f"  {entry}" for entry in analysis.missing)
    return "\n".join(lines)


def summary_table(reports: Mapping[str, RunAnalysis]) -> str:
    """The measures of several runs side by side, a plain-text table.

    The measures of several runs (a RunReport is one) side by side, one column per run; a measure that only
    some runs have (the bridge's) is blank for the others.
    """
    columns = [report.measure_values() for report in reports.values()]
    rows = list(dict.fromkeys(key for values in columns for key in values))
    width = max(len(r) for r in rows)
    lines = [" " * width + "".join(f"  {name[-22:]:>22}" for name in reports)]
    for row in rows:
        cells = "".join(f"  {_format(values.get(row, '')):>22}" for values in columns)
        lines.append(f"{row:<{width}}{cells}")
    return "\n".join(lines)


def _format(value: Any) -> str:
    return f"{value:.4g}" if isinstance(value, float) else str(value)
