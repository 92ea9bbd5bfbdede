"""The real-time means: applied where permitted (this host runs tests as root), refused with a reason and nothing
changed where not (the same code as an unprivileged user), the CPU list, and the collector between periods. Each
case runs in a child process: the means change the process they are applied to."""
import json
import os
import shutil
import subprocess
import sys
import textwrap

import pytest

from swim_ros.realtime import (
    NO_REALTIME_MEANS,
    RealtimeOutcome,
    RealtimeSettings,
    parse_cpu_list,
    settings_reason_invalid,
)

#: an unprivileged user to run as (nobody), through util-linux's setpriv
UNPRIVILEGED = ["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups", "--inh-caps=-all"]


def run_child(code: str, prefix: tuple[str, ...] = ()) -> dict:
    """Run code in a fresh Python (it prints one JSON object last); that object."""
    completed = subprocess.run([*prefix, sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                               text=True, timeout=60, env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"})
    assert completed.returncode == 0, completed.stderr
    return json.loads(completed.stdout.strip().splitlines()[-1])


APPLY = """
    import json, os, threading
    from swim_ros.realtime import RealtimeSettings, make_process_realtime, memory_locked_kib
    def each_thread(read):
        values = []
        for name in os.listdir("/proc/self/task"):
            try:
                values.append(read(int(name)))
            except ProcessLookupError:   # a thread joined can still be listed for a moment after it ended
                pass
        return values
    started = threading.Event(); stop = threading.Event()
    def worker():
        started.set(); stop.wait()
    thread = threading.Thread(target=worker); thread.start(); started.wait()   # a thread made before
    try:
        outcome = make_process_realtime(RealtimeSettings(**{settings}))
        later = {{}}
        def made_after():
            later["policy"] = os.sched_getscheduler(0)
        after = threading.Thread(target=made_after); after.start(); after.join()
        policies = each_thread(os.sched_getscheduler)
        priorities = each_thread(lambda t: os.sched_getparam(t).sched_priority)
    finally:   # an error still ends the worker, so the process exits with it instead of waiting for the thread
        stop.set(); thread.join()
    print(json.dumps({{"applied": outcome.applied, "refused": outcome.refused, "policies": policies,
                      "priorities": priorities, "later": later["policy"], "locked_kib": memory_locked_kib(),
                      "affinity": sorted(os.sched_getaffinity(0))}}))
"""


@pytest.mark.skipif(os.geteuid() != 0, reason="applying the means needs root (CI runs as root)")
def test_the_means_apply_to_every_thread_and_to_threads_made_later():
    cpu = max(os.sched_getaffinity(0))
    result = run_child(APPLY.format(settings=f"dict(policy='fifo', priority=42, cpu_affinity='{cpu}')"))
    assert result["refused"] == []
    assert set(result["policies"]) == {os.SCHED_FIFO} and set(result["priorities"]) == {42}
    assert result["later"] == os.SCHED_FIFO   # inherited from its creator
    assert result["locked_kib"] > 1024 and result["affinity"] == [cpu]


@pytest.mark.skipif(shutil.which("setpriv") is None, reason="needs util-linux's setpriv to drop privileges")
def test_an_unprivileged_process_is_told_why_and_runs_on_unchanged():
    result = run_child(APPLY.format(settings="dict(policy='fifo', priority=42)"), tuple(UNPRIVILEGED))
    assert set(result["policies"]) == {os.SCHED_OTHER} and result["locked_kib"] == 0   # nothing changed
    reasons = " ".join(result["refused"])
    assert "SCHED_FIFO priority 42: not permitted" in reasons and "rtprio limit" in reasons
    assert "mlockall" in reasons
    outcome = RealtimeOutcome(tuple(result["applied"]), tuple(result["refused"]))
    assert "refused" in outcome.summary() and "docs/rig_session.md" in outcome.summary()


def test_other_leaves_the_policy_as_started():
    result = run_child(APPLY.format(settings="dict(policy='other', lock_memory=False)"))
    assert result["refused"] == [] and result["applied"] == []
    assert set(result["policies"]) == {os.sched_getscheduler(0)}


def test_cpu_lists_read_as_taskset_writes_them():
    assert parse_cpu_list("1") == {1} and parse_cpu_list("0,2") == {0, 2}
    assert parse_cpu_list("0-2,5") == {0, 1, 2, 5}
    for bad in ("", "a", "3-1", "1,", "-1", "1-"):
        with pytest.raises(ValueError):
            parse_cpu_list(bad)


def test_settings_that_cannot_be_asked_for_are_named():
    assert settings_reason_invalid(RealtimeSettings()) is None and settings_reason_invalid(NO_REALTIME_MEANS) is None
    assert "policy" in settings_reason_invalid(RealtimeSettings(policy="deadline"))
    assert "priority" in settings_reason_invalid(RealtimeSettings(priority=99))
    assert "CPU list" in settings_reason_invalid(RealtimeSettings(cpu_affinity="x"))


def test_the_collector_runs_only_between_periods_and_frees_cycles():
    result = run_child("""
        import gc, json, weakref
        from swim_ros.realtime import PeriodicCollector
        class Node:
            pass
        collector = PeriodicCollector(10)
        automatic = gc.isenabled()
        freed = []
        def cycle():
            a, b = Node(), Node()
            a.other, b.other = b, a
            weakref.finalize(a, freed.append, 1)
        for _ in range(2000):   # far past gen 0's threshold (700): no automatic collection frees them
            cycle()
        before = len(freed)
        for _ in range(9):
            collector.after_period()
        after_nine = len(freed)
        collector.after_period()   # the tenth period's end: a collection
        frozen = gc.get_freeze_count()
        collector.stop()
        print(json.dumps({"automatic": automatic, "before": before, "after_nine": after_nine,
                          "after_ten": len(freed), "collections": collector.collections,
                          "longest_s": collector.longest_s, "frozen": frozen, "enabled": gc.isenabled()}))
    """)
    assert not result["automatic"] and result["before"] == 0 and result["after_nine"] == 0
    assert result["after_ten"] == 2000 and result["collections"] == 1
    assert 0.0 < result["longest_s"] < 1.0 and result["frozen"] > 0 and result["enabled"]


@pytest.mark.skipif(os.geteuid() != 0, reason="applying the means needs root (CI runs as root)")
def test_a_background_thread_runs_below_the_periods_and_its_children_as_ordinary_processes():
    result = run_child("""
        import json, os, subprocess
        from swim_ros.realtime import BACKGROUND_PRIORITY, RealtimeSettings, make_thread_background
        make_thread_background(RealtimeSettings())
        child = subprocess.run(["python3", "-c", "import os; print(os.sched_getscheduler(0))"],
                               capture_output=True, text=True).stdout
        print(json.dumps({"policy": os.sched_getscheduler(0), "priority": os.sched_getparam(0).sched_priority,
                          "child": int(child), "lowest": BACKGROUND_PRIORITY}))
    """)
    assert result["policy"] == os.SCHED_FIFO | os.SCHED_RESET_ON_FORK
    assert result["priority"] == result["lowest"] == 1
    assert result["child"] == os.SCHED_OTHER
