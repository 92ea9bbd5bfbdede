"""swim-analyze on bags recorded by rosbag2 itself (no ROS): a cut of a bag that rosbag2 (ROS 2 Humble) recorded
(data/rosbag2_humble: SOURCE.md says where it comes from and how it was cut), and MCAP files written here in its
layout. rosbag2 writes a schema of encoding 'unknown', with no definition, for a type whose definition it could not
find, which rosbags cannot open: such bags are read with the mcap library (Foxglove's reader); every topic is listed,
what decodes is decoded and checked against Foxglove's own decoder or against what was written, and the topics whose
messages cannot be decoded are named with why."""
import json
import math
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.records import Chunk, Message
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap.writer import CompressionType, Writer
from rosbags.rosbag2 import Reader

from swim_bringup.analysis import analyze_bag
from swim_bringup.analysis_cli import EXIT_PARTIAL_REPORT, main
from swim_bringup.bag import BagError, bag_info, read_messages, undecodable_topics
from swim_ros.processes import run_child
from swim_ros.typestore import swim_typestore

HUMBLE_BAG = Path(__file__).parent / "data" / "rosbag2_humble" / "bagfile_0_cut.mcap"
#: the topics of the Humble bag whose schema rosbag2 wrote with encoding 'unknown' (action feedback messages)
HUMBLE_UNKNOWN_SCHEMA_TOPICS = {
    "/reference_hardstops/_action/feedback": "capstan/action/ReferenceHardstops_FeedbackMessage",
    "/motionless_self_test/_action/feedback": "capstan/action/MotionlessSelfTest_FeedbackMessage"}


def mcap_summary(path):
    with open(path, "rb") as stream:
        return make_reader(stream).get_summary()


def test_the_humble_bag_is_rosbag2s_and_rosbags_cannot_open_it():
    """The case the fallback is for: rosbag2's header and metadata, two schemas of encoding 'unknown', and rosbags'
    own reader stopping at them."""
    with open(HUMBLE_BAG, "rb") as stream:
        reader = make_reader(stream)
        header = reader.get_header()
        metadata = [(record.name, record.metadata) for record in reader.iter_metadata()]
    assert (header.profile, header.library) == ("ros2", "libmcap 0.8.0")
    assert metadata == [("rosbag2", {"ROS_DISTRO": "humble"})]
    summary = mcap_summary(HUMBLE_BAG)
    unknown = {channel.topic: summary.schemas[channel.schema_id].name for channel in summary.channels.values()
               if summary.schemas[channel.schema_id].encoding == "unknown"}
    assert unknown == HUMBLE_UNKNOWN_SCHEMA_TOPICS
    with pytest.raises(KeyError, match="unknown"):
        Reader(HUMBLE_BAG).open()


def test_the_humble_bag_lists_every_topic_with_the_messages_foxglove_counts():
    summary = mcap_summary(HUMBLE_BAG)
    counted: dict[str, int] = {channel.topic: 0 for channel in summary.channels.values()}
    with open(HUMBLE_BAG, "rb") as stream:
        for _, channel, _ in make_reader(stream).iter_messages():
            counted[channel.topic] += 1
    info = bag_info(HUMBLE_BAG)
    assert info.complete and info.storage == "mcap" and len(info.topics) == 42
    assert {topic.name: topic.message_count for topic in info.topics} == counted
    assert {topic.name: topic.msgtype for topic in info.topics} == {
        channel.topic: summary.schemas[channel.schema_id].name for channel in summary.channels.values()}
    assert info.message_count == sum(counted.values()) == 5113


def decoded_by_foxglove(path, topic):
    """The messages on topic as Foxglove's decoder (mcap-ros2-support) decodes them, from the bag's definitions."""
    from mcap_ros2.decoder import DecoderFactory
    with open(path, "rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        return [(message.log_time, decoded) for _, _, message, decoded in reader.iter_decoded_messages(topics=[topic])]


@pytest.mark.parametrize("topic, fields", [
    ("/visualizer/primary_camera_pose", lambda m: [m.position.x, m.position.y, m.position.z, m.orientation.x,
                                                   m.orientation.y, m.orientation.z, m.orientation.w]),
    ("/system/state", lambda m: [m.data]),
    ("/rosout", lambda m: [m.name, m.msg, m.level]),
    ("/robot/joint_state", lambda m: [list(m.name), list(map(float, m.position)), list(map(float, m.effort))]),
])
def test_the_humble_bags_messages_decode_as_foxglove_decodes_them(topic, fields):
    """geometry_msgs, std_msgs and rcl_interfaces types (known here) and the recorder's own capstan type (decoded by
    the bag's definition alone) give what Foxglove's decoder gives, message for message."""
    ours = [(stamp, fields(message)) for _, stamp, message in read_messages(HUMBLE_BAG, (topic,))]
    theirs = [(stamp, fields(message)) for stamp, message in decoded_by_foxglove(HUMBLE_BAG, topic)]
    assert len(ours) > 0 and ours == theirs


def test_the_humble_bags_topics_without_a_definition_are_named_with_why():
    undecodable = undecodable_topics(HUMBLE_BAG)
    assert set(undecodable) == set(HUMBLE_UNKNOWN_SCHEMA_TOPICS)
    for topic, msgtype in HUMBLE_UNKNOWN_SCHEMA_TOPICS.items():
        assert undecodable[topic].startswith(f"the bag carries no definition of {msgtype}")
        with pytest.raises(BagError, match=f"{topic} is of type {msgtype}, which neither the bag defines"):
            list(read_messages(HUMBLE_BAG, (topic,)))


def test_swim_analyze_on_the_humble_bag_reports_what_it_can_and_names_the_rest(tmp_path, capsys):
    assert main([str(HUMBLE_BAG), "--output", str(tmp_path)]) == EXIT_PARTIAL_REPORT
    out = capsys.readouterr().out
    assert "42 topics, 5113 messages" in out
    assert "not decodable:" in out and all(f"{topic}: the bag carries no definition" in out
                                           for topic in HUMBLE_UNKNOWN_SCHEMA_TOPICS)
    assert "/joint_states: not in the bag" in out and "/tracking_state: not in the bag" in out
    summary = json.loads((tmp_path / "bag_summary.json").read_text())
    assert {topic["name"] for topic in summary["topics"] if topic["undecodable"]} == set(HUMBLE_UNKNOWN_SCHEMA_TOPICS)
    assert summary["run_measures"] is None and summary["joint_states"] is None
    assert [entry.split(":")[0] for entry in summary["missing"]] == ["/joint_states", "/tracking_state"]


def test_swim_analyze_on_the_humble_bag_in_its_own_process_no_traceback():
    result = run_child([sys.executable, "-m", "swim_bringup.analysis_cli", str(HUMBLE_BAG)], capture_output=True,
                       text=True, timeout_s=120)
    assert result.returncode == EXIT_PARTIAL_REPORT, result.stderr
    assert "Traceback" not in result.stderr and "not decodable:" in result.stdout


# A bag in rosbag2's layout written here: joint_states whose schema has encoding 'unknown' (a type known here, so it
# decodes by the installed definition), a type known nowhere with encoding 'unknown', a channel without schema, and a
# std_msgs/String with its definition.
JOINTS = ("alpha", "phi", "theta")
MESSAGES = 40
PERIOD_NS = 10_000_000                 # 100 Hz
START_NS = 1_700_000_000_000_000_000
#: a chunk of 4 kB: the bag holds several chunks, so it can be cut at a chunk boundary
CHUNK_SIZE_BYTES = 4096


def joint_positions(k):
    return [0.01 * k, 0.2 * math.sin(0.3 * k), -0.1 * math.cos(0.3 * k)]


def write_rosbag2_layout_bag(path: Path) -> Path:
    store = swim_typestore()
    types = store.types
    with open(path, "wb") as stream:
        writer = Writer(stream, chunk_size=CHUNK_SIZE_BYTES, compression=CompressionType.ZSTD)
        writer.start(profile="ros2", library="a test, in rosbag2's layout")
        unknown_joint_states = writer.register_schema("sensor_msgs/msg/JointState", "unknown", b"")
        unknown_thing = writer.register_schema("other_msgs/msg/Thing", "unknown", b"")
        string = writer.register_schema("std_msgs/msg/String", "ros2msg", b"string data\n")
        joint_states = writer.register_channel("/joint_states", "cdr", unknown_joint_states)
        thing = writer.register_channel("/thing", "cdr", unknown_thing)
        raw = writer.register_channel("/raw", "cdr", 0)
        chatter = writer.register_channel("/chatter", "cdr", string)
        for k in range(MESSAGES):
            stamp_ns = START_NS + k * PERIOD_NS
            stamp = types["builtin_interfaces/msg/Time"](stamp_ns // 1_000_000_000, stamp_ns % 1_000_000_000)
            message = types["sensor_msgs/msg/JointState"](types["std_msgs/msg/Header"](stamp, ""), list(JOINTS),
                                                          np.array(joint_positions(k)), np.zeros(0), np.zeros(0))
            writer.add_message(joint_states, stamp_ns,
                               bytes(store.serialize_cdr(message, "sensor_msgs/msg/JointState")), stamp_ns)
            if k % 10 == 0:
                writer.add_message(thing, stamp_ns, b"\x00\x01\x00\x00" + bytes(8), stamp_ns)
                writer.add_message(raw, stamp_ns, b"\x00\x01\x00\x00", stamp_ns)
                chatter_message = types["std_msgs/msg/String"](f"at {k}")
                writer.add_message(chatter, stamp_ns,
                                   bytes(store.serialize_cdr(chatter_message, "std_msgs/msg/String")), stamp_ns)
        writer.finish()
    return path


WRITTEN_COUNTS = {"/joint_states": MESSAGES, "/thing": MESSAGES // 10, "/raw": MESSAGES // 10,
                  "/chatter": MESSAGES // 10}


def metadata_yaml(file_name: str) -> str:
    """A metadata.yaml as rosbag2 Humble writes it (version 5) for one MCAP file holding WRITTEN_COUNTS."""
    topics = {"/joint_states": "sensor_msgs/msg/JointState", "/thing": "other_msgs/msg/Thing",
              "/raw": "other_msgs/msg/Raw", "/chatter": "std_msgs/msg/String"}
    entries = "".join(f"""    - topic_metadata:
        name: {topic}
        type: {msgtype}
        serialization_format: cdr
        offered_qos_profiles: ""
      message_count: {WRITTEN_COUNTS[topic]}
""" for topic, msgtype in topics.items())
    duration_ns = (MESSAGES - 1) * PERIOD_NS
    total = sum(WRITTEN_COUNTS.values())
    return f"""rosbag2_bagfile_information:
  version: 5
  storage_identifier: mcap
  duration:
    nanoseconds: {duration_ns}
  starting_time:
    nanoseconds_since_epoch: {START_NS}
  message_count: {total}
  topics_with_message_count:
{entries}  compression_format: ""
  compression_mode: ""
  relative_file_paths:
    - {file_name}
  files:
    - path: {file_name}
      starting_time:
        nanoseconds_since_epoch: {START_NS}
      duration:
        nanoseconds: {duration_ns}
      message_count: {total}
"""


@pytest.fixture
def rosbag2_layout_bags(tmp_path):
    """The same bag as one .mcap file, as a bag folder with its metadata.yaml, and as one file cut short after its
    first chunk (no summary: its recorder was killed)."""
    single = write_rosbag2_layout_bag(tmp_path / "written_0.mcap")
    folder = tmp_path / "folder"
    folder.mkdir()
    shutil.copy(single, folder / single.name)
    (folder / "metadata.yaml").write_text(metadata_yaml(single.name))
    second_chunk = mcap_summary(single).chunk_indexes[1]
    cut = tmp_path / "cut_0.mcap"
    cut.write_bytes(single.read_bytes()[:second_chunk.chunk_start_offset])
    return single, folder, cut


def test_a_bag_with_unknown_schema_encodings_is_read_not_a_traceback(rosbag2_layout_bags, capsys):
    single, folder, _ = rosbag2_layout_bags
    for bag in (single, folder):
        with pytest.raises(KeyError, match="unknown"):
            Reader(bag).open()   # rosbags alone stops at the schema encoding
        info = bag_info(bag)
        assert info.complete and {t.name: t.message_count for t in info.topics} == WRITTEN_COUNTS
        undecodable = undecodable_topics(bag)
        assert set(undecodable) == {"/thing", "/raw"}
        assert undecodable["/thing"].startswith("the bag carries no definition of other_msgs/msg/Thing, and this "
                                                "environment does not know the type")
        assert undecodable["/raw"] == "its channel has no schema: no type to decode its messages by"
        # joint_states' schema has no definition either, but its type is known here: it decodes by that one
        read = list(read_messages(bag, ("/joint_states", "/chatter")))
        joints = [(stamp, list(message.position)) for topic, stamp, message in read if topic == "/joint_states"]
        assert joints == [(START_NS + k * PERIOD_NS, joint_positions(k)) for k in range(MESSAGES)]
        assert [message.data for topic, _, message in read if topic == "/chatter"] == ["at 0", "at 10", "at 20",
                                                                                       "at 30"]
        with pytest.raises(BagError, match="/thing is of type other_msgs/msg/Thing"):
            list(read_messages(bag, ("/thing",)))

        analysis = analyze_bag(bag)
        assert analysis.joint_states is not None and analysis.joint_states.messages == MESSAGES
        positions = np.array([joint_positions(k) for k in range(MESSAGES)])
        for j, joint in enumerate(analysis.joint_states.joints):
            assert (joint.joint_name, joint.min_position, joint.max_position) == (
                JOINTS[j], positions[:, j].min(), positions[:, j].max())
        assert analysis.joint_states.mean_rate_hz == pytest.approx(1e9 / PERIOD_NS)
        assert dict(analysis.undecodable) == undecodable
        assert [entry.split(":")[0] for entry in analysis.missing] == ["/tracking_state"]
        assert main([str(bag)]) == EXIT_PARTIAL_REPORT
        out = capsys.readouterr().out
        assert "/thing: the bag carries no definition of other_msgs/msg/Thing" in out and "joint motion" in out


def test_a_bag_with_unknown_schema_encodings_cut_short_reads_its_complete_chunks(rosbag2_layout_bags):
    """A recorder killed after its first chunk: no summary; what that chunk holds is listed and read."""
    single, _, cut = rosbag2_layout_bags
    topics = {channel.id: channel.topic for channel in mcap_summary(single).channels.values()}
    with open(single, "rb") as stream:
        first_chunk = next(record for record in StreamReader(stream, emit_chunks=True).records
                           if isinstance(record, Chunk))
        in_first_chunk = [(topics[record.channel_id], record.log_time) for record in breakup_chunk(first_chunk)
                          if isinstance(record, Message)]
    info = bag_info(cut)
    assert not info.complete
    assert {t.name: t.message_count for t in info.topics} == {
        topic: sum(1 for t, _ in in_first_chunk if t == topic) for topic in WRITTEN_COUNTS}
    assert 0 < info.message_count < sum(WRITTEN_COUNTS.values())
    assert set(undecodable_topics(cut)) == {"/thing", "/raw"}
    stamps = [stamp for _, stamp, _ in read_messages(cut, ("/joint_states",))]
    assert stamps == [stamp for topic, stamp in in_first_chunk if topic == "/joint_states"]
    assert analyze_bag(cut).joint_states.messages == len(stamps)
