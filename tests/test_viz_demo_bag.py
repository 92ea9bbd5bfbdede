"""A swim-demo run draws the rig: its bag holds /robot_description, /tf_static, /tf and /markers from swim_viz's
nodes, they decode with the MCAP reader Foxglove maintains (mcap-ros2-support), and the recorded transforms put
the foil where eq. 40 puts it for the joint_states they were made from. docs/foxglove_layout.json reads the topics
and fields the demo bag holds, under the names it records them with."""
import json
import math
import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from conftest import WORKSPACE, run_demo

SHORT = ["constrained/accelerate/E0.05", "constrained/cruise/E0.05"]
MANEUVER_TIMEOUT_S = 120
VIZ_TOPICS = ("/robot_description", "/tf_static", "/tf", "/markers")
FOXGLOVE_LAYOUT = WORKSPACE / "docs" / "foxglove_layout.json"
#: rosbags' names of the numeric field types a Foxglove plot can draw
NUMERIC_TYPES = {"bool", "byte", "char", "int8", "int16", "int32", "int64", "uint8", "uint16", "uint32", "uint64",
                 "float32", "float64"}


@pytest.fixture(scope="module")
def foxglove_messages(ros_domain, tmp_path_factory):
    """{topic: [decoded message]} of the demo bag's topics, read with mcap-ros2-support."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    run_dir = tmp_path_factory.mktemp("viz_demo") / "run"
    run_demo(run_dir, "--primitives", *SHORT, "--repeats", "1", "1", "--timeout", str(MANEUVER_TIMEOUT_S))
    messages = {}
    with open(next((run_dir / "bag").glob("*.mcap")), "rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        for _, channel, _, decoded in reader.iter_decoded_messages():
            messages.setdefault(channel.topic, []).append(decoded)
    return messages


def quaternion_matrix(q):
    x, y, z, w = q.x, q.y, q.z, q.w
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def pose_in(transforms, frame, root="tank"):
    """The 4x4 pose of frame in root, composing the TransformStamped's from child to parent."""
    by_child = {t.child_frame_id: t for t in transforms}
    pose = np.eye(4)
    while frame != root:
        t = by_child[frame]
        local = np.eye(4)
        local[:3, :3] = quaternion_matrix(t.transform.rotation)
        local[:3, 3] = (t.transform.translation.x, t.transform.translation.y, t.transform.translation.z)
        pose = local @ pose
        frame = t.header.frame_id
    return pose


def test_the_visualization_topics_decode_with_foxgloves_reader(foxglove_messages):
    for topic in VIZ_TOPICS:
        assert foxglove_messages.get(topic), f"no {topic} in the bag"
    urdf = ET.fromstring(foxglove_messages["/robot_description"][-1].data)
    assert {link.get("name") for link in urdf.findall("link")} >= {"tank", "hub_arm", "platform", "foil"}
    assert foxglove_messages["/tf_static"][-1].transforms[0].child_frame_id == "foil"
    namespaces = {m.ns for array in foxglove_messages["/markers"] for m in array.markers}
    assert {"planned_platform", "planned_foil", "travelled_platform", "travelled_foil"} <= namespaces


def test_recorded_transforms_put_the_foil_where_eq40_does(foxglove_messages):
    from swim_model import load_rig
    rig = load_rig()
    ld, lh, lf = rig.heave_pivot_inset_m, rig.heave_link_length_m, rig.pitch_axis_to_foil_reference_m
    radius = rig.constrained_lane_radius_m   # the demo's constrained vehicle: its joint_states have no R
    states = {}
    for state in foxglove_messages["/joint_states"]:
        states[(state.header.stamp.sec, state.header.stamp.nanosec)] = dict(zip(state.name, state.position))
    static = foxglove_messages["/tf_static"][-1].transforms
    checked = 0
    for message in foxglove_messages["/tf"]:
        stamp = message.transforms[0].header.stamp
        q = states[(stamp.sec, stamp.nanosec)]   # each /tf is made from a recorded joint_states
        alpha, phi, theta = q["alpha"], q["phi"], q["theta"]
        # eq. 40: F = (R - Ld) e_r(alpha) + Lh dir(alpha + phi) + Lf dir(alpha + theta), dir(b) = (-sin b, cos b)
        foil_x = (radius - ld) * math.cos(alpha) - lh * math.sin(alpha + phi) - lf * math.sin(alpha + theta)
        foil_y = (radius - ld) * math.sin(alpha) + lh * math.cos(alpha + phi) + lf * math.cos(alpha + theta)
        pose = pose_in(list(message.transforms) + list(static), "foil")
        np.testing.assert_allclose(pose[:3, 3], (foil_x, foil_y, 0.0), rtol=0, atol=1e-9)
        # the foil frame's x along the chord, toward the leading edge: dir(alpha + theta)
        np.testing.assert_allclose(pose[:3, 0], (-math.sin(alpha + theta), math.cos(alpha + theta), 0.0), atol=1e-9)
        checked += 1
    assert checked >= 10


def layout_reads(layout):
    """What a Foxglove layout reads: (the topics its 3D panels show and load URDFs from, its plots' message paths
    as (topic, steps)); a step is a field name or an index, e.g. /tracking_state.error.positions[0] is
    ('/tracking_state', ['error', 'positions', 0])."""
    topics, paths = set(), []
    for panel in layout["configById"].values():
        topics.update(panel.get("topics", {}))
        topics.update(layer["topic"] for layer in panel.get("layers", {}).values()
                      if layer.get("sourceType") == "topic")
        for path in panel.get("paths", []):
            topic, fields = re.fullmatch(r"(/[^.]+)\.(.+)", path["value"]).groups()
            steps = []
            for field in fields.split("."):
                name, index = re.fullmatch(r"(\w+)(?:\[(\d+)\])?", field).groups()
                steps.extend([name] if index is None else [name, int(index)])
            paths.append((topic, steps))
    return topics, paths


def test_the_foxglove_layout_reads_run_topics_and_numeric_fields_of_their_types():
    """Without a run: every topic the layout names is one a run records (bag.RUN_TOPICS, by its full name), and each
    plotted path reaches a number in that topic's type (our installed messages')."""
    from rosbags.interfaces import Nodetype

    from swim_bringup.bag import RUN_TOPICS
    from swim_ros.typestore import swim_typestore
    topics, paths = layout_reads(json.loads(FOXGLOVE_LAYOUT.read_text()))
    assert topics and paths   # the 3D panel's markers and URDF, the plots' errors and torques
    assert topics | {topic for topic, _ in paths} <= set(RUN_TOPICS)
    store = swim_typestore()
    for topic, steps in paths:
        node = (Nodetype.NAME, RUN_TOPICS[topic])
        for step in steps:
            if isinstance(step, int):
                assert node[0] in (Nodetype.SEQUENCE, Nodetype.ARRAY), (topic, steps)
                node = node[1][0]
            else:
                assert node[0] == Nodetype.NAME, (topic, steps)
                node = dict(store.fielddefs[node[1]][1])[step]
        assert node[0] == Nodetype.BASE and node[1][0] in NUMERIC_TYPES, (topic, steps)


def test_the_demo_bag_holds_what_the_foxglove_layout_reads(foxglove_messages):
    """Opened on a demo bag, the layout's panels have their topics, and every message of a plotted topic has a
    finite number at each plotted path."""
    topics, paths = layout_reads(json.loads(FOXGLOVE_LAYOUT.read_text()))
    for topic in topics | {topic for topic, _ in paths}:
        assert foxglove_messages.get(topic), f"the layout reads {topic}, which the demo bag lacks"
    for topic, steps in paths:
        for message in foxglove_messages[topic]:
            value = message
            for step in steps:
                value = value[step] if isinstance(step, int) else getattr(value, step)
            assert math.isfinite(value), (topic, steps)
