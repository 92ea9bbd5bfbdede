"""How every process we start runs, and the rule they all follow: no child outlives the process that started it.

The rule. Whatever a starter (swim-demo, swim-experiments, swim-bringup, a benchmark, a test, a script) starts ends
when the starter ends, however it ends: a normal exit, Ctrl-C, SIGTERM, SIGKILL or a crash, at any moment. A node
left behind keeps its ROS domain's topics alive and a core busy long after anyone looks at it. So:
- every child is started through ``start_child`` (or ``run_child``, ``NodeProcess``; a shell script through
  ``python -m swim_ros.processes``; a Python child that another library starts, a multiprocessing worker, calls
  ``end_with_starter`` first thing), which gives it a parent-death signal: util-linux's setpriv sets
  PARENT_DEATH_SIGNAL, then, before the command runs, the child checks that its parent is still the starter. The
  kernel sends that signal only to a child whose starter dies after the setting; a starter that died between the
  fork and the setting (a `timeout` ending a sweep while a run was being brought up) would leave it for good, and
  the check catches that case (the child exits with 128 + SIGTERM instead of running);
- the kernel may send the signal when the *thread* that started the child ends, not the process (prctl(2) says
  so; some kernels, this host's 6.18 among them, wait for the whole process): a child is started from a thread
  that outlives it (the main thread; a worker thread only if it waits for its child before it ends, as
  swim_bringup.parallel's do), so that neither reading ends it early;
- a starter's stop (Ctrl-C, and SIGTERM where a CLI treats it the same: ``interrupt_on_sigterm``) stops its
  children itself, the graceful way; the parent-death signal is for the ends that leave it no chance (SIGKILL, a
  crash, a second signal during its stop). A node takes that signal, SIGTERM, as Ctrl-C (swim_ros.entry).
The one child outside the rule: the C compiler swim_model.codegen runs the first time a model is used (swim_model
lies below swim_ros). A node that ends while it compiles leaves it to finish, seconds later.

One node runs as ``ros2 run <package> <executable> --ros-args --params-file <yaml>`` (on a full ROS install the
same command a user types; here `ros2 run` is our stand-in, scripts/bin/ros2, which executes the node in its own
process) in its own process group, its output in a log file. Stopping sends SIGINT (a user's Ctrl-C: rclpy shuts
down and leaves DDS cleanly), waits, and kills only what is still there after the grace period.
"""
from __future__ import annotations

import ctypes
import dataclasses
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence, Union

#: how long a node has to stop after SIGINT before its process group is killed: rclpy's shutdown takes well under
#: a second; 10 s covers a loaded 2-core host
STOP_GRACE_S = 10.0
#: what a child gets when its starter dies: SIGTERM, which rclpy takes as a normal stop (swim_ros.entry.run_node)
#: and a CLI with interrupt_on_sigterm as Ctrl-C
PARENT_DEATH_SIGNAL = "TERM"
#: the exit status of a child whose starter was gone before its parent-death signal was set: as if the signal had
#: come (128 + SIGTERM)
ORPHAN_EXIT_STATUS = 128 + signal.SIGTERM
#: prctl(2)'s option that sets the calling process's parent-death signal (linux/prctl.h)
_PR_SET_PDEATHSIG = 1
#: what the child runs once setpriv has set its parent-death signal: its parent must still be the starter ($1),
#: else the starter died before the setting and no signal will ever come; then the command, in the same process
_PARENT_CHECK = f'[ "$PPID" = "$1" ] || exit {ORPHAN_EXIT_STATUS}; shift; exec "$@"'


def with_parent_death_signal(command: Sequence[str], starter_pid: Optional[int] = None) -> list[str]:
    """The command run with PARENT_DEATH_SIGNAL set, started by the process starter_pid (default: this one).

    The setpriv tool sets the signal, a shell checks the parent is still the starter and executes command, so command
    keeps the pid the starter was given. command as it is where setpriv is missing (the starter's own stop is then the
    only one).
    """
    setpriv = shutil.which("setpriv")
    if setpriv is None:
        return list(command)
    starter = os.getpid() if starter_pid is None else starter_pid
    return [setpriv, f"--pdeathsig={PARENT_DEATH_SIGNAL}", "--", "/bin/sh", "-c", _PARENT_CHECK, "sh", str(starter),
            *command]


def executable_command(command: Sequence[str], environment: Optional[Mapping[str, str]] = None) -> list[str]:
    """The command with `ros2 run <package> <executable>` replaced by the executable's path.

    The path is found where `ros2 run` looks (lib/<package>/<executable> under AMENT_PREFIX_PATH of environment, default
    this process's), so the executable is the starter's child itself, as ros2 launch runs a node: ros2cli's `ros2 run`
    runs it as a child of its own, out of reach of the parent-death signal. command as it is otherwise, or when nothing
    is found (`ros2 run` then says so).
    """
    if len(command) < 4 or list(command[:2]) != ["ros2", "run"]:
        return list(command)
    package, executable = command[2], command[3]
    prefixes = (environment if environment is not None else os.environ).get("AMENT_PREFIX_PATH", "")
    for prefix in filter(None, prefixes.split(os.pathsep)):
        candidate = Path(prefix) / "lib" / package / executable
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return [str(candidate), *command[4:]]
    return list(command)


def start_child(command: Sequence[str], **popen_arguments: Any) -> subprocess.Popen[Any]:
    """subprocess.Popen(command, **popen_arguments) as a child that dies with this process.

    The one way every process of the workspace starts another (the rule in this module's docstring). Call it from a
    thread that outlives the child (the main thread, or one that waits for it).
    """
    environment = popen_arguments.get("env")
    return subprocess.Popen(with_parent_death_signal(executable_command(command, environment)), **popen_arguments)


def run_child(command: Sequence[str], *, timeout_s: Optional[float] = None, input: Union[str, bytes, None] = None,
              capture_output: bool = False, **popen_arguments: Any) -> subprocess.CompletedProcess[Any]:
    """subprocess.run for a child that dies with this process (start_child).

    command run to its end, its output captured if capture_output. Killed if it runs longer than timeout_s
    (subprocess.TimeoutExpired) or if this process stops waiting for it (Ctrl-C).
    """
    if capture_output:
        popen_arguments["stdout"] = popen_arguments["stderr"] = subprocess.PIPE
    if input is not None:
        popen_arguments["stdin"] = subprocess.PIPE
    with start_child(command, **popen_arguments) as process:
        try:
            stdout, stderr = process.communicate(input, timeout=timeout_s)
        except BaseException:
            process.kill()
            process.wait()
            raise
    return subprocess.CompletedProcess(list(command), process.returncode, stdout, stderr)


def end_with_starter(starter_pid: int) -> None:
    """What start_child gives its children, from inside a Python child that start_child did not start.

    For a multiprocessing worker: SIGTERM when the starter (process starter_pid, its parent) dies, and an exit now if it
    has died already. Nothing where prctl(2) is missing (not Linux).
    """
    if not sys.platform.startswith("linux"):
        return
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.prctl(_PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0) != 0:
        raise OSError(ctypes.get_errno(), "prctl(PR_SET_PDEATHSIG) failed")
    if os.getppid() != starter_pid:
        os._exit(ORPHAN_EXIT_STATUS)


def interrupt_on_sigterm() -> None:
    """From now on SIGTERM is Ctrl-C (KeyboardInterrupt in the main thread).

    So a CLI's `with` blocks and `finally` clauses stop what it started the graceful way; Python's default SIGTERM ends
    the process at once and leaves its children to their parent-death signal. Call it from the main thread.
    """
    signal.signal(signal.SIGTERM, signal.default_int_handler)


@dataclasses.dataclass(frozen=True)
class NodeSpec:
    """A node to start: its package and executable, a parameters file, parameter overrides and other ROS arguments."""

    package: str
    executable: str
    params_file: Optional[Path] = None
    parameters: tuple[str, ...] = ()    # extra `name:=value` overrides
    ros_arguments: tuple[str, ...] = ()  # any other --ros-args arguments, as given (e.g. "-r", "__ns:=/test")

    def command(self) -> list[str]:
        """The `ros2 run` command line that starts the node."""
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
        self.process = start_child(spec.command(), stdout=self._log, stderr=subprocess.STDOUT,
                                   start_new_session=True, env=dict(os.environ))

    def alive(self) -> bool:
        """Whether the node's process is still running."""
        return self.process.poll() is None

    def interrupt(self) -> None:
        """Send SIGINT to the node's process group, as a user's Ctrl-C would, if it is still running."""
        if self.alive():
            os.killpg(self.process.pid, signal.SIGINT)

    def wait(self, timeout_s: float) -> bool:
        """Whether the process ended within timeout_s (s)."""
        try:
            self.process.wait(timeout=timeout_s)
            return True
        except subprocess.TimeoutExpired:
            return False

    def kill(self) -> None:
        """SIGKILL to the process group, then reap the process and close its log."""
        try:
            os.killpg(self.process.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        self.process.wait()
        self._log.close()


def main(argv: Sequence[str]) -> None:
    """`python -m swim_ros.processes STARTER_PID COMMAND [ARGUMENTS...]`.

    start_child for a shell script. The script passes its own pid ($$) and runs this in the foreground or background;
    this process becomes COMMAND (same pid), which ends when the script ends. A STARTER_PID that is this process's own
    is refused: bash expands the words of a background command (`... "$BASHPID" ... &`) in the child it forked, so
    $BASHPID there names the child, and the parent check would end COMMAND before it ran.
    """
    if len(argv) < 2 or not argv[0].isdigit():
        sys.exit("usage: python -m swim_ros.processes STARTER_PID COMMAND [ARGUMENTS...]")
    starter_pid = int(argv[0])
    if starter_pid == os.getpid():
        sys.exit(f"swim_ros.processes: STARTER_PID {starter_pid} is this process, not its starter: pass the script's "
                 "pid ($$), or $BASHPID read before the command is put in the background")
    command = with_parent_death_signal(executable_command(argv[1:]), starter_pid)
    os.execvp(command[0], command)


if __name__ == "__main__":
    main(sys.argv[1:])
