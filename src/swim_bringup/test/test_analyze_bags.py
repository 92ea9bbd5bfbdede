"""swim-analyze on bags other than swim-demo's (no ROS): relative topic names, joint_states alone, a
sqlite3 bag with a type this environment does not know, and paths that are no bag. What it reports is checked
against what was written; a bag that lacks something gets its other parts analysed and the missing part named."""
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from conftest import tracking_state_cdr
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import get_types_from_msg

from swim_bringup.analysis import analyze, analyze_bag
from swim_bringup.analysis_cli import EXIT_FULL_REPORT, EXIT_PARTIAL_REPORT, EXIT_UNREADABLE, main
from swim_bringup.bag import RUN_TOPICS, BagWriter, bag_info, read_messages
from swim_model.rig import default_rig_path
from swim_ros.processes import run_child
from swim_ros.typestore import swim_typestore

PERIOD_S, PERIODS = 0.008, 251                  # 2 s of tracking at the controller's period
LANE_M, ALPHA_OFFSET_RAD = 0.43, 0.02
JOINTS = ["alpha", "phi", "theta"]              # the constrained vehicle
MEASURED = ("/joint_states", "/tracking_state", "/plan")   # the run topics (RUN_TOPICS' names) the measures read


def joint_state_cdr(store, stamp_ns, names, positions, velocities=()):
    types = store.types
    stamp = types["builtin_interfaces/msg/Time"](stamp_ns // 1_000_000_000, stamp_ns % 1_000_000_000)
    message = types["sensor_msgs/msg/JointState"](types["std_msgs/msg/Header"](stamp, ""), list(names),
                                                  np.array(positions, float), np.array(velocities, float),
                                                  np.zeros(0))
    return bytes(store.serialize_cdr(message, "sensor_msgs/msg/JointState"))


def plan_cdr(store, lane_radius_m):
    """A constrained PlannedTrajectory that carries its lane (the analysis reads nothing else of it)."""
    types = store.types
    header = types["std_msgs/msg/Header"](types["builtin_interfaces/msg/Time"](1, 0), "")
    empty = np.zeros(0)
    plan_type = types["swim_interfaces/msg/PlannedTrajectory"]
    message = plan_type(header=header, interface_version=plan_type.INTERFACE_VERSION, constrained=True,
                        lane_radius_m=lane_radius_m, flow_model="ideal", joint_names=JOINTS, time_from_start_s=empty,
                        positions=empty, velocities=empty, foil_accelerations=empty, feedforward_torques=empty,
                        lag_states=empty, disturbance_bounds_n_m=empty, lqr_gains=empty, sliding_gains=empty,
                        segments=[], library_digest="")
    return bytes(store.serialize_cdr(message, "swim_interfaces/msg/PlannedTrajectory"))


def record_constrained_run(path, names, store=None):
    """A constrained run ALPHA_OFFSET_RAD behind its plan for 2 s, under the topic names given: names maps each of
    MEASURED to the bag's name for it. store: the type store whose definitions the bag carries (default: the
    installed ones)."""
    writer = BagWriter(path, {})
    if store is not None:
        writer.store = store
    for topic in MEASURED:
        writer.add_topic(names[topic], RUN_TOPICS[topic])
    writer.write(names["/plan"], 1, plan_cdr(writer.store, LANE_M))
    for k in range(PERIODS):
        time_s = k * PERIOD_S
        reference = [0.3 * time_s, math.sin(time_s), math.cos(time_s)]
        feedback = [reference[0] - ALPHA_OFFSET_RAD, *reference[1:]]
        stamp_ns = 1_000_000_000 + round(time_s * 1e9)
        writer.write(names["/tracking_state"], stamp_ns,
                     tracking_state_cdr(writer.store, JOINTS, stamp_ns, time_s, feedback, reference))
        writer.write(names["/joint_states"], stamp_ns, joint_state_cdr(writer.store, stamp_ns, JOINTS, feedback))
    writer.close()
    return path


def test_a_bag_of_relative_topic_names_is_measured_as_one_of_full_names(tmp_path, capsys):
    """swim-demo, swim-record and rosbag2 name topics in full (/joint_states); a bag whose topics are relative
    (joint_states, as a recorder that subscribes by the nodes' own names writes them) is measured alike."""
    full = record_constrained_run(tmp_path / "full", {t: t for t in MEASURED})
    relative = record_constrained_run(tmp_path / "relative", {t: t.lstrip("/") for t in MEASURED})
    assert [t.name for t in bag_info(relative).topics] == ["joint_states", "tracking_state", "plan"]
    assert analyze(relative) == analyze(full)
    # alpha behind by a constant offset for 2 s: R_d * offset * sqrt(2 s)
    longitudinal = analyze(relative).measures.longitudinal_error_two_norm_m_s05
    assert longitudinal == pytest.approx(LANE_M * ALPHA_OFFSET_RAD * math.sqrt((PERIODS - 1) * PERIOD_S))
    for bag, joint_states in ((full, "/joint_states"), (relative, "joint_states")):
        assert main([str(bag)]) == EXIT_FULL_REPORT
        out = capsys.readouterr().out
        assert "missing" not in out and "longitudinal_error_two_norm_m_s05" in out
        analysis = analyze_bag(bag)
        motion = analysis.joint_states
        assert analysis.missing == () and analysis.run == analyze(full)
        assert motion is not None and motion.topic == joint_states and motion.messages == PERIODS
    alpha = next(j for j in motion.joints if j.joint_name == "alpha")
    assert (alpha.min_position, alpha.max_position) == pytest.approx(
        (-ALPHA_OFFSET_RAD, 0.3 * (PERIODS - 1) * PERIOD_S - ALPHA_OFFSET_RAD))


def test_another_rigs_stops_come_from_its_rig_file(tmp_path, capsys):
    """--rig: the heave sin t (rad) of the recorded run reaches another rig's 45 degree stop from
    t = asin(pi / 4) on (the shipped 60 degree one, never); a rig file that cannot be read is refused, nothing
    analysed."""
    bag = record_constrained_run(tmp_path / "run", {t: t for t in MEASURED})
    assert analyze(bag).measures.hard_stop_periods == 0
    document = yaml.safe_load(default_rig_path().read_text())
    document["limits"]["heave_hard_stop"]["value"] = 45
    document["limits"]["heave_planning_range"]["value"] = 35   # the soft margin still fits below the stop
    other_rig = tmp_path / "other_rig.yaml"
    other_rig.write_text(yaml.safe_dump(document))
    assert main([str(bag), "--rig", str(other_rig), "--output", str(tmp_path / "out")]) == EXIT_FULL_REPORT
    report = json.loads((tmp_path / "out" / "report.json").read_text())
    times_s = np.arange(PERIODS) * PERIOD_S
    assert report["hard_stop_periods"] == np.sum(np.sin(times_s) >= math.pi / 4 - 1e-4) > 0
    capsys.readouterr()
    assert main([str(bag), "--rig", str(tmp_path / "no_such.yaml")]) == EXIT_UNREADABLE
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.startswith("swim-analyze: --rig: ")


def test_a_namespaced_plan_of_another_type_is_named_not_read(tmp_path, capsys):
    """A navigation stack's /plan (nav_msgs/Path) is not ours: the constrained run's lane stays unknown, said so."""
    names = {topic: "/test" + topic for topic in MEASURED}
    writer = BagWriter(tmp_path / "bag", {names["/tracking_state"]: RUN_TOPICS["/tracking_state"],
                                          "/plan": "nav_msgs/msg/Path"})
    path_type = writer.store.types["nav_msgs/msg/Path"]
    header = writer.store.types["std_msgs/msg/Header"](writer.store.types["builtin_interfaces/msg/Time"](0, 0), "")
    writer.write("/plan", 1, bytes(writer.store.serialize_cdr(path_type(header, []), "nav_msgs/msg/Path")))
    for k in range(3):
        writer.write(names["/tracking_state"], k + 2,
                     tracking_state_cdr(writer.store, JOINTS, k, k * PERIOD_S, [0.0] * 3, [0.0] * 3))
    writer.close()
    analysis = analyze_bag(tmp_path / "bag")
    assert analysis.run is None
    assert any(entry.startswith("/plan: no plan message (/plan is nav_msgs/msg/Path, not "
                                "swim_interfaces/msg/PlannedTrajectory)") for entry in analysis.missing)
    assert main([str(tmp_path / "bag")]) == EXIT_PARTIAL_REPORT
    assert "/plan: no plan message" in capsys.readouterr().out


def test_joint_states_alone_give_ranges_rates_and_the_missing_topics_named(tmp_path, capsys):
    """100 Hz for 2 s with one 50 ms hole: the rate, the gap and each joint's range come from the messages alone."""
    rate_hz, gap_s = 100.0, 0.05
    time_s = np.concatenate([np.arange(0.0, 1.0, 1 / rate_hz), np.arange(1.0 - 1 / rate_hz + gap_s, 2.0, 1 / rate_hz)])
    heave = 0.2 * np.sin(2 * np.pi * time_s)
    heave_rate = 0.4 * np.pi * np.cos(2 * np.pi * time_s)
    writer = BagWriter(tmp_path / "bag", {"/joint_states": "sensor_msgs/msg/JointState"})
    for t, phi, phidot in zip(time_s, heave, heave_rate):
        stamp_ns = 5_000_000_000 + round(t * 1e9)
        writer.write("/joint_states", stamp_ns,
                     joint_state_cdr(writer.store, stamp_ns, ["alpha", "phi"], [0.3 * t, phi], [0.3, phidot]))
    writer.close()
    analysis = analyze_bag(tmp_path / "bag")
    motion = analysis.joint_states
    assert analysis.run is None and motion is not None
    assert motion.messages == len(time_s)
    assert motion.duration_s == pytest.approx(time_s[-1] - time_s[0])
    assert motion.mean_rate_hz == pytest.approx((len(time_s) - 1) / (time_s[-1] - time_s[0]))
    assert motion.longest_gap_s == pytest.approx(gap_s)
    alpha, phi = motion.joints
    assert (alpha.joint_name, alpha.min_position, alpha.max_position) == ("alpha", 0.0, pytest.approx(0.3 * time_s[-1]))
    assert (phi.min_position, phi.max_position) == pytest.approx((heave.min(), heave.max()))
    assert phi.peak_speed == pytest.approx(np.abs(heave_rate).max()) and phi.samples == len(time_s)
    assert [entry.split(":")[0] for entry in analysis.missing] == ["/tracking_state"]

    assert main([str(tmp_path / "bag"), "--output", str(tmp_path / "out")]) == EXIT_PARTIAL_REPORT
    out = capsys.readouterr().out
    assert "/tracking_state: not in the bag (no run measures" in out and "joint motion (/joint_states" in out
    summary = json.loads((tmp_path / "out" / "bag_summary.json").read_text())
    assert summary["run_measures"] is None and summary["joint_states"]["messages"] == len(time_s)
    assert (tmp_path / "out" / "joint_states.png").stat().st_size > 0
    assert not (tmp_path / "out" / "report.json").exists()


def test_a_cut_bag_counts_what_its_complete_chunks_hold(tmp_path):
    """A recorder killed after a flush: the topics and counts come from a linear read, up to the flush."""
    writer = BagWriter(tmp_path / "bag", {"/joint_states": "sensor_msgs/msg/JointState",
                                          "/tf": "tf2_msgs/msg/TFMessage"})
    for k in range(20):
        writer.write("/joint_states", k + 1, joint_state_cdr(writer.store, k, ["alpha"], [0.01 * k]))
    writer.flush()
    info = bag_info(tmp_path / "bag")   # not closed: no metadata.yaml
    assert not info.complete
    assert {(t.name, t.message_count) for t in info.topics} == {("/joint_states", 20), ("/tf", 0)}
    assert analyze_bag(tmp_path / "bag").joint_states.messages == 20
    writer.close()


THING_MSG = "float64 value\nstring label\n"


def test_a_sqlite3_bag_with_a_type_unknown_here(tmp_path, capsys):
    """A sqlite3 bag (rosbag2's default storage before Jazzy) with a topic whose type only its recorder knew: the
    topic is listed, not decoded, and the joint_states beside it are analysed."""
    store = swim_typestore()
    store.register(get_types_from_msg(THING_MSG, "other_msgs/msg/Thing"))
    writer = Writer(tmp_path / "bag", version=9, storage_plugin=StoragePlugin.SQLITE3)
    writer.open()
    things = writer.add_connection("/thing", "other_msgs/msg/Thing", typestore=store)
    joints = writer.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=store)
    for k in range(7):
        thing = store.types["other_msgs/msg/Thing"](float(k), "k")
        writer.write(things, 10 + k, bytes(store.serialize_cdr(thing, "other_msgs/msg/Thing")))
    for k in range(4):
        writer.write(joints, 20 + k, joint_state_cdr(store, 20 + k, ["theta"], [0.1 * k]))
    writer.close()
    bag = tmp_path / "bag"
    analysis = analyze_bag(bag)
    assert analysis.info.storage == "sqlite3" and analysis.unknown_types == ("other_msgs/msg/Thing",)
    assert {(t.name, t.message_count) for t in analysis.info.topics} == {("/thing", 7), ("/joint_states", 4)}
    theta, = analysis.joint_states.joints
    assert (theta.min_position, theta.max_position) == pytest.approx((0.0, 0.3))
    assert list(read_messages(bag, ("/tracking_state",))) == []   # absent: nothing, not every message of the bag
    assert main([str(bag)]) == EXIT_PARTIAL_REPORT
    assert "other_msgs/msg/Thing" in capsys.readouterr().out
    # the .db3 file itself opens as its folder does
    database, = bag.glob("*.db3")
    assert set(analyze_bag(database).info.topics) == set(analysis.info.topics)


def corrupt_inputs(root: Path) -> list[Path]:
    """Paths that hold no readable bag: nothing, an empty folder, a text file, a folder whose metadata.yaml is not
    YAML, a closed bag whose MCAP file was overwritten, a .mcap file of noise."""
    (root / "empty").mkdir()
    (root / "notes.txt").write_text("not a bag\n")
    (root / "bad_yaml").mkdir()
    (root / "bad_yaml" / "metadata.yaml").write_text("rosbag2_bagfile_information: [\n")
    writer = BagWriter(root / "overwritten", {"/chatter": "std_msgs/msg/String"})
    writer.close()
    mcap_file, = (root / "overwritten").glob("*.mcap")
    mcap_file.write_bytes(b"\x00" * 512)
    (root / "noise.mcap").write_bytes(bytes(range(256)) * 4)
    return [root / "nothing_here", root / "empty", root / "notes.txt", root / "bad_yaml", root / "overwritten",
            root / "noise.mcap"]


def test_what_is_no_bag_is_an_error_that_names_it(tmp_path, capsys):
    for path in corrupt_inputs(tmp_path):
        assert main([str(path)]) == EXIT_UNREADABLE, path
        captured = capsys.readouterr()
        assert captured.out == "" and captured.err.startswith(f"swim-analyze: {path}"), captured.err


def test_a_corrupt_bag_beside_a_good_one_no_traceback(tmp_path):
    """swim-analyze in a process of its own on a good bag and a corrupt one: the good one is reported, the other
    named; no traceback."""
    good = record_constrained_run(tmp_path / "good", {t: t for t in MEASURED})
    bad = corrupt_inputs(tmp_path)[-1]
    result = run_child([sys.executable, "-m", "swim_bringup.analysis_cli", str(good), str(bad)],
                       capture_output=True, text=True, timeout_s=120)
    assert result.returncode == EXIT_UNREADABLE
    assert "Traceback" not in result.stderr and result.stderr.startswith(f"swim-analyze: {bad}")
    assert "longitudinal_error_two_norm_m_s05" in result.stdout


def test_a_version_4_bag_analyses_as_this_versions(tmp_path):
    """Version 5 changed no message a run records: a bag written with version 4's PlannedTrajectory definition
    (its INTERFACE_VERSION constant 4) reads back with it and is measured as the same run written with version 5's."""
    from ament_index_python.packages import get_package_share_directory
    from rosbags.typesys import Stores, get_typestore
    store = get_typestore(Stores.ROS2_JAZZY)
    for path in sorted((Path(get_package_share_directory("swim_interfaces")) / "msg").glob("*.msg")):
        text = path.read_text()
        if path.stem == "PlannedTrajectory":
            assert "uint32 INTERFACE_VERSION = 5" in text
            text = text.replace("INTERFACE_VERSION = 5", "INTERFACE_VERSION = 4")
        store.register(get_types_from_msg(text, f"swim_interfaces/msg/{path.stem}"))
    names = {t: t for t in MEASURED}
    current = record_constrained_run(tmp_path / "v5", names)
    older = record_constrained_run(tmp_path / "v4", names, store)
    (_, _, plan), = read_messages(older, ("/plan",))
    assert (plan.INTERFACE_VERSION, plan.interface_version) == (4, 4)
    assert analyze(older) == analyze(current)
