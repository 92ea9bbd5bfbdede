"""Trailing-edge separation from a static polar, for the reduced flow model (swim_model.flow).

Leishman & Beddoes's dynamic-stall model (J. Am. Helicopter Soc. 34, 1989): the boundary layer separates from the
trailing edge forward to a point f (1 attached, 0 separated to the leading edge), which the section's static polar
gives as a function of incidence through Kirchhoff's flow, C_N = C_N,attached ((1 + sqrt f) / 2)^2. In motion f
is read at the incidence lagged by T_p (the pressure's lag) and lags itself by T_f (the boundary layer's), both in
semichords travelled. swim_model.flow scales its normal force and suction by it (docs/flow_model.md, Sec. 6,
"Trailing-edge separation from the static polar"); the vortex wake, given f, holds its bound circulation at the
same share (swim_model.wake).

Pure arithmetic: kirchhoff_share, static_separation_point and logistic_separation_point work on floats and CasADi
expressions alike (the last two on numpy arrays too).
"""
from __future__ import annotations

import dataclasses
import math
from typing import Any

import casadi as ca
import numpy as np

from swim_model.errors import FlowModelError

#: the NACA 0012's pressure and boundary-layer lags, semichords (Leishman & Beddoes 1989, Table 1: T_p 1.7,
#: T_f 3.0); the tank's foil stays attached longer (docs/flow_model.md, Sec. 6)
PUBLISHED_PRESSURE_LAG_SEMICHORDS = 1.7
PUBLISHED_POINT_LAG_SEMICHORDS = 3.0
#: set on the 90 deg tank series (docs/flow_model.md, Sec. 6): both published lags doubled, the one number set
#: there; with the published ones the separation removes 15-28 % of the thrust the tank measured
TANK_LAG_FACTOR = 2.0
#: the largest exponent logistic_separation_point evaluates in numpy (f underflows to 0 beyond it)
_MAX_EXPONENT = 700.0


@dataclasses.dataclass(frozen=True)
class TrailingEdgeSeparation:
    """The separation of one section: its static onset from a polar, and its two lags.

    Attributes
    ----------
    onset_rad : float
        Incidence where the static f is 1/2 (``flow_comparison.static_separation_fit``), rad, in (0, 45 deg).
    width_rad : float
        Width of the static f's fall, rad, > 0: f = 1 / (1 + exp((sin^2 a - sin^2 a_f) / (w sin 2 a_f))).
    pressure_lag_semichords : float
        T_p, the lag of the incidence f is read at, semichords travelled, > 0.
    point_lag_semichords : float
        T_f, the lag of f itself, semichords travelled, > 0.

    Raises
    ------
    FlowModelError
        For an onset outside (0, 45 deg), or a width or lag that is not positive and finite.
    """

    onset_rad: float
    width_rad: float
    pressure_lag_semichords: float = TANK_LAG_FACTOR * PUBLISHED_PRESSURE_LAG_SEMICHORDS
    point_lag_semichords: float = TANK_LAG_FACTOR * PUBLISHED_POINT_LAG_SEMICHORDS

    def __post_init__(self) -> None:
        """Check every coefficient's range (the class's Raises)."""
        if not (math.isfinite(self.onset_rad) and 0.0 < self.onset_rad < math.pi / 4):
            raise FlowModelError(f"TrailingEdgeSeparation.onset_rad must be in (0, 45 deg), got {self.onset_rad!r}")
        for name in ("width_rad", "pressure_lag_semichords", "point_lag_semichords"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise FlowModelError(f"TrailingEdgeSeparation.{name} must be positive and finite, got {value!r}")


def kirchhoff_share(separation_point: Any) -> Any:
    """``((1 + sqrt f) / 2)^2``: the share of the attached normal force (and circulation) that Kirchhoff's flow keeps.

    Parameters
    ----------
    separation_point : float or casadi expression
        f >= 0 (1 attached; the lagged f passes 1 a little where the speed falls).

    Returns
    -------
    float or casadi expression
        K, 1/4 at f = 0 and 1 at f = 1.
    """
    root = ca.sqrt(separation_point) if isinstance(separation_point, (ca.SX, ca.MX, ca.DM)) else math.sqrt(
        separation_point)
    return 0.25 * (1.0 + root) ** 2


def static_separation_point(u_m_s: Any, normal_m_s: Any, separation: TrailingEdgeSeparation,
                            speed_regularization_m_s: float) -> Any:
    """The static separation point at the incidence atan(normal / u) (``logistic_separation_point``).

    Parameters
    ----------
    u_m_s : float or casadi expression
        The velocity along the chord, m/s.
    normal_m_s : float or casadi expression
        The normal velocity whose incidence f is read at, m/s.
    separation : TrailingEdgeSeparation
        The section's onset and width.
    speed_regularization_m_s : float
        eps in u^2 + normal^2 + eps^2, m/s.

    Returns
    -------
    float or casadi expression
        f in (0, 1).
    """
    sin2 = normal_m_s * normal_m_s / (u_m_s * u_m_s + normal_m_s * normal_m_s + speed_regularization_m_s ** 2)
    return logistic_separation_point(sin2, separation.onset_rad, separation.width_rad)


def logistic_separation_point(sin2: Any, onset_rad: Any, width_rad: Any) -> Any:
    """``1 / (1 + exp((sin^2 a - sin^2 a_f) / (w sin 2 a_f)))``: f at an incidence a given as sin^2 a.

    1/2 at the onset a_f, its fall's width an angle there, even in the incidence and smooth through zero.

    Parameters
    ----------
    sin2 : float, ndarray or casadi expression
        sin^2 of the incidence.
    onset_rad, width_rad : float or ndarray
        a_f and w, rad (arrays broadcast against sin2: ``flow_comparison.static_separation_fit``'s grid).

    Returns
    -------
    float, ndarray or casadi expression
        f in (0, 1), of the broadcast shape.
    """
    onset_sin2, scale = np.sin(onset_rad) ** 2, width_rad * np.sin(2.0 * onset_rad)
    if np.ndim(scale) == 0:   # plain floats, so that a CasADi sin2 stays a CasADi expression
        onset_sin2, scale = float(onset_sin2), float(scale)
    exponent = (sin2 - onset_sin2) / scale
    if isinstance(exponent, (ca.SX, ca.MX, ca.DM)):
        return 1.0 / (1.0 + ca.exp(exponent))
    point = 1.0 / (1.0 + np.exp(np.minimum(exponent, _MAX_EXPONENT)))
    return float(point) if np.ndim(point) == 0 else point
