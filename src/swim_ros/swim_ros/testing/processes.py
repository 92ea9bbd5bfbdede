"""Finding the processes a test started, whatever became of their parents.

The test starts its starter with an environment variable of its own (``{variable: uuid}``), which every process below it
inherits, and looks for that entry in /proc/<pid>/environ.
"""
from __future__ import annotations

import os
import signal
import time
from pathlib import Path

#: how often a wait for tagged processes to end looks again, s
POLL_PERIOD_S = 0.05


def tagged_processes(variable: str, tag: str) -> dict[int, str]:
    """The live processes whose environment holds variable=tag, by pid, with their command lines.

    A zombie's environment is empty: it is not found.
    """
    marker = f"{variable}={tag}".encode()
    found = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            if marker in (entry / "environ").read_bytes().split(b"\0"):
                command_line = (entry / "cmdline").read_bytes().rstrip(b"\0").split(b"\0")
                found[int(entry.name)] = " ".join(part.decode(errors="replace") for part in command_line)
        except OSError:   # gone meanwhile, or not ours to read
            continue
    return found


def processes_left(variable: str, tag: str, timeout_s: float) -> list[str]:
    """The processes tagged variable=tag still alive timeout_s from now, each then killed (SIGKILL).

    An empty list as soon as two looks a poll apart find none alive; otherwise each as "pid (state): command line",
    the state as /proc/<pid>/stat gives it (S sleeping, R running, T stopped, Z ended, ...), for a failed test's
    message. Killing them makes sure a failed test leaves nothing behind. Two looks, because one can miss a live
    process: its environment is unreadable for a moment while it executes a new program or exits.
    """
    deadline = time.monotonic() + timeout_s
    looks_without = 0
    while True:
        left = tagged_processes(variable, tag)
        looks_without = 0 if left else looks_without + 1
        if looks_without >= 2 or time.monotonic() >= deadline:
            break
        time.sleep(POLL_PERIOD_S)
    described = [f"{pid} ({_process_state(pid)}): {command_line}" for pid, command_line in sorted(left.items())]
    for pid in left:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    return described


def _process_state(pid: int) -> str:
    """The process's state letter from /proc/<pid>/stat, "gone" if it ended meanwhile."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()[0]
    except (OSError, IndexError):
        return "gone"
