"""Bring the closed loop up as separate processes talking over DDS, and down again cleanly.

Each node a swim_ros.processes.NodeProcess (`ros2 run` in its own process group, stopped by SIGINT, then SIGKILL after
the grace period: no orphans).
"""
from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import Sequence

import yaml

from swim_ros.processes import STOP_GRACE_S, NodeProcess, NodeSpec

#: the pipelines a run can use, each a folder of parameter files (config_dir): "realistic", the default, flies the
#: circulatory flow model's plans in the vortex wake under the physical disturbances; "paper" flies the ideal-flow
#: plans in ideal flow under the small disturbances they survive (the paper's reproduction)
PIPELINES = ("realistic", "paper")


def config_dir(pipeline: str = "realistic") -> Path:
    """The installed folder of a pipeline's parameter files.

    The files are the sim, planner, tracker and bridge YAML: swim_bringup's config/ for "realistic", config/paper/ for
    "paper". ValueError for another pipeline.
    """
    if pipeline not in PIPELINES:
        raise ValueError(f"pipeline must be one of {', '.join(PIPELINES)}, got {pipeline!r}")
    from ament_index_python.packages import get_package_share_directory
    folder = Path(get_package_share_directory("swim_bringup")) / "config"
    return folder if pipeline == "realistic" else folder / pipeline


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
        """The system, stopped on leaving the block."""
        return self

    def __exit__(self, *exc) -> None:
        """Stop the system."""
        self.stop()

    def dead(self) -> list[str]:
        """Executables that have exited (a node that should be running and is not)."""
        return [n.spec.executable for n in self.nodes if not n.alive()]

    def stop(self) -> None:
        """Interrupt every node, wait out the grace period, then kill what is left."""
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
    """The sim_node mode a run would start it in.

    sim_node's mode as a run would start it: the last mode:= override, else its parameter file's, else
    sim_node's default (lockstep).
    """
    for override in reversed(overrides):
        if override.startswith("mode:="):
            return override.split(":=", 1)[1]
    try:
        parameters = yaml.safe_load(params_file.read_text())["sim_node"]["ros__parameters"]
    except (OSError, yaml.YAMLError, KeyError, TypeError):
        return "lockstep"
    return str(parameters.get("mode", "lockstep"))


#: what draws a run in RViz or Foxglove (swim_viz): the rig's URDF and /tf, and the markers of its paths. They
#: only read joint_states (best effort) and the plan, so the loop runs the same with or without them. Their
#: publishing rates are the launch files' (tests/test_launch_files.py holds them equal)
VISUALIZATION_SPECS = (NodeSpec("swim_viz", "rig_state_publisher", parameters=("publish_rate_hz:=30.0",)),
                       NodeSpec("swim_viz", "marker_node", parameters=("publish_rate_hz:=10.0",)))


def maneuver_spec(config: Path) -> NodeSpec:
    """The operator's maneuver server with config's maneuver.yaml.

    The perform_maneuver action, which plans through the planner and tracks through the tracker from where the vehicle
    is.
    """
    return NodeSpec("swim_bringup", "maneuver_node", config / "maneuver.yaml")


#: the nodes that load the rig file, each from its rig_path parameter (empty: swim_model's shipped rig)
RIG_NODES = ("sim_node", "bridge_node", "planner_node", "tracker_node", "rig_state_publisher", "marker_node")


def closed_loop_specs(config: Path, sim_overrides: tuple[str, ...] = (),
                      tracker_overrides: tuple[str, ...] = (), plant: str = "sim",
                      visualization: bool = True, maneuver: bool = False, rig_path: str = "") -> list[NodeSpec]:
    """The nodes of the closed loop, as process specs.

    The plant (sim_node or bridge_node, see PLANTS), planner and tracker with the parameter files in config,
    then the maneuver server (maneuver_spec) if maneuver, then VISUALIZATION_SPECS if visualization; sim_overrides go
    to the plant node, whichever it is. With the simulator in lock-step (unless overridden to real time) the
    tracker's stale limit is LOCKSTEP_STALE_OVERRIDE unless tracker_overrides set one. A run that drives the
    tracker itself (swim-demo, swim-experiments) leaves the maneuver server out; swim-bringup starts it. A rig_path
    goes to every node of RIG_NODES (empty: each loads the shipped rig).
    """
    if plant not in PLANTS:
        raise ValueError(f"plant must be one of {', '.join(PLANTS)}, got {plant!r}")
    if plant == "sim" and sim_mode(config / PLANTS["sim"][2], sim_overrides) == "lockstep" \
            and not any(o.startswith("stale_after_periods:=") for o in tracker_overrides):
        tracker_overrides = (LOCKSTEP_STALE_OVERRIDE, *tracker_overrides)
    package, executable, params_file = PLANTS[plant]
    specs = [NodeSpec(package, executable, config / params_file, sim_overrides),
             NodeSpec("swim_planner", "planner_node", config / "planner.yaml"),
             NodeSpec("swim_controller", "tracker_node", config / "tracker.yaml", tracker_overrides),
             *([maneuver_spec(config)] if maneuver else []),
             *(VISUALIZATION_SPECS if visualization else ())]
    if not rig_path:
        return specs
    return [dataclasses.replace(s, parameters=(*s.parameters, f"rig_path:={rig_path}")) if s.executable in RIG_NODES
            else s for s in specs]
