"""No orphans: whatever swim-demo, swim-experiments, swim-bringup or a benchmark starts ends when that starter ends,
by SIGINT, SIGTERM or SIGKILL, at any moment (swim_ros.processes states the rule and how it is kept; SIGKILL stands
for a crash as well: neither leaves the starter a chance to stop anything).

Each starter runs with an environment variable of its own (TAG_VARIABLE=<uuid>), which every process it starts
inherits, nodes and run processes alike: a process left is one whose /proc/<pid>/environ holds it, whatever its
parent (init, once orphaned), and never another test's. Whatever is left is killed after the assertion.

- test_a_starter_killed_at_a_random_moment_leaves_nothing: each starter of CI_STARTERS with SIGTERM and with SIGKILL,
  each at one random moment of a typical run (swim-demo flies the paper's accelerate, 4 s; swim-experiments one
  experiment's two runs at once; bench_planner_latency starts its node its own way, not through swim_bringup's
  System, whose bring-ups swim-demo's cover). The moment and what was left are in a failure's message.
- test_every_starter_signal_and_moment_leaves_nothing, marked slow: every starter of GRID_STARTERS (bench_loop_jitter
  too, and swim-experiments with its two runs one after the other, so that one is torn down and the next brought
  up) with SIGINT, SIGTERM and SIGKILL at each of MOMENTS. Run it by hand with
  `SWIM_SLOW_TESTS=1 python -m pytest tests/test_no_orphans.py -m slow -p no:cacheprovider` (60 cases, about 5 min
  on a 2-core host; the CI test about 1 min).
"""
from __future__ import annotations

import dataclasses
import os
import random
import re
import signal
import subprocess
import sys
import time
import uuid
from pathlib import Path
from typing import Callable, Optional

import pytest
from conftest import WORKSPACE

from swim_bringup.parallel import INTERRUPT_GRACE_S
from swim_ros.processes import STOP_GRACE_S, start_child
from swim_ros.testing.processes import tagged_processes

#: the variable that marks every process a case's starter starts
TAG_VARIABLE = "SWIM_ORPHAN_PROBE"
#: from the signal to the starter's end: SIGKILL at once; SIGINT and SIGTERM stop its nodes (STOP_GRACE_S at most)
#: or swim-experiments' runs (INTERRUPT_GRACE_S at most); 30 s more for a loaded host
STARTER_EXIT_TIMEOUT_S = INTERRUPT_GRACE_S + 30.0
#: from the starter's end to the end of the last process it started: a node stops on its parent-death signal
#: within a second, a run process stops its nodes within STOP_GRACE_S, a node compiling its model's C code
#: (swim_model.codegen) ends once the compiler has (seconds); 30 s more for a loaded host
LEFT_TIMEOUT_S = STOP_GRACE_S + 30.0
#: how often a case looks at its starter's processes and files: a moment is caught within this
POLL_S = 0.05
#: a node's executable, as it appears in a node process's command line
NODE_EXECUTABLE = re.compile(r"/lib/swim_\w+/(sim_node|bridge_node|planner_node|tracker_node|maneuver_node"
                             r"|rig_state_publisher|marker_node)$")
#: what tracker_node logs when a plan starts: a run is under way
PLAN_STARTED = "executing a"
#: what tracker_node logs when it spins: swim-bringup's set is up
TRACKER_READY = "tracker ready"
#: planner_node up this long: bench_planner_latency's planner has loaded its library or nearly (about 2 s here) and
#: its requests (about a second) follow
PLANNER_SERVING_S = 2.0


class Case:
    """One starter run: its processes tagged, its output and files in folder, what the test sees of it."""

    def __init__(self, starter: "Starter", folder: Path) -> None:
        self.starter, self.folder = starter, folder
        self.tag = uuid.uuid4().hex
        (folder / "tmp").mkdir(parents=True)
        self.output_path = folder / "output.txt"
        command = [argument.replace("{folder}", str(folder)) for argument in starter.arguments]
        environment = {**os.environ, TAG_VARIABLE: self.tag, "TMPDIR": str(folder / "tmp"), "PYTHONUNBUFFERED": "1"}
        with open(self.output_path, "w") as output:
            # SIGINT as a terminal's Ctrl-C gives it, whatever this test inherited (a Python started with SIGINT
            # ignored keeps ignoring it)
            self.process = start_child(command, cwd=WORKSPACE, stdout=output, stderr=subprocess.STDOUT,
                                       env=environment, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        self.started_s = time.monotonic()
        self.nodes_seen: dict[int, float] = {}   # node pid -> when it was first seen (time.monotonic)
        self.nodes_ended: set[int] = set()

    def processes(self) -> dict[int, str]:
        """The live processes of this case (the starter too, while it lives), with their command lines."""
        return tagged_processes(TAG_VARIABLE, self.tag)

    def look(self) -> None:
        """Note the nodes that have appeared and those that have ended since the last look."""
        now = time.monotonic()
        alive = {pid for pid, command in self.processes().items()
                 if any(NODE_EXECUTABLE.search(part) for part in command.split(" "))}
        for pid in alive:
            self.nodes_seen.setdefault(pid, now)
        self.nodes_ended |= set(self.nodes_seen) - alive

    def alive(self) -> bool:
        return self.process.poll() is None

    def elapsed_s(self) -> float:
        return time.monotonic() - self.started_s

    def oldest_node_age_s(self) -> float:
        return time.monotonic() - min(self.nodes_seen.values()) if self.nodes_seen else 0.0

    def tracker_logged(self, text: str) -> bool:
        """Whether a tracker_node log of this case holds text (the starter's folders come and go meanwhile)."""
        for directory, _, files in os.walk(self.folder):
            try:
                if "tracker_node.log" in files and text in (Path(directory) / "tracker_node.log").read_text(
                        errors="replace"):
                    return True
            except OSError:
                continue
        return False

    def output(self) -> str:
        return self.output_path.read_text(errors="replace")

    def wait_until(self, event: Callable[["Case"], bool]) -> bool:
        """Look every POLL_S until event holds (True) or the starter has ended (False)."""
        while self.alive():
            self.look()
            if event(self):
                return True
            time.sleep(POLL_S)
        return False

    def sleep(self, seconds: float) -> None:
        """Sleep seconds, looking on; stop early if the starter ends."""
        end = time.monotonic() + seconds
        while self.alive() and time.monotonic() < end:
            self.look()
            time.sleep(min(POLL_S, max(0.0, end - time.monotonic())))

    def signal(self, signum: int) -> None:
        if self.alive():
            self.process.send_signal(signum)

    def finish(self) -> tuple[Optional[int], dict[int, str]]:
        """Wait for the starter's end (SIGKILL after STARTER_EXIT_TIMEOUT_S: None for its status then), then for
        its processes' (at most LEFT_TIMEOUT_S); those still there, which are then killed."""
        try:
            status: Optional[int] = self.process.wait(timeout=STARTER_EXIT_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            status = None
            self.process.kill()
            self.process.wait()
        deadline = time.monotonic() + LEFT_TIMEOUT_S
        while self.processes() and time.monotonic() < deadline:
            time.sleep(POLL_S)
        left = self.processes()
        for pid in left:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        return status, left

    def report(self, what: str, status: Optional[int], left: dict[int, str]) -> str:
        ended = f"exited with {status}" if status is not None else f"still running {STARTER_EXIT_TIMEOUT_S:.0f} s on"
        lines = [f"{self.starter.name}, {what}: the starter {ended}; left:"]
        lines += [f"  {pid} {command}" for pid, command in sorted(left.items())] or ["  nothing"]
        return "\n".join(lines + ["its output ends:", self.output()[-3000:]])


@dataclasses.dataclass(frozen=True)
class Starter:
    name: str
    arguments: tuple[str, ...]               # its command; "{folder}" is the case's own folder
    lifetime_s: float                        # start to exit on an idle 2-core host (swim-bringup: a time it is up)
    running: Callable[[Case], bool]          # the run is under way
    stops_on_a_signal: bool = False          # it runs until a stop signal (then stops its nodes)

    def __str__(self) -> str:
        return self.name


def ros2_run(executable: str, *arguments: str) -> tuple[str, ...]:
    return ("ros2", "run", "swim_bringup", executable, *arguments)


def plan_started(case: Case) -> bool:
    return case.tracker_logged(PLAN_STARTED)


SWIM_DEMO = Starter("swim-demo", ros2_run("swim-demo", "--run-dir", "{folder}/run", "--pipeline", "paper",
                                          "--primitives", "constrained/accelerate/E0.05", "--repeats", "1",
                                          "--timeout", "120"), 8.0, plan_started)
EXPERIMENTS = ("--only", "constrained_lambda1.67", "--seeds", "1", "--pipeline", "paper", "--run-dir", "{folder}/run")
SWIM_EXPERIMENTS = Starter("swim-experiments", ros2_run("swim-experiments", *EXPERIMENTS, "--jobs", "2"), 20.0,
                           plan_started)
SWIM_EXPERIMENTS_ONE_AT_A_TIME = Starter("swim-experiments-jobs1",
                                         ros2_run("swim-experiments", *EXPERIMENTS, "--jobs", "1"), 35.0, plan_started)
SWIM_BRINGUP = Starter("swim-bringup", ros2_run("swim-bringup", "sim", "--log-dir", "{folder}/logs"), 10.0,
                       lambda case: case.tracker_logged(TRACKER_READY), stops_on_a_signal=True)
BENCH_PLANNER_LATENCY = Starter("bench_planner_latency", (sys.executable, "bench/bench_planner_latency.py"), 7.0,
                                lambda case: case.oldest_node_age_s() >= PLANNER_SERVING_S)
BENCH_LOOP_JITTER = Starter("bench_loop_jitter", (sys.executable, "bench/bench_loop_jitter.py"), 37.0, plan_started)

CI_STARTERS = (SWIM_DEMO, SWIM_EXPERIMENTS, SWIM_BRINGUP, BENCH_PLANNER_LATENCY)
GRID_STARTERS = (SWIM_DEMO, SWIM_EXPERIMENTS_ONE_AT_A_TIME, SWIM_BRINGUP, BENCH_PLANNER_LATENCY, BENCH_LOOP_JITTER)
SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGKILL)


def start_up(case: Case, rng: random.Random) -> bool:
    """Within half a second of the start: the interpreter starting, the imports (no node yet)."""
    case.sleep(rng.uniform(0.0, 0.5))
    return case.alive()


def bring_up(case: Case, rng: random.Random) -> bool:
    """Within a second of the first node's start: the nodes importing, joining DDS, the client waiting for them."""
    if not case.wait_until(lambda c: bool(c.nodes_seen)):
        return False
    case.sleep(rng.uniform(0.0, 1.0))
    return case.alive()


def run(case: Case, rng: random.Random) -> bool:
    """Within half a second of the run getting under way (a plan tracked; swim-bringup's set up)."""
    if not case.wait_until(case.starter.running):
        return False
    case.sleep(rng.uniform(0.0, 0.5))
    return case.alive()


def shutdown(case: Case, rng: random.Random) -> bool:
    """The moment a node of the run has ended, the starter alive: its nodes being stopped (swim-bringup's after a
    first SIGINT). swim-experiments with one run at a time brings the next run up right after."""
    if case.starter.stops_on_a_signal:
        if not case.wait_until(case.starter.running):
            return False
        case.signal(signal.SIGINT)
    return case.wait_until(lambda c: bool(c.nodes_ended))


#: the moments of the grid, each a wait that returns whether the starter was still alive at that moment
MOMENTS: dict[str, Callable[[Case, random.Random], bool]] = {
    "start-up": start_up, "bring-up": bring_up, "run": run, "shutdown": shutdown}


@pytest.mark.parametrize("signum", (signal.SIGTERM, signal.SIGKILL), ids=lambda s: signal.Signals(s).name)
@pytest.mark.parametrize("starter", CI_STARTERS, ids=str)
def test_a_starter_killed_at_a_random_moment_leaves_nothing(ros_domain, tmp_path, starter, signum):
    moment_s = random.uniform(0.0, starter.lifetime_s)
    case = Case(starter, tmp_path)
    try:
        case.sleep(moment_s - case.elapsed_s())
        alive = case.alive()
        case.signal(signum)
    finally:
        status, left = case.finish()
    what = (f"{signal.Signals(signum).name} {moment_s:.2f} s after its start"
            + ("" if alive else " (it had ended by then)"))
    assert not left and status is not None, case.report(what, status, left)


@pytest.mark.slow
@pytest.mark.parametrize("moment", MOMENTS)
@pytest.mark.parametrize("signum", SIGNALS, ids=lambda s: signal.Signals(s).name)
@pytest.mark.parametrize("starter", GRID_STARTERS, ids=str)
def test_every_starter_signal_and_moment_leaves_nothing(ros_domain, tmp_path, starter, signum, moment):
    rng = random.Random()
    case = Case(starter, tmp_path)
    try:
        reached = MOMENTS[moment](case, rng)
        signalled_s = case.elapsed_s()
        case.signal(signum)
    finally:
        status, left = case.finish()
    what = f"{signal.Signals(signum).name} at its {moment}, {signalled_s:.2f} s after its start"
    assert not left and status is not None, case.report(what, status, left)
    assert reached, case.report(f"it ended before its {moment}", status, left)
