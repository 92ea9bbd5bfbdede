"""The paper's two-norm ||e||_2 = sqrt(int e^2 dt) (measures.two_norm) against closed forms."""
import math

import numpy as np
import pytest

from swim_control.measures import two_norm


def sine_two_norm(duration_s: float) -> float:
    """sqrt(int_0^T sin(t)^2 dt) = sqrt(T/2 - sin(2T)/4)."""
    return math.sqrt(duration_s / 2.0 - math.sin(2.0 * duration_s) / 4.0)


def test_a_sine_against_its_closed_form():
    """The trapezoidal rule's error in int f is at most T h^2 max|f''| / 12; f = sin^2 has |f''| <= 2."""
    duration_s, samples = 5.0, 2001
    time_s = np.linspace(0.0, duration_s, samples)
    step_s = duration_s / (samples - 1)
    integral_error_bound = duration_s * step_s ** 2 * 2.0 / 12.0
    exact = sine_two_norm(duration_s)
    assert two_norm(time_s, np.sin(time_s)) ** 2 == pytest.approx(exact ** 2, abs=integral_error_bound)


def test_the_error_falls_with_the_square_of_the_step():
    """Second order: halving the step quarters the error of int e^2 (a rectangle sum would only halve it)."""
    duration_s = 5.0
    errors = []
    for samples in (101, 201, 401):
        time_s = np.linspace(0.0, duration_s, samples)
        errors.append(abs(two_norm(time_s, np.sin(time_s)) ** 2 - sine_two_norm(duration_s) ** 2))
    for coarse, fine in zip(errors, errors[1:]):
        assert coarse / fine == pytest.approx(4.0, rel=0.01)


def test_a_constant_and_uneven_steps():
    """A constant e over T: e sqrt(T), exactly, however the samples are spaced; a ramp e = t on uneven samples:
    the trapezoidal rule overestimates the integral of the convex t^2 (int_0^4 t^2 dt = 64/3), and stays below
    the bound 4^2 * 4 of its largest value."""
    time_s = np.array([0.0, 0.1, 0.5, 2.0, 4.0])
    assert two_norm(time_s, np.full(5, 0.2)) == pytest.approx(0.2 * 2.0, rel=1e-15)
    assert math.sqrt(4.0 ** 3 / 3.0) < two_norm(time_s, time_s) < 4.0 * 2.0


def test_no_interval_and_bad_shapes():
    assert two_norm(np.array([1.0]), np.array([3.0])) == 0.0
    with pytest.raises(ValueError, match="one shape"):
        two_norm(np.linspace(0.0, 1.0, 3), np.zeros(4))
    with pytest.raises(ValueError, match="one shape"):
        two_norm(np.linspace(0.0, 1.0, 3), np.zeros((3, 2)))

