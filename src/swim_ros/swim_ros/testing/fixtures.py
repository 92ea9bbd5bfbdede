"""Fixtures of the tests that talk to a node over DDS, for every package's tests and the workspace's.

DDS traffic stays on this host and in a ROS domain no other live test process holds (swim_ros.domains), so two
test runs at once never discover each other's nodes. The node under test runs as a user runs it, `ros2 run` in its
own process (swim_ros.processes), and is stopped with SIGINT as a user's Ctrl-C would.
"""
from __future__ import annotations

import contextlib
import subprocess
from pathlib import Path
from typing import Any, Iterator

import pytest

from swim_ros.domains import claim_ros_domain
from swim_ros.processes import STOP_GRACE_S, NodeProcess, NodeSpec

#: a node's process start and discovery: seconds on a loaded 2-core host (Python imports, DDS matching); 30 s margin
STARTUP_TIMEOUT_S = 30.0
#: a message or state change a running node makes within a second at most (a period or a few, a resend, a
#: watchdog): 10 s covers a loaded host's stalls
MESSAGE_TIMEOUT_S = 10.0


@pytest.fixture(scope="session")
def ros_domain() -> int:
    """A ROS_DOMAIN_ID no other live test process holds (swim_ros.domains), discovery limited to localhost."""
    return claim_ros_domain()


@contextlib.contextmanager
def new_rclpy_context() -> Iterator[Any]:
    """An rclpy context of its own, initialised, shut down on leaving.

    For a fixture that outlives one test (a module's client node). Enter it inside a fixture holding ros_domain, so the
    context joins that domain.
    """
    import rclpy
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        yield context
    finally:
        rclpy.shutdown(context=context)


@pytest.fixture()
def rclpy_context(ros_domain: int) -> Iterator[Any]:
    """An rclpy context of the test's own in the test session's domain, shut down after the test."""
    with new_rclpy_context() as context:
        yield context


@contextlib.contextmanager
def running_node(package: str, executable: str, log_path: Path, *ros_args: str) -> Iterator[subprocess.Popen[Any]]:
    """`ros2 run package executable --ros-args ros_args` in its own process group, output to log_path.

    Stopped with SIGINT as a user's Ctrl-C would (SIGKILL after the grace period). Run it inside a test holding
    ros_domain, so the node starts in that domain.
    """
    node = NodeProcess(NodeSpec(package, executable, ros_arguments=ros_args), log_path)
    try:
        yield node.process
    finally:
        node.interrupt()
        node.wait(STOP_GRACE_S)
        node.kill()


def fast_dds_shared_memory(pid: int) -> set[str]:
    """The Fast DDS shared-memory files (segments and ports under /dev/shm) the process pid has mapped."""
    with open(f"/proc/{pid}/maps") as maps:
        return {line.split()[-1] for line in maps if "/dev/shm/fastrtps_" in line}
