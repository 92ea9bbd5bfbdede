"""The swim-bringup command: the closed loop's nodes kept up for an operator.

swim-bringup: the closed loop's nodes kept up for an operator, the same nodes with the same parameters as
`ros2 launch swim_bringup sim.launch.yaml` (or bridge.launch.xml), where `launch` is not installed.

`swim-bringup sim` starts sim_node (lock-step, or real time with --realtime), `swim-bringup bridge` bridge_node
(--backend emulated | serial | mf624); then planner_node, tracker_node, maneuver_node (the perform_maneuver action)
and swim_viz's rig_state_publisher and marker_node (and, with --foxglove [PORT], foxglove_node: the run live in the
Foxglove app), each in a process of its own (swim_bringup.system) with the
parameter files of a pipeline or of --config, every node's output in a log folder. It watches them until Ctrl-C
or SIGTERM, which stop them all (exit 0). A node that dies is reported at once with its exit status and the end of
its log; the others are then stopped (exit 1), or with --keep-going kept up. Bad input exits 2.
The nodes join the caller's ROS domain (ROS_DOMAIN_ID, 0 when unset) as ros2 launch's do, so an operator's
`ros2 action send_goal /perform_maneuver ...` from another shell reaches them.
"""
from __future__ import annotations

import argparse
import contextlib
import datetime
import os
import signal
import sys
import time
from pathlib import Path
from types import FrameType
from typing import Iterator, Optional

from swim_bringup.system import PIPELINES, PLANTS, System, closed_loop_specs, config_dir
from swim_hw_bridge.backends import BACKENDS
from swim_ros.processes import NodeProcess, NodeSpec

#: how often the nodes are looked at: a node that died is reported at most this late
POLL_S = 0.2
#: the lines of a dead node's log that are printed with its report: its traceback or last messages
LOG_TAIL_LINES = 20
#: the signals that stop the nodes: Ctrl-C, a service manager's stop, the terminal closing
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
#: how an operator flies a maneuver once the nodes are up, by plant (the simulator is the constrained vehicle, the
#: emulated rig the free one)
SEND_GOAL_EXAMPLE = {
    "sim": 'ros2 action send_goal /perform_maneuver swim_interfaces/action/PerformManeuver '
           '"{mode: 1, goal_state: constrained/rest, goal_alpha_rad: 6.3}" --feedback',
    "bridge": 'ros2 action send_goal /perform_maneuver swim_interfaces/action/PerformManeuver '
              '"{mode: 1, goal_state: free/rest/R0.48, goal_alpha_rad: 6.3}" --feedback',
}


class BringupError(ValueError):
    """Input swim-bringup cannot start from: an option the set does not take, a missing parameter file."""


#: foxglove_node's port when --foxglove names none: Foxglove's default (swim_viz.foxglove_node)
FOXGLOVE_DEFAULT_PORT = 8765


def bringup_specs(plant: str, backend: Optional[str] = None, pipeline: str = "realistic", realtime: bool = False,
                  sliding_mode: bool = True, config: Optional[Path] = None,
                  foxglove_port: Optional[int] = None, rig_path: str = "") -> list[NodeSpec]:
    """The nodes swim-bringup starts for a plant.

    The plant is "sim" or "bridge"; the nodes are as the launch files start them: the pipeline's
    parameter files (config_dir(pipeline)) or config's, sim_node in real time if realtime (else as its file says:
    lock-step, with the tracker's stale limit raised, system.LOCKSTEP_STALE_OVERRIDE), bridge_node with backend
    (default emulated), the tracker's sliding mode on or off, the maneuver server, and foxglove_node on
    foxglove_port (loopback) unless it is None, every node that loads the rig with rig_path (empty: the shipped rig).
    BringupError for a backend with the simulator, real time with the bridge (always real time) or an unknown backend.
    """
    if plant not in PLANTS:
        raise BringupError(f"the set is one of {', '.join(PLANTS)}, not {plant!r}")
    if plant == "sim" and backend is not None:
        raise BringupError("--backend is bridge_node's: the sim set has no device")
    if plant == "bridge" and realtime:
        raise BringupError("--realtime is sim_node's: bridge_node always runs in real time")
    if backend is not None and backend not in BACKENDS:
        raise BringupError(f"--backend is one of {', '.join(BACKENDS)}, not {backend!r}")
    plant_overrides = ("mode:=realtime",) if realtime else ()
    if plant == "bridge":
        plant_overrides = (f"backend:={backend or 'emulated'}",)
    if foxglove_port is not None and not 0 <= foxglove_port <= 65535:
        raise BringupError(f"--foxglove takes a TCP port (0-65535), not {foxglove_port}")
    specs = closed_loop_specs(config or config_dir(pipeline), plant_overrides,
                              (f"sliding_mode_enabled:={str(sliding_mode).lower()}",), plant=plant, maneuver=True,
                              rig_path=rig_path)
    if foxglove_port is not None:
        specs.append(NodeSpec("swim_viz", "foxglove_node", parameters=(f"port:={foxglove_port}",)))
    return specs


def missing_files(specs: list[NodeSpec]) -> list[str]:
    """Each parameter file the specs name that is not a file, as 'executable: path'."""
    return [f"{spec.executable}: {spec.params_file}" for spec in specs
            if spec.params_file is not None and not spec.params_file.is_file()]


def parse_arguments(argv: Optional[list[str]]) -> argparse.Namespace:
    """The command line of swim-bringup, parsed."""
    parser = argparse.ArgumentParser(prog="swim-bringup", description=__doc__.splitlines()[0])
    parser.add_argument("plant", choices=tuple(PLANTS),
                        help="sim: sim_node (lock-step unless --realtime); bridge: bridge_node (real time)")
    parser.add_argument("--backend", choices=tuple(BACKENDS), default=None,
                        help="bridge_node's device (bridge only; default emulated)")
    parser.add_argument("--pipeline", choices=PIPELINES, default="realistic",
                        help="realistic (the default): circulatory plans, vortex-wake plant, physical disturbances; "
                             "paper: ideal-flow plans and plant, the paper's small disturbances")
    parser.add_argument("--config", type=Path, default=None,
                        help="folder of the nodes' parameter files (default: the pipeline's)")
    parser.add_argument("--realtime", action="store_true",
                        help="sim_node a period per timer tick instead of lock-step (sim only)")
    parser.add_argument("--sliding-mode", choices=("on", "off"), default="on", help="tracker_node's sliding mode")
    parser.add_argument("--keep-going", action="store_true",
                        help="when a node dies, report it and keep the others up (default: stop them, exit 1)")
    parser.add_argument("--foxglove", type=int, nargs="?", const=FOXGLOVE_DEFAULT_PORT, default=None, metavar="PORT",
                        help=f"also start foxglove_node, the Foxglove app's live connection, on ws://127.0.0.1:PORT "
                             f"(default {FOXGLOVE_DEFAULT_PORT}; no authentication: loopback only)")
    parser.add_argument("--rig", default="", help="rig file every node loads (rig_path; default: swim_model's "
                        "shipped rig)")
    parser.add_argument("--log-dir", type=Path, default=None,
                        help="folder of the nodes' logs (default runs/bringup-<time>/logs)")
    return parser.parse_args(argv)


class StopRequest:
    """The stop signals, recorded instead of acted on.

    The loop that watches the nodes stops them at its next look. A handler that raised could interrupt a node's start
    between its fork and its record, orphaning it.
    """

    def __init__(self) -> None:
        self.signal: Optional[int] = None

    def __call__(self, signum: int, frame: Optional[FrameType]) -> None:
        """Record the stop signal signum."""
        self.signal = signum

    @contextlib.contextmanager
    def installed(self) -> Iterator["StopRequest"]:
        """Record the stop signals while in the block, their previous handlers restored after it."""
        previous = {signum: signal.signal(signum, self) for signum in STOP_SIGNALS}
        try:
            yield self
        finally:
            for signum, handler in previous.items():
                signal.signal(signum, handler)


def exit_status(returncode: int) -> str:
    """A process's end as a person reads it: 'exit status N' or 'killed by SIGNAME'."""
    if returncode < 0:
        try:
            return f"killed by {signal.Signals(-returncode).name}"
        except ValueError:
            return f"killed by signal {-returncode}"
    return f"exit status {returncode}"


def log_tail(path: Path, lines: int = LOG_TAIL_LINES) -> list[str]:
    """The last lines of the log at path, or why it cannot be read."""
    try:
        return path.read_text(errors="replace").splitlines()[-lines:]
    except OSError as err:
        return [f"(log unreadable: {err})"]


def report_death(node: NodeProcess) -> None:
    """Print on stderr that a node ended, with its exit status and the end of its log."""
    returncode = node.process.poll()
    status = exit_status(returncode) if returncode is not None else "ended"
    tail = log_tail(node.log_path)
    ending = f"its log {node.log_path} ends:" if tail else f"its log {node.log_path} is empty"
    print(f"swim-bringup: {node.spec.executable} (pid {node.process.pid}) ended, {status}; {ending}", file=sys.stderr)
    for line in tail:
        print(f"  | {line}", file=sys.stderr)
    sys.stderr.flush()


def watch(system: System, stop: StopRequest, keep_going: bool) -> int:
    """Watch the nodes until a stop signal or a node's death; the exit status.

    Look at the nodes every POLL_S until a stop signal (0), a node's death without keep_going (1), or, with
    keep_going, every node dead (1). Each death is reported once.
    """
    reported: set[int] = set()
    while stop.signal is None:
        for node in system.nodes:
            if node.process.pid not in reported and not node.alive():
                reported.add(node.process.pid)
                report_death(node)
                if not keep_going:
                    print("swim-bringup: stopping the other nodes", file=sys.stderr, flush=True)
                    return 1
                alive = [n.spec.executable for n in system.nodes if n.alive()]
                if not alive:
                    print("swim-bringup: no node is left running", file=sys.stderr, flush=True)
                    return 1
                print(f"swim-bringup: --keep-going: {', '.join(alive)} stay up", file=sys.stderr, flush=True)
        time.sleep(POLL_S)
    print(f"swim-bringup: {signal.Signals(stop.signal).name}: stopping the nodes", flush=True)
    return 0


def main(argv: Optional[list[str]] = None) -> int:
    """The swim-bringup command; its exit status."""
    args = parse_arguments(argv)
    log_dir = args.log_dir or Path("runs") / datetime.datetime.now().strftime("bringup-%Y%m%d-%H%M%S") / "logs"
    try:
        if args.config is not None and not args.config.is_dir():
            raise BringupError(f"--config {args.config}: no such folder")
        config = args.config or config_dir(args.pipeline)
        specs = bringup_specs(args.plant, args.backend, args.pipeline, args.realtime, args.sliding_mode == "on",
                              config, args.foxglove, args.rig)
        missing = missing_files(specs)
        if missing:
            raise BringupError(f"no parameter file {'; '.join(missing)}")
        log_dir.mkdir(parents=True, exist_ok=True)
    except (BringupError, OSError) as err:
        print(f"swim-bringup: {err}", file=sys.stderr)
        return 2
    source = f"the {args.pipeline} pipeline" if args.config is None else "--config"
    with StopRequest().installed() as stop:   # before the first node starts: a stop signal never orphans one
        print(f"swim-bringup: starting the {args.plant} set with the parameter files of {source} ({config}) in ROS "
              f"domain {os.environ.get('ROS_DOMAIN_ID') or 0}; logs in {log_dir}", flush=True)
        if stop.signal is not None:
            return 0
        with System(specs, log_dir) as system:
            for node in system.nodes:
                print(f"  {node.spec.executable:<20} pid {node.process.pid:<8} {node.log_path}")
            print(f"swim-bringup: Ctrl-C stops them. Fly a maneuver: {SEND_GOAL_EXAMPLE[args.plant]}", flush=True)
            if args.foxglove is not None:
                print(f"swim-bringup: the Foxglove app connects to ws://127.0.0.1:{args.foxglove} "
                      "(Open connection, Foxglove WebSocket; layout docs/foxglove_layout.json)", flush=True)
            status = watch(system, stop, args.keep_going)
        print("swim-bringup: every node stopped", flush=True)
    return status


if __name__ == "__main__":
    sys.exit(main())
