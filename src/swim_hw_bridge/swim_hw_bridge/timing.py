"""How the I/O loop's periods went: why a period overran, and histograms of the times a run is judged by.

An overrun's cause is the largest of the parts of its period, each measured on the loop's clock:
    LATE_WAKEUP   the period started late: the thread was woken late (a busy host, no real-time policy) or waited
                  for the interpreter lock held by another thread;
    SLOW_READ     the device's read took longest (the emulated rig integrates its vehicle in the read);
    SLOW_WRITE    the device's write (currents, enable line) took longest;
    SLOW_WORK     the rest of the period did: unwrapping, velocities, the safety rules, the snapshot.
A user who sees OVERRUN latched can tell a busy host (LATE_WAKEUP) from a slow device (SLOW_READ, SLOW_WRITE).

LatencyHistogram counts durations in fixed bins from the start of a run (no allocation per sample, so the loop's
thread can add to it every period); its percentiles are exact to one bin.
"""
from __future__ import annotations

import enum

import numpy as np


class OverrunCause(enum.IntEnum):
    """What made a period late (overrun_cause)."""

    NONE = 0
    LATE_WAKEUP = 1
    SLOW_READ = 2
    SLOW_WRITE = 3
    SLOW_WORK = 4


def overrun_cause(wake_lateness_s: float, read_s: float, write_s: float, work_s: float) -> OverrunCause:
    """The largest part of a late period: its wake-up lateness, its read, its write, or the rest of its work.

    work_s is the whole period's work, read and write included.
    """
    rest_s = work_s - read_s - write_s
    parts = ((wake_lateness_s, OverrunCause.LATE_WAKEUP), (read_s, OverrunCause.SLOW_READ),
             (write_s, OverrunCause.SLOW_WRITE), (rest_s, OverrunCause.SLOW_WORK))
    return max(parts, key=lambda part: part[0])[1]


#: the histograms' bin, s: well below the 1 ms the loop's jitter is judged against
HISTOGRAM_BIN_S = 25e-6
#: the histograms' range, s: ten 8 ms periods; longer durations count in the last bin
HISTOGRAM_RANGE_S = 0.08


class LatencyHistogram:
    """Durations (s) counted in bins of bin_s up to range_s (beyond: the last bin); percentiles to one bin."""

    def __init__(self, bin_s: float = HISTOGRAM_BIN_S, range_s: float = HISTOGRAM_RANGE_S) -> None:
        self.bin_s = bin_s
        self.counts = np.zeros(int(round(range_s / bin_s)) + 1, dtype=np.int64)
        self._last_bin = len(self.counts) - 1
        self.largest_s = 0.0

    def add(self, duration_s: float) -> None:
        """Count a duration, s; a negative or NaN one is ignored."""
        if not duration_s >= 0.0:   # negative or nan: not a duration
            return
        index = int(duration_s / self.bin_s)
        self.counts[index if index < self._last_bin else self._last_bin] += 1
        if duration_s > self.largest_s:
            self.largest_s = duration_s

    @property
    def count(self) -> int:
        """How many durations were counted."""
        return int(self.counts.sum())

    def percentile_s(self, percent: float) -> float:
        """The upper edge of the bin holding the percent-th percentile, at most the largest duration.

        NaN while empty.
        """
        counts = self.counts.copy()   # the loop's thread may add meanwhile
        total = int(counts.sum())
        if total == 0:
            return float("nan")
        index = int(np.searchsorted(np.cumsum(counts), percent / 100.0 * total))
        return self.largest_s if index >= self._last_bin else min((index + 1) * self.bin_s, self.largest_s)
