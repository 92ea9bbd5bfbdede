"""The leading edge's smooth suction cap (swim_model.leading_edge), the one formula of the reduced flow model and the
vortex wake."""
import math

import casadi as ca
import pytest

from swim_model.errors import FlowModelError, StateError
from swim_model.flow import FlowParameters
from swim_model.leading_edge import (
    CRITICAL_LEADING_EDGE_SUCTION,
    SPEED_REGULARIZATION_M_S,
    SUCTION_CAP_EXPONENT,
    is_cap_exponent,
    smooth_cap,
)
from swim_model.wake import WakeParameters

LIMIT = CRITICAL_LEADING_EDGE_SUCTION
N = SUCTION_CAP_EXPONENT


def test_below_half_the_limit_the_value_passes_within_its_documented_share():
    """Below half the limit the cap takes at most (1/2)^n / n of the value, to first order: 0.05 % for n = 8."""
    for fraction in (0.01, 0.1, 0.3, 0.5):
        value = fraction * LIMIT
        assert 1.0 - smooth_cap(value, LIMIT, N) / value == pytest.approx(fraction ** N / N, rel=0.01)
    assert 1.0 - smooth_cap(0.5 * LIMIT, LIMIT, N) / (0.5 * LIMIT) < 5e-4


def test_far_above_the_limit_the_value_is_held_at_it():
    """(1 + x^n)^(1/n) -> x for x >> 1: the result tends to the limit; at the limit it is 2^(-1/n) of it (9 % below
    for n = 8)."""
    assert smooth_cap(1e3 * LIMIT, LIMIT, N) == pytest.approx(LIMIT, rel=1e-12)
    assert smooth_cap(LIMIT, LIMIT, N) == pytest.approx(LIMIT * 2.0 ** (-1.0 / N), rel=1e-15)
    assert 1.0 - 2.0 ** (-1.0 / N) < 0.09


def test_it_is_odd_and_monotonic():
    values = [LIMIT * k / 10.0 for k in range(-40, 41)]
    capped = [smooth_cap(v, LIMIT, N) for v in values]
    assert all(smooth_cap(-v, LIMIT, N) == -c for v, c in zip(values, capped))
    assert all(b > a for a, b in zip(capped, capped[1:]))


def test_a_casadi_expression_gives_the_floats_numbers_to_the_bit():
    x, limit = ca.SX.sym("x"), ca.SX.sym("limit")
    function = ca.Function("cap", [x, limit], [smooth_cap(x, limit, N)])
    for value in (-0.4, 0.0, 0.05, 0.18, 2.0):
        assert float(function(value, LIMIT)) == smooth_cap(value, LIMIT, N)
    assert math.isfinite(float(ca.Function("d", [x], [ca.jacobian(smooth_cap(x, LIMIT, N), x)])(0.0)))


def test_both_models_default_to_the_shared_edge():
    flow, wake = FlowParameters(), WakeParameters()
    assert flow.critical_leading_edge_suction == wake.critical_leading_edge_suction == CRITICAL_LEADING_EDGE_SUCTION
    assert flow.suction_cap_exponent == wake.suction_cap_exponent == SUCTION_CAP_EXPONENT
    assert flow.speed_regularization_m_s == wake.speed_regularization_m_s == SPEED_REGULARIZATION_M_S


@pytest.mark.parametrize("exponent", [2, 4, 8, 16])
def test_even_integers_from_two_are_cap_exponents(exponent):
    assert is_cap_exponent(exponent)
    assert FlowParameters(suction_cap_exponent=exponent).suction_cap_exponent == exponent
    assert WakeParameters(suction_cap_exponent=exponent).suction_cap_exponent == exponent


@pytest.mark.parametrize("exponent", [0, -2, 1, 3, 4.0, True, "8", None])
def test_both_models_refuse_what_is_not_a_cap_exponent(exponent):
    """An odd exponent leaves the cap undefined for suction below -limit; a float, a bool or a string is not the
    integer the field is."""
    assert not is_cap_exponent(exponent)
    with pytest.raises(FlowModelError, match="suction_cap_exponent"):
        FlowParameters(suction_cap_exponent=exponent)
    with pytest.raises(StateError, match="suction_cap_exponent"):
        WakeParameters(suction_cap_exponent=exponent)
