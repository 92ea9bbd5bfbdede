"""The real-time means of a periodic process.

Scheduling policy and priority, locked memory, CPU affinity, and the garbage collector kept out of the period.

The means are those of the ROS 2 real-time guides (the pendulum_control demo, realtime_tools) and of
ros2_control's controller manager: a real-time policy (SCHED_FIFO) so that ordinary processes cannot delay the
loop, mlockall so that no page fault stalls it, a CPU set (with isolcpus on the rig), and no garbage collection
in the periodic path. Each takes effect where the permission exists (root, CAP_SYS_NICE or an rtprio limit for
the policy; CAP_IPC_LOCK or a memlock limit for the locked memory) and is otherwise reported as refused, so that
the node says it once and runs on as an ordinary process.

Threads: on Linux the scheduling policy belongs to a thread, and a new thread inherits its creator's. So
``make_process_realtime`` sets every thread the process has (the executor's, the middleware's), and
``make_thread_realtime`` and ``make_thread_background`` set the calling thread: a loop thread above the rest, a
compilation thread at the lowest real-time priority, whose children (a C compiler) run as ordinary processes.
The interpreter's switch interval is shortened too (SWITCH_INTERVAL_S), so that a woken periodic thread waits
little for the interpreter lock.

The garbage collector: ``PeriodicCollector`` freezes every object the start-up made (gc.freeze: a collection
never walks them again), turns automatic collection off (it would run inside whichever period allocates the
object that crosses its threshold) and collects what the periods leave behind at a fixed interval, at the end of
a period, where the loop calls it.
"""
from __future__ import annotations

import ctypes
import ctypes.util
import dataclasses
import gc
import os
import sys
import time
from pathlib import Path
from typing import Optional

#: the policies a node can ask for ("other": the ordinary time-sharing policy, no real-time means)
SCHEDULING_POLICIES = {"fifo": os.SCHED_FIFO, "rr": os.SCHED_RR, "other": os.SCHED_OTHER}
#: the interpreter's switch interval in a real-time process, s: how long a woken real-time thread waits at most for
#: another thread to hand over the interpreter lock before it is taken from that thread (Python's default, 5 ms, is
#: most of an 8 ms period)
SWITCH_INTERVAL_S = 0.5e-3
#: the priority of a real-time process's background thread (a model build): the lowest real-time one, so that an
#: ordinary process cannot preempt it while it holds the interpreter lock a periodic thread waits for
BACKGROUND_PRIORITY = 1
#: mlockall(2) flags: what is mapped now, what will be, and "as each page is first touched" (Linux 4.4)
_MCL_CURRENT, _MCL_FUTURE, _MCL_ONFAULT = 1, 2, 4


@dataclasses.dataclass(frozen=True)
class RealtimeSettings:
    """What a node asks for.

    policy: a key of SCHEDULING_POLICIES; priority: 1-98 for fifo and rr (ignored for other); lock_memory: mlockall of
    the current and future pages; cpu_affinity: taskset's list form ("1", "0,2", "2-3"), empty for every CPU;
    collect_garbage_between_periods: PeriodicCollector instead of automatic collection.
    """

    policy: str = "fifo"
    priority: int = 70
    lock_memory: bool = True
    cpu_affinity: str = ""
    collect_garbage_between_periods: bool = True

    @property
    def realtime(self) -> bool:
        """Whether the policy is a real-time one (not the ordinary "other")."""
        return self.policy != "other"


#: no means at all: the ordinary policy as started, nothing locked, the collector automatic
NO_REALTIME_MEANS = RealtimeSettings(policy="other", lock_memory=False, collect_garbage_between_periods=False)


@dataclasses.dataclass(frozen=True)
class RealtimeOutcome:
    """What took effect (applied) and what was refused, each a short phrase with its reason."""

    applied: tuple[str, ...]
    refused: tuple[str, ...]

    def summary(self) -> str:
        """One line for the node's log: what is in effect, and what is not and why."""
        applied = ", ".join(self.applied) or "none"
        if not self.refused:
            return f"real-time means in effect: {applied}"
        return (f"real-time means refused: {'; '.join(self.refused)} (in effect: {applied}); the loop runs as an "
                f"ordinary process and a busy host can delay it (docs/rig_session.md, 'The rig PC')")


def parse_cpu_list(text: str) -> frozenset[int]:
    """A CPU list as taskset writes it ("1", "0,2", "2-3", "0-1,3"), as a set; ValueError otherwise or if empty."""
    cpus: set[int] = set()
    for part in text.replace(" ", "").split(","):
        low, dash, high = part.partition("-")
        if not low.isdigit() or (dash and not high.isdigit()):
            raise ValueError(f"CPU list {text!r}: expected numbers and ranges such as '1', '0,2' or '2-3'")
        first, last = int(low), int(high) if dash else int(low)
        if last < first:
            raise ValueError(f"CPU list {text!r}: range {part} runs backwards")
        cpus.update(range(first, last + 1))
    return frozenset(cpus)


def settings_reason_invalid(settings: RealtimeSettings) -> Optional[str]:
    """Why settings cannot be asked for at all (not whether this host permits them), or None."""
    if settings.policy not in SCHEDULING_POLICIES:
        return f"policy must be one of {', '.join(SCHEDULING_POLICIES)}, got {settings.policy!r}"
    if settings.realtime and not 1 <= settings.priority <= 98:
        return f"priority must be in [1, 98] (99 is the kernel's own threads'), got {settings.priority}"
    if settings.cpu_affinity:
        try:
            parse_cpu_list(settings.cpu_affinity)
        except ValueError as err:
            return str(err)
    return None


def _set_policy(thread_id: int, settings: RealtimeSettings, priority: int) -> Optional[str]:
    """Set the policy of one thread (0: the calling one); the refusal's reason, or None."""
    policy = SCHEDULING_POLICIES[settings.policy]
    try:
        os.sched_setscheduler(thread_id, policy, os.sched_param(priority if settings.realtime else 0))
    except PermissionError:
        return (f"SCHED_{settings.policy.upper()} priority {priority}: not permitted (rtprio limit "
                f"{_rtprio_limit()}; needs CAP_SYS_NICE or an rtprio limit of at least {priority})")
    except ProcessLookupError:
        return None   # the thread ended meanwhile
    except OSError as err:
        return f"SCHED_{settings.policy.upper()} priority {priority}: {err.strerror}"
    return None


def _rtprio_limit() -> str:
    import resource
    soft, _ = resource.getrlimit(resource.RLIMIT_RTPRIO)
    return "unlimited" if soft == resource.RLIM_INFINITY else str(soft)


def _thread_ids() -> list[int]:
    try:
        return sorted(int(name) for name in os.listdir("/proc/self/task"))
    except OSError:
        return [0]


_CAP_IPC_LOCK = 14   # capability(7)'s bit


def _has_capability(bit: int) -> bool:
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("CapEff:"):
                return bool(int(line.split()[1], 16) >> bit & 1)
    except (OSError, ValueError, IndexError):
        pass
    return False


def _lock_memory() -> Optional[str]:
    """Lock the current and future pages (mlockall), each as it is first touched (MCL_ONFAULT).

    The refusal's reason, or None. On fault, not at once: populating and locking every mapping at once (1.4 GB of
    libraries, stacks and middleware segments for a node here) held this host's kernel long enough to delay a real-time
    task on the same CPU by 6 ms; a page the loop touches is still never paged out once touched. Future pages are locked
    only without a limit: under a finite memlock limit an allocation past it would fail later, in a period.
    """
    import resource
    soft, _ = resource.getrlimit(resource.RLIMIT_MEMLOCK)
    if soft != resource.RLIM_INFINITY and not _has_capability(_CAP_IPC_LOCK):
        return (f"mlockall: the memlock limit is {soft // 1024} KiB and locking future pages under a limit makes "
                "allocations fail once it is reached (set memlock unlimited, or give CAP_IPC_LOCK)")
    libc = ctypes.CDLL(ctypes.util.find_library("c"), use_errno=True)
    if libc.mlockall(_MCL_CURRENT | _MCL_FUTURE | _MCL_ONFAULT) != 0:
        return f"mlockall: {os.strerror(ctypes.get_errno())}"
    return None


def make_process_realtime(settings: RealtimeSettings) -> RealtimeOutcome:
    """Apply settings to the whole process.

    The policy to every thread it has (threads made later inherit it from their creator), the CPU set to every thread,
    and mlockall. Never raises for a refusal: see RealtimeOutcome.
    """
    reason = settings_reason_invalid(settings)
    if reason is not None:
        raise ValueError(reason)
    applied: list[str] = []
    refused: list[str] = []
    if settings.cpu_affinity:
        cpus = parse_cpu_list(settings.cpu_affinity)
        try:
            for thread_id in _thread_ids():
                try:
                    os.sched_setaffinity(thread_id, cpus)
                except ProcessLookupError:
                    pass   # the thread ended meanwhile
            applied.append(f"CPUs {settings.cpu_affinity}")
        except OSError as err:
            refused.append(f"CPUs {settings.cpu_affinity}: {err.strerror} (this host has CPUs "
                           f"{sorted(os.sched_getaffinity(0))})")
    if settings.realtime:   # "other" leaves the policy the process was started with (chrt, a launcher's)
        reasons = {r for r in (_set_policy(t, settings, settings.priority) for t in _thread_ids()) if r is not None}
        refused.extend(sorted(reasons))
        if not reasons:
            applied.append(f"SCHED_{settings.policy.upper()} priority {settings.priority}")
            sys.setswitchinterval(SWITCH_INTERVAL_S)
    if settings.lock_memory:
        reason = _lock_memory()
        if reason is None:
            applied.append("memory locked")
        else:
            refused.append(reason)
    return RealtimeOutcome(tuple(applied), tuple(refused))


def make_process_ordinary() -> None:
    """Every thread of the process back to the ordinary policy (locked memory stays locked)."""
    for thread_id in _thread_ids():
        try:
            os.sched_setscheduler(thread_id, os.SCHED_OTHER, os.sched_param(0))
        except OSError:
            pass   # lowering a policy is always permitted; a thread that ended meanwhile has none


def make_thread_realtime(settings: RealtimeSettings, priority: int) -> Optional[str]:
    """The calling thread at settings' policy and this priority (nothing for "other").

    The refusal's reason, or None.
    """
    return _set_policy(0, settings, priority) if settings.realtime else None


def make_thread_background(settings: RealtimeSettings) -> None:
    """The calling thread as a real-time process's background thread (a model build).

    At the lowest real-time priority, below every periodic thread, with SCHED_RESET_ON_FORK so that what it starts (a C
    compiler) runs as an ordinary process. Why not the ordinary policy: a thread that busy ordinary processes preempt
    while it holds the interpreter lock would hold up the periodic threads that wait for it. The ordinary policy where
    settings are not real-time or the host refuses.
    """
    if settings.realtime:
        try:
            os.sched_setscheduler(0, SCHEDULING_POLICIES[settings.policy] | os.SCHED_RESET_ON_FORK,
                                  os.sched_param(BACKGROUND_PRIORITY))
            return
        except OSError:
            pass
    make_thread_ordinary()


def make_thread_ordinary() -> None:
    """The calling thread back to the ordinary policy.

    For a compilation thread in a real-time process: what it starts, a C compiler, inherits the policy.
    """
    try:
        os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
    except OSError:
        pass   # lowering one's own policy is always permitted; a failure leaves what was


def thread_policy() -> tuple[str, int]:
    """The calling thread's policy name and priority (for diagnostics and tests)."""
    policy = os.sched_getscheduler(0)
    name = next((key for key, value in SCHEDULING_POLICIES.items() if value == policy), str(policy))
    return name, os.sched_getparam(0).sched_priority


def memory_locked_kib() -> int:
    """The process's locked memory, KiB (/proc/self/status VmLck; 0 where it cannot be read)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmLck:"):
                return int(line.split()[1])
    except (OSError, ValueError, IndexError):
        pass
    return 0


class PeriodicCollector:
    """The garbage collector out of the periodic path.

    Freeze what exists, no automatic collection, and a full collection of what the periods left every interval_periods
    periods, where the loop calls after_period().

    Each collection walks only the objects made since the last one, and freezes what survives it: a long-lived
    object is walked once, not once a second (a wake's first steps import numba's tens of thousands of objects,
    whose walk would take some 40 ms at every collection). What this gives up: a reference cycle that becomes
    garbage after surviving a collection is not freed (objects freed by their reference count are). The longest
    collection is kept (longest_s) for the node's diagnostics. stop() gives the collector back to automatic
    collection.
    """

    def __init__(self, interval_periods: int) -> None:
        if interval_periods < 1:
            raise ValueError("interval_periods must be at least 1")
        self.interval_periods = interval_periods
        self._count = 0
        self.collections = 0
        self.longest_s = 0.0
        gc.collect()
        gc.freeze()
        gc.disable()

    def after_period(self) -> None:
        """Count a period; every interval_periods periods, collect what the last ones left and freeze the survivors."""
        self._count += 1
        if self._count < self.interval_periods:
            return
        self._count = 0
        start_s = time.monotonic()
        gc.collect()
        gc.freeze()
        self.collections += 1
        self.longest_s = max(self.longest_s, time.monotonic() - start_s)

    def stop(self) -> None:
        """Give the collector back to automatic collection."""
        gc.enable()
