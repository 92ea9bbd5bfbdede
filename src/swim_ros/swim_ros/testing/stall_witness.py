"""A stall witness: whether the host itself held every process up while a test's run went on.

One process per CPU, pinned to it at SCHED_FIFO WITNESS_PRIORITY (above every thread of the nodes) with its memory
locked, wakes on an absolute grid every PERIOD_S and writes each wake-up later than REPORT_LATENESS_S to its file. A
process that does nothing else can be woken that late only by the kernel or the hypervisor: no process of the run
can delay it. So a run lost while the witness saw no stall was lost to the run's own processes, and one lost while
it saw the host stall for longer than the run's limits is the host's (docs/realtime.md, "A publish held for 333 ms").

    with StallWitness(tmp_path) as witness:
        ...   # the run
    witness.worst_s, witness.stalls
"""
from __future__ import annotations

import dataclasses
import gc
import os
import sys
import time
from pathlib import Path
from types import TracebackType
from typing import Optional

from swim_ros.processes import start_child
from swim_ros.realtime import RealtimeSettings, make_process_realtime

#: above the bridge's I/O loop (80) and every other thread of the nodes (70)
WITNESS_PRIORITY = 90
#: the grid's period, s: a thousandth of a second, as cyclictest's default
PERIOD_S = 1e-3
#: a wake-up later than this is written down, s: the probe's own jitter in Python stays well under it
REPORT_LATENESS_S = 0.02
#: how long the witnesses have to start and say whether the host gave them their means, s
START_TIMEOUT_S = 30.0
#: the first line of a witness's file once its means are in effect ("refused: ..." otherwise)
READY = "ready"


@dataclasses.dataclass(frozen=True)
class Stall:
    """One late wake-up: the CPU, when it came (wall clock, s) and how late, s."""

    cpu: int
    wall_time_s: float
    lateness_s: float


class StallWitness:
    """The witness processes, one per CPU this process may run on, started on entering and killed on leaving.

    Parameters
    ----------
    directory : Path
        Where each witness writes its file (``stall_witness_cpu<N>.txt``).

    Attributes
    ----------
    refused : str or None
        Why the host refused a witness its real-time means (it then witnesses nothing): None when all have them.
    """

    def __init__(self, directory: Path) -> None:
        self.paths = {cpu: directory / f"stall_witness_cpu{cpu}.txt" for cpu in sorted(os.sched_getaffinity(0))}
        self.refused: Optional[str] = None
        self._processes: list = []

    def __enter__(self) -> "StallWitness":
        """Start the witnesses and wait until each has its means (or was refused them)."""
        for cpu, path in self.paths.items():
            path.unlink(missing_ok=True)
            self._processes.append(start_child([sys.executable, "-m", "swim_ros.testing.stall_witness", str(cpu),
                                                str(path)]))
        deadline = time.monotonic() + START_TIMEOUT_S
        try:
            for path in self.paths.values():
                while not (path.exists() and path.read_text().endswith("\n")):
                    if time.monotonic() > deadline:
                        raise RuntimeError(f"the stall witness {path.name} did not start within {START_TIMEOUT_S} s")
                    time.sleep(0.05)
                first = path.read_text().splitlines()[0]
                if first != READY:
                    self.refused = first
        except BaseException:
            self._stop()
            raise
        return self

    def __exit__(self, exc_type: Optional[type], exc: Optional[BaseException],
                 traceback: Optional[TracebackType]) -> None:
        """Kill the witnesses."""
        self._stop()

    @property
    def pids(self) -> list[int]:
        """The witness processes' pids, in the order of their CPUs."""
        return [process.pid for process in self._processes]

    def _stop(self) -> None:
        for process in self._processes:
            process.kill()
            process.wait()
        self._processes = []

    @property
    def stalls(self) -> list[Stall]:
        """Every wake-up later than REPORT_LATENESS_S, in the order written, CPU by CPU."""
        found = []
        for cpu, path in self.paths.items():
            if not path.exists():
                continue
            for line in path.read_text().splitlines()[1:]:
                wall_time_s, lateness_s = line.split()
                found.append(Stall(cpu, float(wall_time_s), float(lateness_s)))
        return found

    @property
    def worst_s(self) -> float:
        """The latest wake-up written down, s (0 when none was later than REPORT_LATENESS_S)."""
        return max((stall.lateness_s for stall in self.stalls), default=0.0)


def witness(cpu: int, path: Path) -> None:
    """Run one witness on cpu until killed, writing to path: READY (or the refusal), then one line per stall."""
    os.sched_setaffinity(0, {cpu})
    outcome = make_process_realtime(RealtimeSettings(priority=WITNESS_PRIORITY, collect_garbage_between_periods=False))
    gc.disable()   # the loop allocates a float or two a period: nothing for a collection to find
    with path.open("w", buffering=1) as out:
        out.write(f"refused: {'; '.join(outcome.refused)}\n" if outcome.refused else f"{READY}\n")
        deadline_s = time.monotonic()
        while True:
            deadline_s += PERIOD_S
            remaining_s = deadline_s - time.monotonic()
            if remaining_s > 0.0:
                time.sleep(remaining_s)
            lateness_s = time.monotonic() - deadline_s
            if lateness_s > REPORT_LATENESS_S:
                out.write(f"{time.time():.3f} {lateness_s:.4f}\n")
            if lateness_s > PERIOD_S:
                deadline_s = time.monotonic()   # the grid from here: one stall is written once


if __name__ == "__main__":
    witness(int(sys.argv[1]), Path(sys.argv[2]))
