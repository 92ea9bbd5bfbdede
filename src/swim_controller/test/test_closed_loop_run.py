"""The closed loop's Run measures by the paper's two-norm (swim_control.measures.two_norm)."""
import math

import numpy as np
import pytest

from swim_control.measures import two_norm
from swim_controller.testing.closed_loop import Run


def test_the_closed_loops_run_measures_by_the_same_rule():
    """Run.two_norm of a coordinate over the run and over its start (t < until_s) against the closed form
    sqrt(int_0^T sin(t)^2 dt) = sqrt(T/2 - sin(2T)/4)."""
    def sine_two_norm(duration_s: float) -> float:
        return math.sqrt(duration_s / 2.0 - math.sin(2.0 * duration_s) / 4.0)

    time_s = np.arange(0, 2001) * 0.0025
    q_reference = np.zeros((len(time_s), 3))
    q = q_reference.copy()
    q[:, 1] = np.sin(time_s)
    run = Run(time_s, q, q_reference, np.zeros((len(time_s), 2)), np.zeros((len(time_s), 2), bool))
    assert run.two_norm(1) == two_norm(time_s, np.sin(time_s))
    assert run.two_norm(1) == pytest.approx(sine_two_norm(5.0), rel=1e-5)
    assert run.two_norm(0) == 0.0
    # samples at t < 2 s: the last one at 2 - 0.0025 s
    assert run.two_norm(1, 2.0) == pytest.approx(sine_two_norm(2.0 - 0.0025), rel=1e-5)
