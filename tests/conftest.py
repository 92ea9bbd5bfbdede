"""Workspace tests: shared fixtures. DDS traffic stays on this host and in a domain of our own."""
import contextlib
import subprocess
from pathlib import Path

import pytest

WORKSPACE = Path(__file__).resolve().parents[1]
PACKAGES = ("swim_model", "swim_ros", "swim_planner", "swim_controller", "swim_sim", "swim_hw_bridge", "swim_bringup",
            "swim_viz", "swim_interfaces")

#: a node's process start and discovery: seconds on a loaded 2-core host (Python imports, DDS matching); 30 s margin
STARTUP_TIMEOUT_S = 30.0
#: a message or state change a running node makes within a second at most (a period or a few, a resend, a
#: watchdog): 10 s covers a loaded host's stalls
MESSAGE_TIMEOUT_S = 10.0
#: a whole swim-demo process (bring-up, maneuver, recording, analysis, stop): about 10-20 s (bench_demo_walltime:
#: 17 s at load ~5), more on a busier host; 300 s only stops a hung run (the demo's --timeout bounds the maneuver)
DEMO_TIMEOUT_S = 300.0


@pytest.fixture(scope="session")
def ros_domain():
    """A ROS_DOMAIN_ID no other live test process holds (swim_ros.domains), discovery limited to localhost."""
    from swim_ros.domains import claim_ros_domain
    return claim_ros_domain()


@pytest.fixture()
def rclpy_context(ros_domain):
    import rclpy
    context = rclpy.Context()
    rclpy.init(context=context)
    yield context
    rclpy.shutdown(context=context)


@contextlib.contextmanager
def running_node(package: str, executable: str, log_path: Path, *ros_args: str):
    """`ros2 run package executable --ros-args ros_args` in its own process group, output to log_path;
    stopped with SIGINT as a user's Ctrl-C would (SIGKILL after the grace period): swim_bringup's NodeProcess."""
    from swim_bringup.system import STOP_GRACE_S, NodeProcess, NodeSpec
    node = NodeProcess(NodeSpec(package, executable, ros_arguments=ros_args), log_path)
    try:
        yield node.process
    finally:
        node.interrupt()
        node.wait(STOP_GRACE_S)
        node.kill()


def run_demo(run_dir: Path, *arguments: str, timeout_s: float = DEMO_TIMEOUT_S, expected_returncode: int = 0) -> str:
    """`ros2 run swim_bringup swim-demo --run-dir run_dir arguments` in the workspace's environment; its stdout
    (the summary table) and stderr. Fails the test with the tail of its output if it does not exit with
    expected_returncode."""
    command = f"source scripts/env.sh && ros2 run swim_bringup swim-demo --run-dir {run_dir} {' '.join(arguments)}"
    result = subprocess.run(["bash", "-c", command], cwd=WORKSPACE, capture_output=True, text=True,
                            timeout=timeout_s)
    assert result.returncode == expected_returncode, result.stdout[-2000:] + result.stderr[-2000:]
    return result.stdout + result.stderr
