"""How every process we start runs: one node as `ros2 run`, in its own process group, stopped as a user would.

Each node runs as `ros2 run <package> <executable> --ros-args --params-file <yaml>` (on a full ROS install the
same command a user types; here `ros2 run` is our stand-in, scripts/bin/ros2) in its own process group, its
output in a log file. Stopping sends SIGINT (a user's Ctrl-C: rclpy shuts down and leaves DDS cleanly), waits,
and kills only what is still there after the grace period: no orphans. A starter that dies without stopping its
nodes (SIGKILL, a crash) takes them with it: each node is started with a parent-death signal (util-linux's setpriv
sets it, then executes `ros2 run`), so the kernel sends it PARENT_DEATH_SIGNAL when the thread that started it ends.
"""
from __future__ import annotations

import dataclasses
import os
import shutil
import signal
import subprocess
from pathlib import Path
from typing import Optional

#: how long a node has to stop after SIGINT before its process group is killed: rclpy's shutdown takes well under
#: a second; 10 s covers a loaded 2-core host
STOP_GRACE_S = 10.0
#: what a node gets when its starter dies: SIGTERM, which rclpy takes as a normal stop (swim_ros.entry.run_node)
PARENT_DEATH_SIGNAL = "TERM"


def with_parent_death_signal(command: list[str]) -> list[str]:
    """command run with PARENT_DEATH_SIGNAL set (setpriv keeps the process: ros2 run, and the node it executes, have
    its pid); command as it is where setpriv is missing (the starter's own stop is then the only one)."""
    setpriv = shutil.which("setpriv")
    return command if setpriv is None else [setpriv, f"--pdeathsig={PARENT_DEATH_SIGNAL}", "--", *command]


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
        self.process = subprocess.Popen(with_parent_death_signal(spec.command()), stdout=self._log,
                                        stderr=subprocess.STDOUT, start_new_session=True, env=dict(os.environ))

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
