"""A bag cut before its close (a killed recorder) reads up to its last flush; unknown types are refused (no ROS)."""
import shutil

import pytest

from swim_bringup.bag import BagError, BagWriter, read_messages


def string_cdr(store, text):
    message = store.types["std_msgs/msg/String"](data=text)
    return bytes(store.serialize_cdr(message, "std_msgs/msg/String"))


def test_a_bag_copied_before_close_reads_the_flushed_messages_only(tmp_path):
    writer = BagWriter(tmp_path / "bag", {"/chatter": "std_msgs/msg/String"})
    for k in range(50):
        writer.write("/chatter", 1_000 + k, string_cdr(writer.store, f"flushed {k}"))
    writer.flush()
    writer.write("/chatter", 2_000, string_cdr(writer.store, "after the flush"))
    shutil.copytree(tmp_path / "bag", tmp_path / "cut")   # the files as a recorder killed now leaves them
    writer.close()
    assert not (tmp_path / "cut" / "metadata.yaml").exists()
    cut = [(t, m.data) for _, t, m in read_messages(tmp_path / "cut", ("/chatter",))]
    assert cut == [(1_000 + k, f"flushed {k}") for k in range(50)]
    whole = [m.data for _, _, m in read_messages(tmp_path / "bag", ("/chatter",))]
    assert whole == [f"flushed {k}" for k in range(50)] + ["after the flush"]


def test_an_unknown_type_is_refused_and_the_bag_still_closes(tmp_path):
    writer = BagWriter(tmp_path / "bag", {})
    with pytest.raises(BagError, match="no_such_msgs/msg/Thing"):
        writer.add_topic("/thing", "no_such_msgs/msg/Thing")
    writer.add_topic("/chatter", "std_msgs/msg/String")
    writer.write("/chatter", 1, string_cdr(writer.store, "still fine"))
    writer.close()
    assert [m.data for _, _, m in read_messages(tmp_path / "bag", ("/chatter",))] == ["still fine"]
