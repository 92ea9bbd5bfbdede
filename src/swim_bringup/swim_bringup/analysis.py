"""swim-analyze: the paper's measures of a recorded run (Sec. 7), a JSON report, figures, side-by-side tables.

From the tracking_state topic (reference and measured q each control period) and the plan:
- two-norms of the errors, ||e||_2 = sqrt(int e(t)^2 dt): longitudinal R_d (alpha - alpha_d) in m, lateral
  R - R_d in m, Cartesian |p - p_d| of the platform's position p = R (cos alpha, sin alpha) in m;
- the final lateral offset and final alpha error, the duration, peak |torque| per motor, the fraction of
  periods with a saturated motor, the periods with the heave or the pitch at a hard limit (at the rig's stop: by
  default the shipped rig file's limits, which sim_node's stops also take; --rig for another rig's),
  and the energy used, int (|tau_h phidot| + |tau_p thetadot|) dt in J (motors do not take energy back, so
  negative power is counted as spent too).

Any rosbag2 bag opens (swim-demo's, swim-record's, one recorded by `ros2 bag record`, Humble's included; MCAP or
sqlite3): its topics are listed with their types and message counts, and those whose messages cannot be decoded (a
type neither the bag defines nor this environment knows: rosbag2 records no definition of a type it could not find)
named with why; from joint_states alone, each joint's range and peak speed and the messages' rate; the measures
above when the bag has what they need (tracking_state, and for the constrained vehicle the plan). A topic is found
under its full name (/joint_states: swim-demo's, swim-record's and rosbag2's), a relative one (joint_states, as
other recorders may give it) or one namespace (/test/joint_states). What a bag lacks is named, with why.

Exit status: 0 every bag analysed in full; 1 some bag lacked what the run's measures need (what it holds is
analysed, what it lacks named); 2 some bag could not be read (no bag at the path, a corrupt file) or the output
not written, or the arguments were wrong. Nothing a bag holds ends in a traceback.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
from pathlib import Path
from typing import Any, Mapping, Optional

import numpy as np

from swim_bringup.bag import RUN_TOPICS, BagError, BagInfo, bag_info, read_messages, undecodable_topics
from swim_ros.typestore import swim_typestore
from swim_bringup.reports import BridgeMeasures, RunAnalysis, RunMeasures
from swim_controller.measures import two_norm
from swim_model import RigConfigError, load_rig
from swim_model.limits import HardLimits


@dataclasses.dataclass
class Run:
    time_s: np.ndarray            # plan time of each tracked period
    q: np.ndarray                 # measured, (n, nq)
    qdot: np.ndarray
    q_reference: np.ndarray
    torque: np.ndarray            # commanded (heave, pitch), (n, 2)
    saturated: np.ndarray         # (n, 2) bool
    joint_names: list[str]
    lane_radius_m: float
    sliding_mode_enabled: bool


#: a foil joint within this of a hard limit is at its stop: about one encoder count there (the heave's 512 lines, x4,
#: through 43:1: 7.1e-5 rad; the pitch's through 25:1: 1.2e-4 rad); the simulator's stops hold a joint at the limit
HARD_STOP_TOLERANCE_RAD = 1.0e-4

#: swim-analyze's exit status: every bag analysed in full (the run's measures) ...
EXIT_FULL_REPORT = 0
#: ... some bag lacked what the run's measures need: what it holds was analysed, what it lacks named
EXIT_PARTIAL_REPORT = 1
#: ... some bag could not be read (or the output not written, or the arguments were wrong: argparse's status)
EXIT_UNREADABLE = 2


class MissingTopic(ValueError):
    """A topic the analysis needs that a bag lacks, or holds in a form it cannot use: which, and why."""

    def __init__(self, bag_path: Path, topic: str, reason: str) -> None:
        super().__init__(f"{bag_path}: {topic}: {reason}")
        self.topic, self.reason = topic, reason


def find_topic(info: BagInfo, name: str) -> str:
    """The bag's name for the run topic `name` (a key of bag.RUN_TOPICS, /joint_states): the topic recorded under
    that full name (swim-demo's, swim-record's and rosbag2's) or its relative one (joint_states) or, failing both,
    under one namespace (/test/joint_states). MissingTopic if there is none, several, one of another type than
    RUN_TOPICS gives, or one without messages."""
    bare = name.lstrip("/")
    candidates = ([topic for topic in info.topics if topic.name.lstrip("/") == bare]
                  or [topic for topic in info.topics if topic.name.endswith("/" + bare)])
    if not candidates:
        raise MissingTopic(info.path, name, "not in the bag")
    if len(candidates) > 1:
        raise MissingTopic(info.path, name, f"several topics could be it ({', '.join(t.name for t in candidates)})")
    topic = candidates[0]
    if topic.msgtype != RUN_TOPICS[name]:
        raise MissingTopic(info.path, name, f"{topic.name} is {topic.msgtype}, not {RUN_TOPICS[name]}")
    if topic.message_count == 0:
        raise MissingTopic(info.path, name, f"{topic.name} was recorded without messages")
    return topic.name


def load_run(bag_path: Path) -> Run:
    """The tracked periods of the last plan executed in the bag. MissingTopic if the bag has no tracking_state, or,
    for the constrained vehicle, no plan; BagError if the bag cannot be read."""
    info = bag_info(bag_path)
    tracking_topic = find_topic(info, "/tracking_state")
    try:
        topics: tuple[str, ...] = (tracking_topic, find_topic(info, "/plan"))
        no_plan = ""
    except MissingTopic as err:
        topics, no_plan = (tracking_topic,), err.reason
    rows: list[Any] = []   # the tracking_state messages (the typestore's class)
    lane_radius_m = None
    for topic, _, message in read_messages(bag_path, topics):
        if topic != tracking_topic:
            lane_radius_m = message.lane_radius_m
            continue
        if rows and message.plan_time_s < rows[-1].plan_time_s:
            rows = []   # a new plan started: keep the last one
        rows.append(message)
    if not rows:
        raise MissingTopic(bag_path, "/tracking_state", f"no message of {tracking_topic} could be read")
    if "alpha" not in rows[0].joint_names:
        raise MissingTopic(bag_path, "/tracking_state", f"its joints {list(rows[0].joint_names)} have no alpha")
    if lane_radius_m is None and "R" not in rows[0].joint_names:
        raise MissingTopic(bag_path, "/plan", f"no plan message ({no_plan}): the constrained vehicle's lane "
                                              f"radius, which turns its alpha errors into metres, is unknown")
    return Run(time_s=np.array([r.plan_time_s for r in rows]),
               q=np.array([r.feedback.positions for r in rows]),
               qdot=np.array([r.feedback.velocities for r in rows]),
               q_reference=np.array([r.reference.positions for r in rows]),
               torque=np.array([r.output_torques for r in rows]),
               saturated=np.array([r.torque_saturated for r in rows], dtype=bool),
               joint_names=list(rows[0].joint_names),
               lane_radius_m=float(lane_radius_m or 0.0),
               sliding_mode_enabled=bool(rows[-1].sliding_mode_enabled))


def _radius(run: Run, q: np.ndarray) -> np.ndarray:
    return q[:, run.joint_names.index("R")] if "R" in run.joint_names else np.full(len(q), run.lane_radius_m)


def hard_stop_periods(run: Run, hard_limits_rad: HardLimits) -> int:
    """The periods in which the heave or the pitch (the run's last two joints) is at or past one of its hard limits
    ((heave lower, upper), (pitch lower, upper), rad), to within HARD_STOP_TOLERANCE_RAD."""
    (heave_lower, heave_upper), (pitch_lower, pitch_upper) = hard_limits_rad
    foil = run.q[:, -2:]
    at_stop = ((foil <= np.array([heave_lower, pitch_lower]) + HARD_STOP_TOLERANCE_RAD)
               | (foil >= np.array([heave_upper, pitch_upper]) - HARD_STOP_TOLERANCE_RAD))
    return int(at_stop.any(axis=1).sum())


def measures(run: Run, hard_limits_rad: Optional[HardLimits] = None) -> RunMeasures:
    """The run's measures; its hard stops are hard_limits_rad's, by default the shipped rig's (its limits)."""
    if hard_limits_rad is None:
        hard_limits_rad = load_rig().hard_limits_rad
    alpha = run.joint_names.index("alpha")
    radius, radius_reference = _radius(run, run.q), _radius(run, run.q_reference)
    alpha_error = run.q[:, alpha] - run.q_reference[:, alpha]
    position = radius[:, None] * np.column_stack([np.cos(run.q[:, alpha]), np.sin(run.q[:, alpha])])
    reference = radius_reference[:, None] * np.column_stack([np.cos(run.q_reference[:, alpha]),
                                                             np.sin(run.q_reference[:, alpha])])
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


def bridge_measures(bag_path: Path) -> Optional[BridgeMeasures]:
    """From a bridge_node's /diagnostics in the bag (None without any): the faults it latched during the run (a
    latched fault holds the motors at zero until reset: the vehicle did not swim as commanded from then on) and
    its count of overrun periods."""
    try:
        topic = find_topic(bag_info(bag_path), "/diagnostics")
    except MissingTopic:
        return None
    faults: set[str] = set()
    overruns = None
    timing: dict[str, str] = {}
    for _, _, array in read_messages(bag_path, (topic,)):
        for status in array.status:
            if status.name.endswith("bridge_node: I/O loop"):
                values = {pair.key: pair.value for pair in status.values}
                faults.update(name for name in values.get("faults", "NONE").split("|") if name != "NONE")
                overruns = int(values.get("overruns", overruns or 0))
                if "worst_lateness_ms" in values:
                    timing = values
    if overruns is None:
        return None

    def number(key: str) -> Optional[float]:
        try:
            value = float(timing[key])
        except (KeyError, ValueError):
            return None
        return value if math.isfinite(value) else None

    return BridgeMeasures(
        bridge_faults="|".join(sorted(faults)) or "NONE", bridge_overruns=overruns,
        bridge_worst_lateness_ms=number("worst_lateness_ms"),
        bridge_overrun_cause=timing.get("worst_lateness_cause"),
        bridge_wake_lateness_p99_ms=number("wake_lateness_p99_ms"),
        bridge_command_latency_p50_ms=number("command_latency_p50_ms"),
        bridge_command_latency_p99_ms=number("command_latency_p99_ms"),
        bridge_command_jitter_p50_ms=number("command_jitter_p50_ms"),
        bridge_command_jitter_p99_ms=number("command_jitter_p99_ms"))


def analyze(bag_path: Path, hard_limits_rad: Optional[HardLimits] = None) -> RunAnalysis:
    """The measures of the last plan tracked in the bag (hard_limits_rad: as measures'), and the bridge's if a
    bridge ran."""
    return RunAnalysis(measures(load_run(bag_path), hard_limits_rad), bridge_measures(bag_path))


@dataclasses.dataclass(frozen=True)
class JointSeries:
    """One joint's samples in a bag's joint_states: log time (when the recorder received the message) in s from
    the topic's first message, position and velocity in the joint's unit (rad for a revolute joint, m for a
    prismatic one such as R; per s for the velocity), each (n,); velocity is empty when the messages carry none."""
    time_s: np.ndarray
    position: np.ndarray
    velocity: np.ndarray


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


def read_joint_states(bag_path: Path, topic: str) -> tuple[np.ndarray, dict[str, JointSeries]]:
    """The log times (s, from the first message) of the sensor_msgs/JointState messages on topic, (messages,),
    and each joint's samples by name, in the order the joints first appear. A message whose position (velocity)
    list is shorter than its names gives no position (velocity) for the joints past its end."""
    log_ns: list[int] = []
    samples: dict[str, tuple[list[int], list[float], list[float]]] = {}
    for _, stamp_ns, message in read_messages(bag_path, (topic,)):
        log_ns.append(stamp_ns)
        for k, name in enumerate(message.name):
            if k < len(message.position):
                times, positions, velocities = samples.setdefault(name, ([], [], []))
                times.append(stamp_ns)
                positions.append(float(message.position[k]))
                if k < len(message.velocity):
                    velocities.append(float(message.velocity[k]))
    start_ns = min(log_ns, default=0)

    def seconds(stamps: list[int]) -> np.ndarray:
        return (np.array(stamps, dtype=np.int64) - start_ns) * 1e-9
    return seconds(log_ns), {name: JointSeries(seconds(times), np.array(positions),
                                               np.array(velocities) if len(velocities) == len(times) else
                                               np.zeros(0))
                             for name, (times, positions, velocities) in samples.items()}


def joint_states_summary(topic: str, message_time_s: np.ndarray,
                         joints: Mapping[str, JointSeries]) -> JointStatesSummary:
    """The messages' count, span, rate and longest gap, and each joint's range and peak speed."""
    times = np.sort(message_time_s)
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
    """What swim-analyze makes of one bag: its topics, the joint motion when it has joint_states, the run's measures
    when it has what they need, and what it lacks, each with why."""
    info: BagInfo
    unknown_types: tuple[str, ...]           # the bag's message types this environment does not know (ours and
    #                                          ROS 2 Jazzy's); the bag's own definitions may still decode them
    joint_states: Optional[JointStatesSummary]
    run: Optional[RunAnalysis]
    missing: tuple[str, ...]                 # "what: why (what is not reported for it)"
    undecodable: tuple[tuple[str, str], ...] = ()   # (topic, why) for each topic whose messages cannot be decoded

    def to_json(self) -> dict[str, Any]:
        """bag_summary.json: the bag, its topics (each with whether its type is known here and, when its messages
        cannot be decoded, why), the joint motion, the run's measures (report.json's keys), what is missing."""
        undecodable = dict(self.undecodable)
        return {"bag": str(self.info.path), "storage": self.info.storage, "complete": self.info.complete,
                "topics": [{**dataclasses.asdict(topic), "type_known": topic.msgtype not in self.unknown_types,
                            "undecodable": undecodable.get(topic.name)}
                           for topic in self.info.topics],
                "joint_states": dataclasses.asdict(self.joint_states) if self.joint_states else None,
                "run_measures": self.run.to_json() if self.run else None,
                "missing": list(self.missing)}


def analyze_bag(bag_path: Path, hard_limits_rad: Optional[HardLimits] = None) -> BagAnalysis:
    """All that swim-analyze can tell of the bag at bag_path (a bag folder, or one .mcap or .db3 file; hard_limits_rad:
    as measures'). BagError if there is no readable bag there; anything else the bag lacks or holds unreadably is
    named in `missing`."""
    info = bag_info(bag_path)
    known_types = swim_typestore().fielddefs
    missing = []
    joints = None
    try:
        topic = find_topic(info, "/joint_states")
        joints = joint_states_summary(topic, *read_joint_states(bag_path, topic))
    except MissingTopic as err:
        missing.append(f"/joint_states: {err.reason} (no joint motion)")
    except BagError as err:
        missing.append(f"/joint_states: {err} (no joint motion)")
    run = None
    try:
        run = analyze(bag_path, hard_limits_rad)
    except MissingTopic as err:
        hint = ": the tracker publishes it while it executes a plan" if err.topic == "/tracking_state" else ""
        missing.append(f"{err.topic}: {err.reason} (no run measures{hint})")
    except (ValueError, BagError) as err:   # ValueError: tracking_state messages that do not make a run
        missing.append(f"run measures: {err}")
    return BagAnalysis(info, tuple(sorted({t.msgtype for t in info.topics if t.msgtype not in known_types})),
                       joints, run, tuple(missing), tuple(sorted(undecodable_topics(bag_path).items())))


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


def write_joint_figure(joints: Mapping[str, JointSeries], path: Path) -> Path:
    """Each joint's position against log time, one panel per joint."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    figure, axes = plt.subplots(max(len(joints), 1), 1, sharex=True, figsize=(8, 1.0 + 1.8 * max(len(joints), 1)),
                                squeeze=False)
    for axis, (name, series) in zip(axes[:, 0], joints.items()):
        axis.plot(series.time_s, series.position)
        axis.set_ylabel(name)
    axes[-1, 0].set_xlabel("log time [s]")
    return save_figure(figure, path)


def write_figures(bag_path: Path, output_dir: Path) -> list[Path]:
    """Desired vs actual alpha and alphadot (Figs. 19-20 style), heave and pitch, the Cartesian path; with the vortex
    wake recorded, its last vortices over the path (wake.png)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    run = load_run(bag_path)
    output_dir.mkdir(parents=True, exist_ok=True)
    alpha = run.joint_names.index("alpha")
    paths = []
    figure, axes = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
    axes[0].plot(run.time_s, run.q_reference[:, alpha], "--", label="desired")
    axes[0].plot(run.time_s, run.q[:, alpha], label="actual")
    axes[0].set_ylabel("alpha [rad]")
    axes[0].legend()
    axes[1].plot(run.time_s, run.qdot[:, alpha], label="actual")
    axes[1].set_ylabel("alphadot [rad/s]")
    axes[1].set_xlabel("plan time [s]")
    paths.append(save_figure(figure, output_dir / "displacement.png"))
    figure, axes = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
    for axis, column, name in ((axes[0], -2, "phi (heave)"), (axes[1], -1, "theta (pitch)")):
        axis.plot(run.time_s, run.q_reference[:, column], "--", label="desired")
        axis.plot(run.time_s, run.q[:, column], label="actual")
        axis.set_ylabel(f"{name} [rad]")
    axes[0].legend()
    axes[1].set_xlabel("plan time [s]")
    paths.append(save_figure(figure, output_dir / "heave_pitch.png"))
    figure, axis = plt.subplots(figsize=(6, 6))
    for q, style, label in ((run.q_reference, "--", "desired"), (run.q, "-", "actual")):
        radius = _radius(run, q)
        axis.plot(radius * np.cos(q[:, alpha]), radius * np.sin(q[:, alpha]), style, label=label)
    axis.set_aspect("equal")
    axis.set_xlabel("x [m]")
    axis.set_ylabel("y [m]")
    axis.legend()
    paths.append(save_figure(figure, output_dir / "cartesian_path.png"))
    wake = [message for _, _, message in read_messages(bag_path, ("/wake_vortices",))]
    if wake:   # a run in the vortex wake (sim_node's flow: wake): its last vortices over the path
        from swim_bringup.wake_figure import write_wake_figure

        def tank_xy(q: np.ndarray) -> np.ndarray:
            radius = _radius(run, q)
            return np.column_stack([radius * np.cos(q[:, alpha]), radius * np.sin(q[:, alpha])])
        last = wake[-1]
        paths.append(write_wake_figure(output_dir / "wake.png", tank_xy(run.q),
                                       np.column_stack([last.x_m, last.y_m]), np.asarray(last.circulations_m2_s),
                                       reference_xy_m=tank_xy(run.q_reference),
                                       tank_radius_m=0.5 * load_rig().tank_diameter_m))
    return paths


def save_figure(figure, path: Path) -> Path:
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    import matplotlib.pyplot as plt
    plt.close(figure)
    return path


def summary_table(reports: Mapping[str, RunAnalysis]) -> str:
    """The measures of several runs (a RunReport is one) side by side, one column per run; a measure that only
    some runs have (the bridge's) is blank for the others."""
    columns = [report.measure_values() for report in reports.values()]
    rows = list(dict.fromkeys(key for values in columns for key in values))
    width = max(len(r) for r in rows)
    lines = [" " * width + "".join(f"  {name[-22:]:>22}" for name in reports)]
    for row in rows:
        cells = "".join(f"  {_format(values.get(row, '')):>22}" for values in columns)
        lines.append(f"{row:<{width}}{cells}")
    return "\n".join(lines)


def _format(value) -> str:
    return f"{value:.4g}" if isinstance(value, float) else str(value)


def _label(bag: Path) -> str:
    return bag.parent.name if bag.name == "bag" else str(bag)   # a run folder's bag is named for its folder


def write_outputs(bag_path: Path, analysis: BagAnalysis, output_dir: Path) -> list[Path]:
    """bag_summary.json always; joint_states.png with joint_states; with the run's measures, report.json and the
    run's figures (write_figures)."""
    output_dir.mkdir(parents=True, exist_ok=True)
    paths = [output_dir / "bag_summary.json"]
    paths[0].write_text(json.dumps(analysis.to_json(), indent=2))
    if analysis.joint_states is not None:
        _, joints = read_joint_states(bag_path, analysis.joint_states.topic)
        paths.append(write_joint_figure(joints, output_dir / "joint_states.png"))
    if analysis.run is not None:
        paths.append(output_dir / "report.json")
        paths[-1].write_text(json.dumps(analysis.run.to_json(), indent=2))
        paths.extend(write_figures(bag_path, output_dir))
    return paths


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="swim-analyze", description=__doc__.splitlines()[0],
        epilog=f"exit status: {EXIT_FULL_REPORT} every bag analysed in full; {EXIT_PARTIAL_REPORT} some bag lacked "
               f"what the run's measures need (the rest analysed, what it lacks named); {EXIT_UNREADABLE} some bag "
               f"could not be read, or the output not written")
    parser.add_argument("bags", type=Path, nargs="+",
                        help="rosbag2 bags: folders, or single .mcap or .db3 files (several: a side-by-side table)")
    parser.add_argument("--output", type=Path, default=None,
                        help="folder for bag_summary.json, report.json and figures (one bag)")
    parser.add_argument("--rig", type=Path, default=None,
                        help="the rig file, whose hard stops (its limits) hard_stop_periods counts (default: "
                             "swim_model's shipped rig, every node's when its rig_path is empty)")
    args = parser.parse_args(argv)
    try:
        hard_limits_rad = load_rig(args.rig).hard_limits_rad
    except RigConfigError as err:
        print(f"swim-analyze: --rig: {err}", file=sys.stderr)
        return EXIT_UNREADABLE
    status = EXIT_FULL_REPORT
    analyses: dict[str, BagAnalysis] = {}
    for bag in args.bags:
        try:
            analyses[_label(bag)] = analysis = analyze_bag(bag, hard_limits_rad)
        except BagError as err:
            print(f"swim-analyze: {err}", file=sys.stderr)
            status = max(status, EXIT_UNREADABLE)
            continue
        print(bag_section(_label(bag), analysis) + "\n")
        if analysis.run is None:
            status = max(status, EXIT_PARTIAL_REPORT)
    runs = {label: analysis.run for label, analysis in analyses.items() if analysis.run is not None}
    if runs:
        print(summary_table(runs))
    if args.output is not None and len(args.bags) == 1 and analyses:
        try:
            write_outputs(args.bags[0], next(iter(analyses.values())), args.output)
        except (OSError, BagError) as err:
            print(f"swim-analyze: {args.output}: not written: {err}", file=sys.stderr)
            status = EXIT_UNREADABLE
    return status


if __name__ == "__main__":
    sys.exit(main())
