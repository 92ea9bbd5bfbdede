"""Bring the closed loop up as separate processes talking over DDS, and down again cleanly.

Each node runs as `ros2 run <package> <executable> --ros-args --params-file <yaml>` (on a full ROS install the
same command a user types; here `ros2 run` is our stand-in, scripts/bin/ros2) in its own process group, its
output in a log file. Stopping sends SIGINT (a user's Ctrl-C: rclpy shuts down and leaves DDS cleanly), waits,
and kills only what is still there after the grace period: no orphans.
"""
from __future__ import annotations

import dataclasses
import os
import signal
import subprocess
import time
from pathlib import Path
from typing import Optional, Sequence

import yaml

STOP_GRACE_S = 10.0


def config_dir() -> Path:
    """The installed swim_bringup/config folder (parameter files of the demo and the experiments)."""
    from ament_index_python.packages import get_package_share_directory
    return Path(get_package_share_directory("swim_bringup")) / "config"


@dataclasses.dataclass(frozen=True)
class NodeSpec:
    package: str
    executable: str
    params_file: Optional[Path] = None
    parameters: tuple[str, ...] = ()    # extra `name:=value` overrides
    ros_arguments: tuple[str, ...] = ()  # any other --ros-args arguments, as given (e.g. "-r", "__ns:=/test")

    def command(self) -> list[str]:
        arguments: list[str] = []
        if self.params_file is not None:
            arguments += ["--params-file", str(self.params_file)]
        for parameter in self.parameters:
            arguments += ["-p", parameter]
        arguments += list(self.ros_arguments)
        return ["ros2", "run", self.package, self.executable] + (["--ros-args"] + arguments if arguments else [])


class NodeProcess:
    """One node in its own process group, output to log_path."""

    def __init__(self, spec: NodeSpec, log_path: Path) -> None:
        self.spec, self.log_path = spec, log_path
        self._log = open(log_path, "w")
        self.process = subprocess.Popen(spec.command(), stdout=self._log, stderr=subprocess.STDOUT,
                                        start_new_session=True, env=dict(os.environ))

    def alive(self) -> bool:
        return self.process.poll() is None

    def interrupt(self) -> None:
        if self.alive():
            os.killpg(self.process.pid, signal.SIGINT)

    def wait(self, timeout_s: float) -> bool:
        try:
            self.process.wait(timeout=timeout_s)
            return True
        except subprocess.TimeoutExpired:
            return False

    def kill(self) -> None:
        try:
            os.killpg(self.process.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        self.process.wait()
        self._log.close()


class System:
    """The nodes of a run; a context manager that always stops them all."""

    def __init__(self, specs: Sequence[NodeSpec], log_dir: Path) -> None:
        log_dir.mkdir(parents=True, exist_ok=True)
        self.nodes: list[NodeProcess] = []
        try:
            for spec in specs:
                self.nodes.append(NodeProcess(spec, log_dir / f"{spec.executable}.log"))
        except BaseException:
            self.stop()
            raise

    def __enter__(self) -> "System":
        return self

    def __exit__(self, *exc) -> None:
        self.stop()

    def dead(self) -> list[str]:
        """Executables that have exited (a node that should be running and is not)."""
        return [n.spec.executable for n in self.nodes if not n.alive()]

    def stop(self) -> None:
        for node in self.nodes:
            node.interrupt()
        deadline = time.monotonic() + STOP_GRACE_S
        for node in self.nodes:
            node.wait(max(0.0, deadline - time.monotonic()))
            node.kill()   # whatever of its process group outlived the grace period; closes the log


#: the plants a closed loop can run on: (package, executable, parameter file in the config folder)
PLANTS = {
    "sim": ("swim_sim", "sim_node", "sim.yaml"),              # the simulator (lock-step by default)
    "bridge": ("swim_hw_bridge", "bridge_node", "bridge.yaml"),   # the hardware bridge (emulated rig: real time)
}


#: the tracker's stale-state limit when the simulator runs in lock-step. A stalled process stops simulated time
#: with it, so the watch only has to notice a simulator that died; 2 s covers a loaded 2-core host, whose stalls
#: reach 0.6 s and ended runs with "no valid joint_states for 200 ms" (tracker.yaml's, which a real-time plant needs)
LOCKSTEP_STALE_OVERRIDE = "stale_after_periods:=250"


def sim_mode(params_file: Path, overrides: tuple[str, ...]) -> str:
    """sim_node's mode as a run would start it: the last mode:= override, else its parameter file's, else
    sim_node's default (lockstep)."""
    for override in reversed(overrides):
        if override.startswith("mode:="):
            return override.split(":=", 1)[1]
    try:
        parameters = yaml.safe_load(params_file.read_text())["sim_node"]["ros__parameters"]
    except (OSError, yaml.YAMLError, KeyError, TypeError):
        return "lockstep"
    return str(parameters.get("mode", "lockstep"))


#: what draws a run in RViz or Foxglove (swim_viz): the rig's URDF and /tf, and the markers of its paths. They
#: only read joint_states (best effort) and the plan, so the loop runs the same with or without them.
VISUALIZATION_SPECS = (NodeSpec("swim_viz", "rig_state_publisher"), NodeSpec("swim_viz", "marker_node"))


def closed_loop_specs(config: Path, sim_overrides: tuple[str, ...] = (),
                      tracker_overrides: tuple[str, ...] = (), plant: str = "sim",
                      visualization: bool = True) -> list[NodeSpec]:
    """The plant (sim_node or bridge_node, see PLANTS), planner and tracker with the parameter files in config,
    then VISUALIZATION_SPECS if visualization; sim_overrides go to the plant node, whichever it is. With the
    simulator in lock-step (unless overridden to real time) the tracker's stale limit is LOCKSTEP_STALE_OVERRIDE
    unless tracker_overrides set one."""
    if plant not in PLANTS:
        raise ValueError(f"plant must be one of {', '.join(PLANTS)}, got {plant!r}")
    if plant == "sim" and sim_mode(config / PLANTS["sim"][2], sim_overrides) == "lockstep" \
            and not any(o.startswith("stale_after_periods:=") for o in tracker_overrides):
        tracker_overrides = (LOCKSTEP_STALE_OVERRIDE, *tracker_overrides)
    package, executable, params_file = PLANTS[plant]
    return [NodeSpec(package, executable, config / params_file, sim_overrides),
            NodeSpec("swim_planner", "planner_node", config / "planner.yaml"),
            NodeSpec("swim_controller", "tracker_node", config / "tracker.yaml", tracker_overrides),
            *(VISUALIZATION_SPECS if visualization else ())]
