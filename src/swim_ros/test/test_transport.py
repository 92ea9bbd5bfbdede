"""swim's Fast DDS profiles.

The large-message profile: set for Fast DDS unless the user chose a profile, another RMW or a /dev/shm too small for
its segment (checked in a tmpfs of a known size, in a mount namespace of its own); a valid profile that keeps UDP
(other hosts) and enlarges shared memory; a node run with it sends a plan-sized message intact.

The real-time profile: UDP only, with discovery as far as the user's ROS_AUTOMATIC_DISCOVERY_RANGE reaches (on this
host, the range is handed to the profile, since rmw_fastrtps adds shared memory to LOCALHOST's); left alone where it
cannot carry the user's discovery. bridge_node's tests check a node run with it (src/swim_hw_bridge/test).
"""
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
    DISCOVERY_RANGE_VARIABLE,
    FREE_SHM_FACTOR,
    PROFILE_VARIABLES,
    choose_transport,
    large_message_profile,
    real_time_profile,
    segment_bytes,
    use_large_message_transport,
    use_real_time_transport,
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


@pytest.mark.parametrize("use", [use_large_message_transport, use_real_time_transport])
def test_a_users_profile_or_rmw_is_left_alone(use, monkeypatch, tmp_path):
    monkeypatch.setenv(DISCOVERY_RANGE_VARIABLE, "LOCALHOST")
    for variable in PROFILE_VARIABLES:
        _clear(monkeypatch)
        monkeypatch.setenv(variable, str(tmp_path / "mine.xml"))
        assert use().profile is None
        assert os.environ[variable] == str(tmp_path / "mine.xml")
    _clear(monkeypatch)
    monkeypatch.setenv("RMW_IMPLEMENTATION", "rmw_cyclonedds_cpp")
    assert use().profile is None
    assert not any(os.environ.get(variable) for variable in PROFILE_VARIABLES)
    assert os.environ[DISCOVERY_RANGE_VARIABLE] == "LOCALHOST"


@pytest.mark.parametrize("discovery_range, localhost", [("LOCALHOST", True), ("SUBNET", False),
                                                        ("SYSTEM_DEFAULT", False), (None, False)])
def test_a_real_time_process_gets_udp_with_the_users_discovery(discovery_range, localhost, monkeypatch):
    """On this host (LOCALHOST), the profile that keeps discovery here, and the range handed to it (SYSTEM_DEFAULT:
    rmw_fastrtps takes the profile as it is); otherwise the plain one, the range untouched."""
    _clear(monkeypatch)
    for variable in ("RMW_IMPLEMENTATION", "ROS_STATIC_PEERS", "ROS_LOCALHOST_ONLY", DISCOVERY_RANGE_VARIABLE):
        monkeypatch.delenv(variable, raising=False)
    if discovery_range is not None:
        monkeypatch.setenv(DISCOVERY_RANGE_VARIABLE, discovery_range)
    choice = use_real_time_transport()
    assert choice.profile == real_time_profile(localhost) and not choice.warning
    assert os.environ[PROFILE_VARIABLES[0]] == str(choice.profile)
    assert os.environ.get(DISCOVERY_RANGE_VARIABLE) == ("SYSTEM_DEFAULT" if localhost else discovery_range)


@pytest.mark.parametrize("variable, value, warning", [(DISCOVERY_RANGE_VARIABLE, "OFF", False),
                                                      ("ROS_STATIC_PEERS", "192.168.1.7", True),
                                                      ("ROS_LOCALHOST_ONLY", "1", True)])
def test_discovery_the_profile_would_not_carry_keeps_fast_dds_defaults(variable, value, warning, monkeypatch):
    _clear(monkeypatch)
    monkeypatch.setenv(DISCOVERY_RANGE_VARIABLE, "LOCALHOST")
    monkeypatch.setenv(variable, value)
    choice = use_real_time_transport()
    assert choice.profile is None and choice.warning == warning
    assert not any(os.environ.get(v) for v in PROFILE_VARIABLES)
    assert os.environ[variable] == value


def _participant_and_transports(profile):
    root = ElementTree.parse(profile).getroot()
    transports = {d.findtext("p:transport_id", namespaces=NAMESPACE): d
                  for d in root.iterfind("p:transport_descriptors/p:transport_descriptor", NAMESPACE)}
    participant = root.find("p:participant", NAMESPACE)
    assert participant.get("is_default_profile") == "true"
    assert participant.findtext("p:rtps/p:useBuiltinTransports", namespaces=NAMESPACE) == "false"
    used = [t.text for t in participant.iterfind("p:rtps/p:userTransports/p:transport_id", NAMESPACE)]
    assert sorted(used) == sorted(transports)
    return participant, transports


@pytest.mark.parametrize("localhost", [False, True])
def test_the_real_time_profiles_are_udp_only(localhost):
    """No shared memory: UDPv4 is the one transport. The localhost variant carries what rmw_fastrtps's LOCALHOST
    range sets: no multicast (a unicast metatraffic locator only), 127.0.0.1 as the initial peer, 32 participant
    ports tried on it."""
    participant, transports = _participant_and_transports(real_time_profile(localhost))
    assert [d.findtext("p:type", namespaces=NAMESPACE) for d in transports.values()] == ["UDPv4"]
    builtin = participant.find("p:rtps/p:builtin", NAMESPACE)
    if not localhost:
        assert builtin is None
        return
    assert builtin.find("p:metatrafficMulticastLocatorList", NAMESPACE) is None
    assert len(builtin.findall("p:metatrafficUnicastLocatorList/p:locator", NAMESPACE)) == 1
    peers = [a.text for a in builtin.iterfind("p:initialPeersList/p:locator/p:udpv4/p:address", NAMESPACE)]
    assert peers == ["127.0.0.1"]
    (udp,) = transports.values()
    assert udp.findtext("p:maxInitialPeersRange", namespaces=NAMESPACE) == "32"


def test_profile_keeps_udp_and_holds_a_plan_in_shared_memory():
    _, transports = _participant_and_transports(large_message_profile())
    kinds = {d.findtext("p:type", namespaces=NAMESPACE) for d in transports.values()}
    assert kinds == {"UDPv4", "SHM"}
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
    from swim_ros.transport import use_large_message_transport

    class Sender(Node):
        def __init__(self):
            super().__init__("large_message_sender")
            message = JointState(name=["ramp"])
            message.position = float_array(np.arange({count}, dtype=float))
            self.create_publisher(JointState, "large", LATCHED_QOS).publish(message)
            print(os.environ["FASTRTPS_DEFAULT_PROFILES_FILE"], flush=True)

    run_node(Sender, name="large_message_sender", transport=use_large_message_transport)
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
