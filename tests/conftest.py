"""Workspace tests: the tests that need several packages at once, and nothing a single package could test itself.

What belongs here: the whole closed loop (the demo, the bridge closed loop, the wake run, killing a node, the
recorder and visualization on a demo's bag, the experiments run), the launch files, the interfaces as every
package sees them, packaging, and the checks of the whole source tree (style, types, comments, repeated tests).
A test of one node over DDS lives in that node's package, src/<package>/test/, so `colcon test
--packages-select <package>` starts it. The DDS fixtures and timeouts every test shares are swim_ros.testing's.

A test marked `slow` (a grid of cases run by hand before a change that needs it, minutes long) is skipped unless
SWIM_SLOW_TESTS=1: `SWIM_SLOW_TESTS=1 python -m pytest tests -m slow` runs them.
"""
import functools
import os
from pathlib import Path
from typing import Optional

import pytest

from swim_ros.processes import run_child
from swim_ros.testing.fixtures import MESSAGE_TIMEOUT_S, STARTUP_TIMEOUT_S, rclpy_context, ros_domain, running_node  # noqa: F401

WORKSPACE = Path(__file__).resolve().parents[1]
PACKAGES = ("swim_model", "swim_control", "swim_ros", "swim_planner", "swim_controller", "swim_sim", "swim_hw_bridge",
            "swim_bringup", "swim_viz", "swim_interfaces")

#: a whole swim-demo process (bring-up, maneuver, recording, analysis, stop): about 10-20 s (bench_demo_walltime:
#: 17 s at load ~5), more on a busier host; 300 s only stops a hung run (the demo's --timeout bounds the maneuver)
DEMO_TIMEOUT_S = 300.0
#: the lines of each node's log a failed demo's message ends with
LOG_TAIL_LINES = 12
#: Docker's default /dev/shm, MiB: what a run in a container has for Fast DDS's shared memory
CONTAINER_SHM_MIB = 64
#: the environment variable that runs the tests marked slow (SWIM_SLOW_TESTS=1)
SLOW_TESTS_VARIABLE = "SWIM_SLOW_TESTS"


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", f"slow: minutes long, run by hand; skipped unless {SLOW_TESTS_VARIABLE}=1")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if os.environ.get(SLOW_TESTS_VARIABLE) == "1":
        return
    skip = pytest.mark.skip(reason=f"slow: run with {SLOW_TESTS_VARIABLE}=1")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)


@functools.lru_cache(maxsize=None)
def own_shm_possible() -> bool:
    """Whether a process here may have a /dev/shm of its own (a tmpfs in a mount namespace of its own: root)."""
    command = ["unshare", "-m", "sh", "-c", "mount -t tmpfs -o size=1m tmpfs /dev/shm"]
    try:
        return run_child(command, capture_output=True, timeout_s=30).returncode == 0
    except OSError:
        return False


def run_demo(run_dir: Path, *arguments: str, timeout_s: float = DEMO_TIMEOUT_S,
             expected_returncode: Optional[int] = 0, shm_mib: Optional[int] = None) -> str:
    """`ros2 run swim_bringup swim-demo --run-dir run_dir arguments` in the workspace's environment; its stdout
    (the summary table) and stderr. With shm_mib, the run's processes share a new /dev/shm of that size (a tmpfs
    in a mount namespace of their own; the test is skipped where that is not allowed). Fails the test with the
    tail of its output if it does not exit with expected_returncode (None: whatever its exit status)."""
    command = f"source scripts/env.sh && exec ros2 run swim_bringup swim-demo --run-dir {run_dir} {' '.join(arguments)}"
    argv = ["bash", "-c", command]
    if shm_mib is not None:
        if not own_shm_possible():
            pytest.skip("a /dev/shm of the run's own needs a mount namespace (root)")
        argv = ["unshare", "-m", "bash", "-c", f"mount -t tmpfs -o size={shm_mib}m tmpfs /dev/shm && {command}"]
    result = run_child(argv, cwd=WORKSPACE, capture_output=True, text=True, timeout_s=timeout_s)
    assert expected_returncode is None or result.returncode == expected_returncode, (
        result.stdout[-2000:] + result.stderr[-2000:] + log_tails(run_dir / "logs"))
    return result.stdout + result.stderr


def log_tails(log_dir: Path, lines: int = LOG_TAIL_LINES) -> str:
    """The last lines of each node's log in log_dir, for a failed run's message (CI keeps no run folder)."""
    tails = []
    for log in sorted(log_dir.glob("*.log")):
        tail = log.read_text(errors="replace").splitlines()[-lines:]
        tails.append(f"\n--- {log.name}, last {len(tail)} lines\n" + "\n".join(tail))
    return "".join(tails)


def track_plan(library, sequence: tuple[list[str], list[int]], time_scale: float, plant, constrained: bool = False,
               range_guard=None):
    """The circulatory plan of sequence (primitive ids, repeats) at time_scale from library, tracked in one process
    (no DDS) by the circulatory tracker without sliding mode (with range_guard, a FoilRangeGuard, if given) on plant
    (swim_sim's Plant of the free vehicle, or of the constrained one if constrained, on the rig's home lane); the run
    (swim_controller.testing.closed_loop.Run), checked to have been tracked: never a radian of alpha off its plan."""
    from swim_controller.sliding_mode import SlidingMode
    from swim_controller.testing.closed_loop import simulate
    from swim_controller.tracker import CascadeTracker, model_io_linearization, model_lag_rate
    from swim_model import load_rig
    from swim_model.plant import vehicle_model
    from swim_planner.maneuver import concatenate, expand_sequence
    rig = load_rig()
    plan = concatenate(library, rig, expand_sequence(*sequence), time_scale)
    model = vehicle_model("circulatory", rig, constrained, rig.lane_1_radius_m)
    tracker = CascadeTracker(model_io_linearization(model), model.torque_limits(), SlidingMode(),
                             sliding_mode_enabled=False, sample_period_s=rig.sample_period_s,
                             lag_rate=model_lag_rate(model), range_guard=range_guard)
    run = simulate(model, tracker, plan, rig.sample_period_s, plant=plant)
    assert abs(run.error[:, 0]).max() < 1.0
    return run
