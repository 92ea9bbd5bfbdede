"""Statistics over seeds of swim-experiments' runs (no ROS).

The value of largest magnitude, the mean and standard deviation of a measure, and sliding mode's relative change of a
two-norm with a paired 95 % interval.

Each seed seeds the simulator's disturbances and sensor noise; the runs with and without sliding mode of one seed
meet the same disturbance sequence, so they are a pair. Sliding mode's relative change of seed k is
c_k = (on_k - off_k) / off_k. Its interval is Student's t interval of the mean of the n paired changes:

    mean(c) -/+ t_{0.975, n-1} s(c) / sqrt(n),     s: the sample standard deviation (n - 1 in the denominator),

which assumes the c_k independent and normal about their mean. With one seed there is no spread, so no interval.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Optional, Sequence

#: the paired interval's coverage: the conventional 95 %, at which the results say whether a change excludes zero
CONFIDENCE = 0.95


def largest_magnitude(values: Sequence[float]) -> float:
    """The value of largest absolute value, its sign kept (the first of equal magnitudes). ValueError if empty."""
    if not values:
        raise ValueError("no values to choose the largest magnitude from")
    return max(values, key=abs)


def relative_change(with_sliding: float, without_sliding: float) -> Optional[float]:
    """(with - without) / without: negative where sliding mode lowers the error; None where without is 0."""
    return None if without_sliding == 0.0 else (with_sliding - without_sliding) / without_sliding


@dataclasses.dataclass(frozen=True)
class Spread:
    """A measure over seeds: its mean and sample standard deviation (n - 1 in the denominator; None for n = 1)."""

    mean: float
    std: Optional[float]

    @classmethod
    def of(cls, values: Sequence[float]) -> Spread:
        """ValueError if values is empty."""
        if not values:
            raise ValueError("no values to average")
        mean = math.fsum(values) / len(values)
        if len(values) < 2:
            return cls(mean, None)
        return cls(mean, math.sqrt(math.fsum((v - mean) ** 2 for v in values) / (len(values) - 1)))


def t_quantile(probability: float, degrees_of_freedom: int) -> float:
    """Student's t distribution's quantile (scipy.stats.t.ppf)."""
    from scipy.stats import t
    return float(t.ppf(probability, degrees_of_freedom))


@dataclasses.dataclass(frozen=True)
class PairedChange:
    """Sliding mode's relative change of a two-norm over seeds, with its paired interval.

    Sliding mode's relative change of a two-norm over seeds: the change per seed, their mean, and the paired
    t interval of the mean at CONFIDENCE (None with one seed), and whether it excludes zero (False without one).
    """

    per_seed: list[float]
    mean: float
    interval: Optional[tuple[float, float]]
    excludes_zero: bool

    @classmethod
    def of(cls, changes: Sequence[float], confidence: float = CONFIDENCE) -> PairedChange:
        """changes: c_k = (on_k - off_k) / off_k of each seed. ValueError if empty."""
        spread = Spread.of(changes)
        if spread.std is None:
            return cls(list(changes), spread.mean, None, False)
        half_width = t_quantile(0.5 + confidence / 2, len(changes) - 1) * spread.std / math.sqrt(len(changes))
        low, high = spread.mean - half_width, spread.mean + half_width
        return cls(list(changes), spread.mean, (low, high), low > 0.0 or high < 0.0)


@dataclasses.dataclass(frozen=True)
class NormStatistics:
    """A two-norm over seeds with and without sliding mode, and the changes.

    A two-norm over seeds, m s^0.5, with (on) and without (off) sliding mode; sliding mode's change (None where
    a run without it has a zero two-norm: the constrained vehicle's lateral error) and the paper's change (None:
    not reported there).
    """

    sliding_on: Spread
    sliding_off: Spread
    change: Optional[PairedChange]
    paper_change: Optional[float]

    @classmethod
    def of(cls, sliding_on: Sequence[float], sliding_off: Sequence[float],
           paper_change: Optional[float]) -> NormStatistics:
        """sliding_on[k], sliding_off[k]: the two-norms of seed k. ValueError if their lengths differ or are 0."""
        if len(sliding_on) != len(sliding_off):
            raise ValueError(f"{len(sliding_on)} runs with sliding mode but {len(sliding_off)} without: not pairs")
        changes = [relative_change(on, off) for on, off in zip(sliding_on, sliding_off)]
        defined = [c for c in changes if c is not None]
        change = PairedChange.of(defined) if len(defined) == len(changes) else None
        return cls(Spread.of(sliding_on), Spread.of(sliding_off), change, paper_change)
