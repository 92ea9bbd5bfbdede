"""The velocity estimator (filtered differences of positions) against its closed form."""
import math

import numpy as np
import pytest

from swim_model.velocity_filter import VelocityEstimator


def test_velocity_estimate_of_a_ramp_follows_its_closed_form():
    """For q = v t the estimate is v (1 - a^k) after k differences, a = exp(-2 pi fc h)."""
    estimator = VelocityEstimator(cutoff_hz=10.0)
    h, v = 0.008, np.array([0.3, -2.0, 1.0])
    a = math.exp(-2 * math.pi * 10.0 * h)
    for k in range(40):
        rate = estimator.update(k * h, v * k * h)
    np.testing.assert_allclose(rate, v * (1 - a ** 39), rtol=1e-12)


def test_a_bad_cutoff_is_refused():
    with pytest.raises(ValueError, match="cutoff"):
        VelocityEstimator(cutoff_hz=float("nan"))
