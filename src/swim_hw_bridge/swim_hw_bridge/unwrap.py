"""Encoder counters: unwrapping modulo 2**bits and flagging physically impossible jumps.

A hardware counter holds c_k = n_k mod M, M = 2**counter_bits. Between two reads the true count changes by
less than M/2 (at 8 ms and the rig's speeds by a few hundred counts against M/2 = 2**31), so the step is
    d_k = ((c_k - c_(k-1) + M/2) mod M) - M/2      in [-M/2, M/2)
and n_k = n_(k-1) + d_k, exact in Python's unbounded integers in both directions across the wrap.

A step larger than the joint can move, |d_k| > v_max * (t_k - t_(k-1)) * counts_per_unit + slack, is a
jump: a missed read, electrical noise or a counter reset. It is flagged (the safety layer faults on it);
the step is still accumulated, since no better estimate exists.
"""
from __future__ import annotations

from collections.abc import Sequence

#: counts always allowed per step on top of the speed bound: quantization and edge jitter at standstill
JUMP_SLACK_COUNTS = 2


class CounterUnwrapper:
    """Unwrapped counts since the first sample, for any number of channels."""

    def __init__(self, counter_bits: int, max_counts_per_s: Sequence[float]) -> None:
        if counter_bits < 2:
            raise ValueError(f"counter_bits must be at least 2, got {counter_bits}")
        self.modulus = 1 << counter_bits
        self._half = self.modulus >> 1
        self.max_counts_per_s = tuple(float(v) for v in max_counts_per_s)
        self._raw: list[int] | None = None
        self._time_s = 0.0
        self.unwrapped: list[int] = [0] * len(self.max_counts_per_s)

    def reset(self) -> None:
        """Forget the history: the next sample counts as zero."""
        self._raw = None
        self.unwrapped = [0] * len(self.max_counts_per_s)

    def update(self, raw_counts: Sequence[int], time_s: float) -> int:
        """Take a sample; returns a bit mask of the channels whose step was a jump (0: none).

        self.unwrapped holds the counts since the first sample afterwards.
        """
        if self._raw is None:
            self._raw = [int(c) % self.modulus for c in raw_counts]
            self._time_s = time_s
            return 0
        elapsed_s = max(time_s - self._time_s, 0.0)
        jumps = 0
        for channel, raw in enumerate(raw_counts):
            raw = int(raw) % self.modulus
            step = (raw - self._raw[channel] + self._half) % self.modulus - self._half
            if abs(step) > self.max_counts_per_s[channel] * elapsed_s + JUMP_SLACK_COUNTS:
                jumps |= 1 << channel
            self.unwrapped[channel] += step
            self._raw[channel] = raw
        self._time_s = time_s
        return jumps
