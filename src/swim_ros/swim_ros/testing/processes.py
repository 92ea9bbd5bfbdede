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


def processes_left(variable: str, tag: str, timeout_s: float) -> list[int]:
    """The processes tagged variable=tag still alive timeout_s from now, each then killed (SIGKILL).

    An empty list as soon as none is alive. Killing the rest makes sure a failed test leaves nothing behind.
    """
    deadline = time.monotonic() + timeout_s
    while tagged_processes(variable, tag) and time.monotonic() < deadline:
        time.sleep(POLL_PERIOD_S)
    left = sorted(tagged_processes(variable, tag))
    for pid in left:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    return left
