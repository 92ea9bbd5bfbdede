"""Statistics over seeds (swim_bringup.statistics) against independent computations: the standard library's mean
and sample standard deviation, Student's t quantile in closed form (1 and 2 degrees of freedom), and scipy's
one-sample t test's confidence interval of the paired changes."""
import math
import statistics as stdlib

import pytest
from scipy import stats

from swim_bringup.statistics import NormStatistics, PairedChange, Spread, largest_magnitude, relative_change, t_quantile

SEED_VALUES = [0.031, 0.027, 0.035, 0.029, 0.033]


def test_the_largest_magnitude_keeps_its_sign():
    assert largest_magnitude([0.1, -0.3, 0.2]) == -0.3
    assert largest_magnitude([0.1, 0.3, -0.2]) == 0.3
    assert largest_magnitude([-0.2, 0.2]) == -0.2        # equal magnitudes: the first
    assert largest_magnitude([0.004]) == 0.004
    with pytest.raises(ValueError, match="no values"):
        largest_magnitude([])


def test_mean_and_sample_standard_deviation_are_the_standard_librarys():
    spread = Spread.of(SEED_VALUES)
    assert spread.mean == pytest.approx(stdlib.mean(SEED_VALUES), rel=1e-12)
    assert spread.std == pytest.approx(stdlib.stdev(SEED_VALUES), rel=1e-12)   # n - 1 in the denominator
    assert Spread.of([0.2]) == Spread(0.2, None)     # one seed: no spread
    with pytest.raises(ValueError):
        Spread.of([])


@pytest.mark.parametrize("probability", [0.9, 0.975, 0.995])
def test_t_quantiles_match_their_closed_forms(probability):
    """nu = 1 (Cauchy): tan(pi (p - 1/2)); nu = 2: (2p - 1) / sqrt(2 p (1 - p))."""
    assert t_quantile(probability, 1) == pytest.approx(math.tan(math.pi * (probability - 0.5)), rel=1e-10)
    assert t_quantile(probability, 2) == pytest.approx((2 * probability - 1)
                                                       / math.sqrt(2 * probability * (1 - probability)), rel=1e-10)


def test_the_paired_interval_of_three_seeds_in_closed_form():
    """n = 3: mean -/+ t_{0.975, 2} s / sqrt(3), t_{0.975, 2} = 0.95 / sqrt(2 0.975 0.025)."""
    changes = [-0.10, -0.14, -0.12]
    change = PairedChange.of(changes)
    half_width = 0.95 / math.sqrt(2 * 0.975 * 0.025) * stdlib.stdev(changes) / math.sqrt(3)
    assert change.mean == pytest.approx(-0.12)
    assert change.interval == pytest.approx((-0.12 - half_width, -0.12 + half_width))
    assert change.excludes_zero and change.interval[1] < 0.0
    assert change.per_seed == changes


@pytest.mark.parametrize("changes", [[-0.05, 0.02, -0.04, 0.01, -0.03], [0.08, 0.11, 0.05, 0.09, 0.12],
                                     [-0.3, 0.25]])
def test_the_paired_interval_is_scipys_one_sample_t_interval(changes):
    expected = stats.ttest_1samp(changes, 0.0).confidence_interval(0.95)
    change = PairedChange.of(changes)
    assert change.interval == pytest.approx((expected.low, expected.high), rel=1e-10)
    assert change.excludes_zero == (expected.low > 0.0 or expected.high < 0.0)


def test_one_seed_has_no_interval_and_excludes_nothing():
    change = PairedChange.of([-0.2])
    assert (change.mean, change.interval, change.excludes_zero) == (-0.2, None, False)


def test_a_norms_statistics_pair_the_seeds():
    on, off = [0.9, 1.8, 2.85], [1.0, 2.0, 3.0]            # -10 %, -10 %, -5 %
    norm = NormStatistics.of(on, off, -0.14)
    assert norm.change is not None
    assert norm.change.per_seed == pytest.approx([-0.1, -0.1, -0.05])
    assert norm.change.mean == pytest.approx(stdlib.mean([-0.1, -0.1, -0.05]))
    assert norm.sliding_on == Spread.of(on) and norm.sliding_off == Spread.of(off)
    assert norm.paper_change == -0.14
    # the constrained vehicle's lateral two-norm is zero without sliding mode: no relative change
    assert NormStatistics.of([0.0, 0.0], [0.0, 0.0], None).change is None
    assert relative_change(1.0, 0.0) is None and relative_change(0.9, 1.0) == pytest.approx(-0.1)
    with pytest.raises(ValueError, match="not pairs"):
        NormStatistics.of([1.0, 2.0], [1.0], None)
