"""Runs side by side (swim_bringup.parallel) with cheap stand-in runs, pure Python in real processes (no DDS): each
run's process holds a ROS domain no other run at the same time holds, none the caller's; whatever stops a run
(an exception, a process that dies, one that hangs, on this host or a Dask worker) is named, and the other runs'
results are kept. A caller killed outright takes its runs and what they started with it; a caller interrupted
starts no further run and interrupts those under way, which stop what they started."""
import concurrent.futures
import os
import signal
import subprocess
import sys
import textwrap
import time
import uuid
from pathlib import Path

import pytest

from swim_bringup.parallel import RunFailed, run_all, run_isolated
from swim_ros.domains import RUN_DOMAINS
from swim_ros.processes import start_child
from swim_ros.testing.processes import processes_left

#: how long a stand-in waits for the others to start: all start at once on an idle host, within seconds on a busy one
START_TIMEOUT_S = 120.0


def domain_once_all_started(task: tuple[Path, int, str]) -> tuple[int, int]:
    """A stand-in run: note it started, wait until `count` runs have, then give its ROS domain and process id
    (so every run is alive, holding its domain, while the others read theirs)."""
    folder, count, name = task
    (folder / name).write_text(str(os.getpid()))
    deadline = time.monotonic() + START_TIMEOUT_S
    while len(list(folder.iterdir())) < count:
        if time.monotonic() > deadline:
            raise TimeoutError(f"only {len(list(folder.iterdir()))} of {count} runs started")
        time.sleep(0.05)
    return int(os.environ["ROS_DOMAIN_ID"]), os.getpid()


def fail_on_seed_three(seed: int) -> int:
    """A stand-in run that fails for seed 3, and exits its process without a word for seed 4."""
    if seed == 3:
        raise ValueError("the plan of seed 3 was lost")
    if seed == 4:
        os._exit(7)
    return 10 * seed


def sleep_forever(_: object) -> None:
    time.sleep(3600.0)


#: the variable that tags the processes of a caller started by a test (its runs and theirs inherit it)
TAG_VARIABLE = "SWIM_PARALLEL_TEST"
#: how long the processes of a stopped caller may take to end: a run process stops its child at once
END_TIMEOUT_S = 30.0


def start_a_child_and_wait(folder: Path) -> None:
    """A stand-in run that starts a child as a bring-up starts its nodes, notes its start, and waits; in its
    `finally` (where a run stops its nodes) it notes its stop."""
    child = start_child(["sleep", "3600"])
    (folder / f"started-{os.getpid()}").touch()
    try:
        child.wait()
    finally:
        child.terminate()
        (folder / f"stopped-{os.getpid()}").touch()


#: how the caller of start_caller stops: SIGINT as a terminal's Ctrl-C gives it, whatever this test inherited (a
#: Python started with SIGINT ignored keeps ignoring it, as one put in the background by a shell without job control
#: is); or, as a CLI put in the background that way, SIGINT ignored (its runs inherit that) and SIGTERM taken as Ctrl-C
CTRL_C, BACKGROUND = "signal.default_int_handler", "signal.SIG_IGN"


def start_caller(folder: Path, runs: int, jobs: int, tag: str, sigint: str = CTRL_C) -> subprocess.Popen:
    """A process that runs `runs` stand-in runs (start_a_child_and_wait), `jobs` at once, through run_all; its
    SIGINT handler sigint, its SIGTERM Ctrl-C."""
    script = textwrap.dedent(f"""
        import concurrent.futures, signal, sys
        signal.signal(signal.SIGINT, {sigint})
        signal.signal(signal.SIGTERM, signal.default_int_handler)
        from pathlib import Path
        sys.path.insert(0, {str(Path(__file__).parent)!r})
        from swim_bringup.parallel import run_all
        from test_parallel import start_a_child_and_wait
        tasks = {{f"run{{k}}": Path({str(folder)!r}) for k in range({runs})}}
        with concurrent.futures.ThreadPoolExecutor({jobs}) as executor:
            run_all(start_a_child_and_wait, tasks, executor, timeout_s=3600.0)
        """)
    return start_child([sys.executable, "-c", script], env={**os.environ, TAG_VARIABLE: tag})


def wait_for_starts(folder: Path, count: int, caller: subprocess.Popen) -> None:
    deadline = time.monotonic() + START_TIMEOUT_S
    while len(list(folder.glob("started-*"))) < count:
        assert caller.poll() is None and time.monotonic() < deadline, "the runs did not start"
        time.sleep(0.05)


def assert_nothing_left(tag: str) -> None:
    """No process tagged tag within END_TIMEOUT_S; whatever is left is killed after the assertion."""
    assert processes_left(TAG_VARIABLE, tag, END_TIMEOUT_S) == []


def test_a_killed_caller_takes_its_runs_and_what_they_started_with_it(tmp_path):
    """SIGKILL of the caller: each run process gets its parent-death signal, stops what it started (its `finally`
    runs, as a run's nodes are stopped) and ends."""
    tag = uuid.uuid4().hex
    caller = start_caller(tmp_path, runs=2, jobs=2, tag=tag)
    try:
        wait_for_starts(tmp_path, 2, caller)
    finally:
        caller.kill()
        caller.wait()
    assert_nothing_left(tag)
    assert len(list(tmp_path.glob("stopped-*"))) == 2


@pytest.mark.parametrize("sigint, stop", [(CTRL_C, signal.SIGINT), (BACKGROUND, signal.SIGTERM)],
                         ids=["ctrl_c", "sigterm_with_sigint_ignored"])
def test_an_interrupted_caller_starts_no_further_run_and_stops_those_under_way(tmp_path, sigint, stop):
    """SIGINT to the caller alone (not its process group), or SIGTERM to a caller started with SIGINT ignored (its
    run processes inherit that): run_all cancels the runs not started and interrupts the one under way, which stops
    the graceful way at once (not killed after INTERRUPT_GRACE_S), so the caller ends within seconds instead of
    running the others."""
    tag = uuid.uuid4().hex
    caller = start_caller(tmp_path, runs=3, jobs=1, tag=tag, sigint=sigint)
    try:
        wait_for_starts(tmp_path, 1, caller)
        caller.send_signal(stop)
        caller.wait(timeout=END_TIMEOUT_S)
    finally:
        caller.kill()
        caller.wait()
    assert_nothing_left(tag)
    assert len(list(tmp_path.glob("started-*"))) == len(list(tmp_path.glob("stopped-*"))) == 1


def test_runs_at_once_hold_distinct_domains_none_the_callers(tmp_path, monkeypatch):
    monkeypatch.setenv("ROS_DOMAIN_ID", "7")        # a caller's domain: no run may inherit it
    runs = 3
    tasks = {f"run{k}": (tmp_path, runs, f"run{k}") for k in range(runs)}
    with concurrent.futures.ThreadPoolExecutor(runs) as executor:
        outcomes = run_all(domain_once_all_started, tasks, executor, timeout_s=2 * START_TIMEOUT_S)
    assert list(outcomes) == list(tasks)
    assert all(outcome.failure is None for outcome in outcomes.values()), [o.failure for o in outcomes.values()]
    results = [outcome.result for outcome in outcomes.values()]
    domains, pids = [r[0] for r in results], [r[1] for r in results]
    assert len(set(pids)) == runs and os.getpid() not in pids          # each run a process of its own
    assert len(set(domains)) == runs, domains                          # ... and a domain of its own
    assert all(domain in RUN_DOMAINS for domain in domains) and 7 not in domains


def test_a_failed_run_is_named_and_the_others_kept():
    tasks = {f"experiment/seed{seed}/sliding_on": seed for seed in (1, 2, 3, 4)}
    finished = []
    with concurrent.futures.ThreadPoolExecutor(2) as executor:
        outcomes = run_all(fail_on_seed_three, tasks, executor, timeout_s=120.0,
                           done=lambda run, outcome: finished.append(run))
    assert sorted(finished) == sorted(tasks)
    assert [outcomes[f"experiment/seed{seed}/sliding_on"].result for seed in (1, 2)] == [10, 20]
    failure = outcomes["experiment/seed3/sliding_on"].failure
    assert failure is not None and failure.run == "experiment/seed3/sliding_on"
    assert failure.reason == "ValueError: the plan of seed 3 was lost"
    died = outcomes["experiment/seed4/sliding_on"].failure
    assert died is not None and died.reason.startswith("its process exited with 7"), died.reason


def test_a_hung_run_is_interrupted_and_named():
    started = time.monotonic()
    with pytest.raises(RunFailed, match=r"^hung/seed1/sliding_off: no result within 2 s: interrupted") as failed:
        run_isolated(sleep_forever, None, "hung/seed1/sliding_off", timeout_s=2.0)
    assert failed.value.run == "hung/seed1/sliding_off"
    assert time.monotonic() - started < 60.0


def test_runs_go_to_a_dask_cluster_the_same_way(tmp_path):
    """A Dask cluster in this process (one worker of two threads, on TCP as a remote one would be): its workers
    start the runs' processes, each with a domain of its own, and a failure comes back named."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, protocol="tcp",
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster.scheduler_address) as client:
        assert cluster.scheduler_address.startswith("tcp://")
        executor = client.get_executor()
        outcomes = run_all(domain_once_all_started, {f"run{k}": (tmp_path, 2, f"run{k}") for k in range(2)},
                           executor, timeout_s=2 * START_TIMEOUT_S)
        failed = run_all(fail_on_seed_three, {"lost/seed3/sliding_on": 3}, executor, timeout_s=120.0)
    domains = [outcome.result[0] for outcome in outcomes.values() if outcome.result is not None]
    assert len(set(domains)) == 2, [outcome.failure for outcome in outcomes.values()]
    failure = failed["lost/seed3/sliding_on"].failure
    assert failure is not None and (failure.run, failure.reason) == ("lost/seed3/sliding_on",
                                                                     "ValueError: the plan of seed 3 was lost")
