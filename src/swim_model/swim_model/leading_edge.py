"""The leading edge's suction cap, shared by the reduced flow model and the vortex wake.

swim_model.flow and swim_model.wake: one edge, one criterion, one formula. A rounded leading edge holds suction
only up to a critical leading-edge suction parameter (LESP); beyond it the flow separates there (Ramesh,
Gopalarathnam, Granlund, Ol & Edwards, J. Fluid Mech. 751, 2014). Both models cap the suction smoothly,
x / (1 + (x / limit)^n)^(1/n), so that the optimizer has derivatives everywhere: flow caps the suction velocity at
CRITICAL_LEADING_EDGE_SUCTION |u|, the wake its LESP at CRITICAL_LEADING_EDGE_SUCTION.

Pure arithmetic: smooth_cap works on floats and on CasADi expressions alike, and this module sits below both models
(flow imports the towed foil, which imports the wake).
"""
from __future__ import annotations

from typing import Any

#: Ramesh et al. (2014): LESP_crit of a rounded-nose section at chord Reynolds numbers of order 1e4 (0.18 for their
#: SD7003; 0.11 for a flat plate with a sharp nose)
CRITICAL_LEADING_EDGE_SUCTION = 0.18
#: assumed: the order of the smooth saturation; 8 keeps the suction within 0.05 % of uncapped below half the
#: critical value and reaches the cap within 9 % of it (an even integer keeps it smooth through zero)
SUCTION_CAP_EXPONENT = 8
#: assumed: eps in the speed sqrt(U^2 + V^2 + eps^2); makes every term smooth at rest and changes forces by
#: (eps/|u|)^2 (1e-12 at 0.1 m/s); the forces' second derivatives stay bounded as eps -> 0 (they are homogeneous of
#: degree 2)
SPEED_REGULARIZATION_M_S = 1.0e-7


def is_cap_exponent(exponent: object) -> bool:
    """Whether exponent can be smooth_cap's: an even integer >= 2.

    An odd one leaves 1 + (value / limit)^n negative for value below -limit.

    Parameters
    ----------
    exponent : object
        The candidate.

    Returns
    -------
    bool
        True for an even int >= 2 (not a bool).
    """
    return isinstance(exponent, int) and not isinstance(exponent, bool) and exponent >= 2 and exponent % 2 == 0


def smooth_cap(value: Any, limit: Any, exponent: int) -> Any:
    """Value / (1 + (value / limit)^exponent)^(1/exponent).

    value where |value| << limit, limit in size where |value| >> limit, smooth through zero for an even exponent.

    Parameters
    ----------
    value : float or casadi expression
        The quantity to cap, in the unit of ``limit``.
    limit : float or casadi expression
        The cap, > 0.
    exponent : int
        The saturation's order, even (``is_cap_exponent``).

    Returns
    -------
    float or casadi expression
        The capped value, in value's unit.
    """
    return value / (1.0 + (value / limit) ** exponent) ** (1.0 / exponent)
