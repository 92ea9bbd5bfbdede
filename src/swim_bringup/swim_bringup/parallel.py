"""Runs side by side, each in a fresh process on a ROS domain of its own, on this host's cores or a Dask cluster.

A run is a function of one picklable task, importable by name (a module's top-level function). ``run_isolated``
calls it in a new Python process (``python -m swim_bringup.parallel``) that claims a ROS domain in
swim_ros.domains.RUN_DOMAINS before anything else: the caller's ROS_DOMAIN_ID is not passed on, since two runs at
once must never share a domain, and a process keeps the domain it claimed for its life. ``run_all`` submits every
run to a ``concurrent.futures.Executor``: a thread pool on this host (each thread only waits on its run's
process), or a Dask ``distributed.Client``'s executor, whose workers then start the runs' processes on their hosts
(swim installed there too). Whatever stops a run (an exception of the function, a process that died or hung, a
lost worker) comes back as a RunFailed naming the run and why; the other runs' results are kept.

A run's process dies with the one that started it (swim_ros.processes.start_child) and takes that death's signal,
SIGTERM, as Ctrl-C: it stops its nodes before it ends. A caller that stops (Ctrl-C, SIGTERM) while run_all waits
starts no further run and interrupts those under way on this host.
"""
from __future__ import annotations

import concurrent.futures
import os
import pickle
import signal
import subprocess
import sys
import tempfile
import threading
from pathlib import Path
from typing import Any, Callable, Generic, Mapping, Optional, TypeVar

from swim_ros.processes import interrupt_on_sigterm, start_child

T = TypeVar("T")
R = TypeVar("R")

#: how long a run's process has to stop after SIGINT (it stops its nodes: swim_ros.processes.STOP_GRACE_S each,
#: in parallel, and leaves DDS) before it is killed
INTERRUPT_GRACE_S = 30.0
#: the lines of a dead run process's output its failure quotes
FAILURE_OUTPUT_LINES = 20

#: the run processes under way in this process, and whether its run_all is stopping (then a run process that starts
#: is interrupted at once): what a caller's Ctrl-C interrupts
_running: set[subprocess.Popen[str]] = set()
_stopping = False
_running_lock = threading.Lock()


class RunFailed(RuntimeError):
    """A run that gave no result: run is its label, reason says why."""

    def __init__(self, run: str, reason: str) -> None:
        super().__init__(f"{run}: {reason}")
        self.run, self.reason = run, reason

    def __reduce__(self) -> tuple[type, tuple[str, str]]:   # back from a Dask worker with both fields
        """Pickle the failure with both fields (back from a Dask worker)."""
        return (RunFailed, (self.run, self.reason))


class Outcome(Generic[R]):
    """A run's result or its failure (exactly one is set)."""

    def __init__(self, result: Optional[R] = None, failure: Optional[RunFailed] = None) -> None:
        self.result, self.failure = result, failure


def _tail(text: str) -> str:
    lines = text.strip().splitlines()[-FAILURE_OUTPUT_LINES:]
    return " | ".join(line.strip() for line in lines if line.strip()) or "no output"


def run_isolated(function: Callable[[T], R], task: T, run: str, timeout_s: float) -> R:
    """Call function(task) in a new Python process with a ROS domain of its own; its result.

    function(task) in a new Python process with a ROS domain of its own; its result. RunFailed(run, reason) if
    the function raised (reason: the exception's type and message), its process died (its exit code and the end
    of its output) or it ran longer than timeout_s (then it is interrupted like Ctrl-C, and killed after
    INTERRUPT_GRACE_S).
    """
    environment = {key: value for key, value in os.environ.items() if key != "ROS_DOMAIN_ID"}
    environment["PYTHONPATH"] = os.pathsep.join(path for path in sys.path if path)   # the caller's imports
    with tempfile.TemporaryDirectory(prefix="swim_run_") as folder:
        call, answer = Path(folder) / "call.pickle", Path(folder) / "answer.pickle"
        call.write_bytes(pickle.dumps((function, task)))
        # the thread that starts the process waits for its end below, so the parent-death signal, which comes when
        # that thread ends, never comes early
        process = start_child([sys.executable, "-m", "swim_bringup.parallel", str(call), str(answer)],
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=environment)
        try:
            _track(process)
            output, _ = process.communicate(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            process.send_signal(signal.SIGINT)
            try:
                output, _ = process.communicate(timeout=INTERRUPT_GRACE_S)
            except subprocess.TimeoutExpired:
                process.kill()
                output, _ = process.communicate()
            raise RunFailed(run, f"no result within {timeout_s:.0f} s: interrupted ({_tail(output)})") from None
        except BaseException:   # the caller is stopping (Ctrl-C): the run stops its nodes before we go
            process.send_signal(signal.SIGINT)
            try:
                process.wait(INTERRUPT_GRACE_S)
            except subprocess.TimeoutExpired:
                process.kill()
            raise
        finally:
            _untrack(process)
        if not answer.exists():
            raise RunFailed(run, f"its process exited with {process.returncode} ({_tail(output)})")
        kind, value = pickle.loads(answer.read_bytes())
    if kind == "error":
        raise RunFailed(run, value)
    return value


def _track(process: subprocess.Popen[str]) -> None:
    with _running_lock:
        _running.add(process)
        if _stopping:
            process.send_signal(signal.SIGINT)


def _untrack(process: subprocess.Popen[str]) -> None:
    with _running_lock:
        _running.discard(process)


def _interrupt_runs(stopping: bool) -> None:
    """Interrupt the run processes under way and any that start, or start runs normally again.

    With stopping, SIGINT to every run process under way, and to any that starts from now on; without, runs
    start normally again.
    """
    global _stopping
    with _running_lock:
        _stopping = stopping
        if stopping:
            for process in _running:
                process.send_signal(signal.SIGINT)   # nothing if it has ended


def run_all(function: Callable[[T], R], tasks: Mapping[str, T], executor: concurrent.futures.Executor,
            timeout_s: float, done: Callable[[str, Outcome[R]], None] = lambda run, outcome: None
            ) -> dict[str, Outcome[R]]:
    """Every task's run in its own process, by its label.

    Every task's run (run_isolated, submitted to executor), by its label (the keys of tasks); done is called
    with each as it ends. A run that failed has its RunFailed; the executor's own failures (a lost Dask worker)
    are named the same way. If the caller stops while waiting (Ctrl-C, SIGTERM as Ctrl-C), the runs not started
    are cancelled and those under way on this host interrupted (they stop their nodes), then the exception goes
    on.
    """
    _interrupt_runs(stopping=False)
    futures = {executor.submit(run_isolated, function, task, run, timeout_s): run for run, task in tasks.items()}
    outcomes: dict[str, Outcome[R]] = {}
    try:
        for future in concurrent.futures.as_completed(futures):
            run = futures[future]
            try:
                outcome: Outcome[R] = Outcome(result=future.result())
            except RunFailed as failure:
                outcome = Outcome(failure=failure)
            except Exception as err:   # noqa: BLE001 - whatever stops a run is named, and the others kept
                outcome = Outcome(failure=RunFailed(run, f"{type(err).__name__}: {err}"))
            outcomes[run] = outcome
            done(run, outcome)
    except BaseException:
        for future in futures:
            future.cancel()
        _interrupt_runs(stopping=True)
        raise
    return {run: outcomes[run] for run in tasks}


def _run_in_this_process(call: Path, answer: Path) -> None:
    """The new process's side of run_isolated.

    Claim a domain, call the function, write its result or error. SIGINT, how run_isolated stops a run, is Ctrl-C here
    even where the caller was started with SIGINT ignored (a command put in the background by a shell without job
    control: Python then leaves it ignored, and the process inherits that), and so is SIGTERM (the parent-death signal
    among others): the run stops its nodes before the process ends.
    """
    signal.signal(signal.SIGINT, signal.default_int_handler)
    interrupt_on_sigterm()
    from swim_ros.domains import RUN_DOMAINS, claim_ros_domain
    claim_ros_domain(RUN_DOMAINS)
    function, task = pickle.loads(call.read_bytes())
    reply: tuple[str, Any]
    try:
        reply = ("result", function(task))
    except Exception as err:   # noqa: BLE001 - the run's failure, named for the caller
        reply = ("error", f"{type(err).__name__}: {err}")
    answer.write_bytes(pickle.dumps(reply))


if __name__ == "__main__":
    _run_in_this_process(Path(sys.argv[1]), Path(sys.argv[2]))
