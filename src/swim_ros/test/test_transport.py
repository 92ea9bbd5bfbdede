"""swim's Fast DDS profile: set for Fast DDS unless the user chose a profile, another RMW or a /dev/shm too small
for its segment (checked in a tmpfs of a known size, in a mount namespace of its own); a valid profile that keeps
UDP (other hosts) and enlarges shared memory; a node run with it sends a plan-sized message intact."""
import os
import select
import shutil
import signal
import subprocess
import sys
import textwrap
import xml.etree.ElementTree as ElementTree

import numpy as np
import pytest

from swim_ros.processes import run_child, start_child
from swim_ros.transport import (
    FREE_SHM_FACTOR,
    PROFILE_VARIABLES,
    choose_transport,
    large_message_profile,
    segment_bytes,
    use_large_message_transport,
)

#: the size of a 20-primitive plan with per-sample gains (bench/bench_planner_latency.py's request), bytes
PLAN_BYTES = 4_600_000
#: how long the child may take to start rclpy and match the test's subscription, s (a loaded 2-core host)
START_TIMEOUT_S = 30.0
NAMESPACE = {"p": "http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles"}


def _clear(monkeypatch):
    for variable in PROFILE_VARIABLES:
        monkeypatch.delenv(variable, raising=False)


def test_fastdds_gets_the_profile_where_shared_memory_has_room(monkeypatch, tmp_path):
    _clear(monkeypatch)
    monkeypatch.setenv("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp")
    choice = use_large_message_transport(shm_dir=tmp_path / "none")   # no /dev/shm: not Linux, nothing to check
    assert choice.profile == large_message_profile() and not choice.warning
    assert os.environ[PROFILE_VARIABLES[0]] == str(large_message_profile())


def test_the_segment_must_fit_twice_in_the_free_shared_memory():
    segment = segment_bytes(large_message_profile())
    assert segment == 16 << 20    # the profile's segment_size
    assert choose_transport(segment, None)
    assert choose_transport(segment, int(FREE_SHM_FACTOR * segment))
    assert not choose_transport(segment, int(FREE_SHM_FACTOR * segment) - 1)


CHOICE_SCRIPT = ("import os; from swim_ros.transport import use_large_message_transport as use; c = use(); "
                 "print(c.profile, c.warning, os.environ.get('FASTRTPS_DEFAULT_PROFILES_FILE'), c.reason)")


def _choice_in_shm_of(size_mib):
    """What a process decides whose /dev/shm is a new tmpfs of size_mib (its own mount namespace): its line."""
    if shutil.which("unshare") is None:
        pytest.skip("no unshare here to give a process a /dev/shm of its own")
    command = f"mount -t tmpfs -o size={size_mib}m tmpfs /dev/shm && exec {sys.executable} -c \"{CHOICE_SCRIPT}\""
    result = run_child(["unshare", "-m", "sh", "-c", command], capture_output=True, text=True, timeout_s=60,
                       env={k: v for k, v in os.environ.items() if k not in PROFILE_VARIABLES})
    if result.returncode != 0 and "mount" in result.stderr:
        pytest.skip(f"no tmpfs of our own here (not root?): {result.stderr.strip()}")
    assert result.returncode == 0, result.stderr
    return result.stdout.strip()


def test_a_small_dev_shm_keeps_fast_dds_defaults():
    """A container's /dev/shm (Docker's default is 64 MiB) with less than twice the segment free: Fast DDS's
    defaults and a warning; with room (64 MiB, empty): the profile."""
    assert _choice_in_shm_of(24).startswith("None True None /dev/shm has 24 MiB free")
    profile = str(large_message_profile())
    assert _choice_in_shm_of(64).startswith(f"{profile} False {profile} ")


def test_a_users_profile_or_rmw_is_left_alone(monkeypatch, tmp_path):
    for variable in PROFILE_VARIABLES:
        _clear(monkeypatch)
        monkeypatch.setenv(variable, str(tmp_path / "mine.xml"))
        assert use_large_message_transport().profile is None
        assert os.environ[variable] == str(tmp_path / "mine.xml")
    _clear(monkeypatch)
    monkeypatch.setenv("RMW_IMPLEMENTATION", "rmw_cyclonedds_cpp")
    assert use_large_message_transport().profile is None
    assert not any(os.environ.get(variable) for variable in PROFILE_VARIABLES)


def test_profile_keeps_udp_and_holds_a_plan_in_shared_memory():
    root = ElementTree.parse(large_message_profile()).getroot()
    transports = {d.findtext("p:transport_id", namespaces=NAMESPACE): d
                  for d in root.iterfind("p:transport_descriptors/p:transport_descriptor", NAMESPACE)}
    kinds = {d.findtext("p:type", namespaces=NAMESPACE) for d in transports.values()}
    assert kinds == {"UDPv4", "SHM"}
    participant = root.find("p:participant", NAMESPACE)
    assert participant.get("is_default_profile") == "true"
    used = [t.text for t in participant.iterfind("p:rtps/p:userTransports/p:transport_id", NAMESPACE)]
    assert sorted(used) == sorted(transports)
    shm = next(d for d in transports.values() if d.findtext("p:type", namespaces=NAMESPACE) == "SHM")
    assert int(shm.findtext("p:segment_size", namespaces=NAMESPACE)) >= 3 * PLAN_BYTES   # three plans in flight


SENDER_SCRIPT = textwrap.dedent("""
    import os
    import numpy as np
    from rclpy.node import Node
    from sensor_msgs.msg import JointState
    from swim_ros.codecs import float_array
    from swim_ros.entry import run_node
    from swim_ros.qos import LATCHED_QOS

    class Sender(Node):
        def __init__(self):
            super().__init__("large_message_sender")
            message = JointState(name=["ramp"])
            message.position = float_array(np.arange({count}, dtype=float))
            self.create_publisher(JointState, "large", LATCHED_QOS).publish(message)
            print(os.environ["FASTRTPS_DEFAULT_PROFILES_FILE"], flush=True)

    run_node(Sender, name="large_message_sender", large_messages=True)
""")


def test_a_node_sends_a_plan_sized_message_with_the_profile(rclpy_context, monkeypatch):
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from sensor_msgs.msg import JointState

    from swim_ros.calls import spin_until
    from swim_ros.qos import LATCHED_QOS
    _clear(monkeypatch)
    count = PLAN_BYTES // 8
    sender = start_child([sys.executable, "-c", SENDER_SCRIPT.format(count=count)], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    node = rclpy.create_node("large_message_receiver", context=rclpy_context)
    executor = SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(node)
    received = []
    node.create_subscription(JointState, "large", received.append, LATCHED_QOS)
    try:
        ready, _, _ = select.select([sender.stdout], [], [], START_TIMEOUT_S)
        assert ready and sender.stdout.readline().strip() == str(large_message_profile())
        assert spin_until(executor, lambda: bool(received), START_TIMEOUT_S)
        np.testing.assert_array_equal(np.asarray(received[0].position), np.arange(count, dtype=float))
    finally:
        executor.shutdown()
        node.destroy_node()
        sender.send_signal(signal.SIGINT)   # a user's Ctrl-C; how long the stop takes is not what is tested here
        try:
            _, err = sender.communicate(timeout=START_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            sender.kill()
            _, err = sender.communicate()
    assert "XMLPARSER" not in err and "Error" not in err, err
