"""The symmetric Joukowski foil (paper Sec. 2 and eq. 1) and its added mass (Appendix A.1).

Map (eq. 1): the circle ``|zeta| = r_c`` goes to the foil by

    z = F(zeta) = zeta + zeta_c + a^2 / (zeta + zeta_c).

For a symmetric foil ``zeta_c`` is real and ``r_c = a + zeta_c``: the circle passes through
``zeta + zeta_c = -a``, where ``F' = 0``, which maps to the cusp (trailing edge) at ``z = -2a``.
``zeta_c = 0`` with ``r_c > a`` gives an ellipse of semi-axes ``r_c + a^2/r_c`` (along x) and
``r_c - a^2/r_c`` (along y).

Foil frame, reference point and axes (the frame of eq. 40's U, V, Omega): origin at the map origin
``z = 0`` (near mid-chord), x along the chord toward the leading edge, y normal to it (x rotated by
+90 deg). ``m26 = m62`` couples sway V and yaw Omega about that origin and changes with it; the
vehicle model places this origin ``Lf`` from the pitch axis along x (eq. 40).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import numpy.typing as npt
from scipy import optimize

from swim_model.added_mass import added_mass_from_circle_map
from swim_model.errors import FoilGeometryError


@dataclasses.dataclass(frozen=True)
class AddedMass:
    """Added-mass coefficients in the foil frame (Kirchhoff form, eq. 46).

    ``m11`` (surge, kg), ``m22`` (sway, kg), ``m26 = m62`` (sway-yaw, kg m), ``m66`` (yaw, kg m^2);
    for the whole span unless stated otherwise.
    """

    m11: float
    m22: float
    m26: float
    m66: float

    def matrix(self) -> npt.NDArray[np.float64]:
        """M_A = [[m11, 0, 0], [0, m22, m26], [0, m62, m66]] (eq. 41)."""
        return np.array([[self.m11, 0.0, 0.0], [0.0, self.m22, self.m26], [0.0, self.m26, self.m66]])

    @classmethod
    def from_matrix(cls, matrix: npt.ArrayLike) -> "AddedMass":
        m = np.asarray(matrix, dtype=float)
        return cls(m11=float(m[0, 0]), m22=float(m[1, 1]), m26=float(0.5 * (m[1, 2] + m[2, 1])),
                   m66=float(m[2, 2]))

    def scaled(self, factor: float) -> "AddedMass":
        return AddedMass(self.m11 * factor, self.m22 * factor, self.m26 * factor, self.m66 * factor)


@dataclasses.dataclass(frozen=True)
class JoukowskiMap:
    """The map ``z = zeta + zeta_c + a^2/(zeta + zeta_c)`` of the circle ``|zeta| = r_c`` (eq. 1)."""

    a_m: float
    zeta_c_m: float
    r_c_m: float

    def __call__(self, zeta: npt.NDArray[np.complex128]) -> npt.NDArray[np.complex128]:
        shifted = zeta + self.zeta_c_m
        return shifted + self.a_m ** 2 / shifted

    def profile(self, points: int = 400) -> npt.NDArray[np.complex128]:
        """Body points z, counter-clockwise, starting at the angle of the trailing edge."""
        start = math.pi if self.zeta_c_m > 0.0 else 0.0
        angle = start + 2.0 * np.pi * np.arange(points) / points
        return self(self.r_c_m * np.exp(1j * angle))

    def max_thickness(self) -> float:
        """Largest extent of the profile normal to the chord (2 max y: the profile is symmetric)."""
        def negative_half_thickness(angle: float) -> float:
            return -float(self(np.array([self.r_c_m * np.exp(1j * angle)]))[0].imag)
        grid = np.linspace(0.0, np.pi, 721)
        best = grid[np.argmin([negative_half_thickness(t) for t in grid])]
        result = optimize.minimize_scalar(negative_half_thickness,
                                          bounds=(max(best - 0.01, 0.0), min(best + 0.01, np.pi)),
                                          method="bounded", options={"xatol": 1e-12})
        return -2.0 * float(result.fun)

    def chord(self) -> float:
        """Extent along x, from the point of smallest x to the point of largest x."""
        x = self.profile(4096).real
        return float(x.max() - x.min())

    def added_mass_per_span(self, density_kg_m3: float) -> AddedMass:
        """Added mass per metre of span about the map origin (Appendix A.1)."""
        return AddedMass.from_matrix(added_mass_from_circle_map(self, self.r_c_m, density_kg_m3))


def _symmetric_map(a_m: float, offset_ratio: float) -> JoukowskiMap:
    zeta_c = offset_ratio * a_m
    return JoukowskiMap(a_m=a_m, zeta_c_m=zeta_c, r_c_m=a_m + zeta_c)


def _symmetric_chord(a_m: float, offset_ratio: float) -> float:
    """Trailing edge at -2a; leading edge at F(r_c), the circle's point on the positive real axis."""
    zeta_c = offset_ratio * a_m
    leading = a_m + 2.0 * zeta_c
    return leading + a_m ** 2 / leading + 2.0 * a_m


class JoukowskiFoil:
    """A symmetric Joukowski foil of given chord, maximum thickness and span (paper Sec. 2).

    The map parameters follow from the two lengths: the thickness ratio fixes ``zeta_c / a``
    (solved numerically), the chord then fixes ``a``.
    """

    def __init__(self, chord_m: float, thickness_m: float, span_m: float = 1.0) -> None:
        for name, value in (("chord_m", chord_m), ("thickness_m", thickness_m), ("span_m", span_m)):
            if not (math.isfinite(value) and value > 0.0):
                raise FoilGeometryError(f"{name} must be a positive finite length, got {value!r}")
        ratio = thickness_m / chord_m
        if ratio >= 0.5:
            raise FoilGeometryError(
                f"thickness/chord = {ratio:.3f}: a symmetric Joukowski foil must be thinner than half its chord")
        self.chord_m = float(chord_m)
        self.thickness_m = float(thickness_m)
        self.span_m = float(span_m)

        def thickness_ratio_error(offset_ratio: float) -> float:
            unit = _symmetric_map(1.0, offset_ratio)
            return unit.max_thickness() / _symmetric_chord(1.0, offset_ratio) - ratio

        offset_ratio = optimize.brentq(thickness_ratio_error, 1e-12, 50.0, xtol=1e-15, rtol=1e-14)
        a_m = chord_m / _symmetric_chord(1.0, offset_ratio)
        self.map = _symmetric_map(a_m, offset_ratio)

    @property
    def leading_edge_x_m(self) -> float:
        return float(self.map(np.array([self.map.r_c_m + 0j]))[0].real)

    @property
    def trailing_edge_x_m(self) -> float:
        return -2.0 * self.map.a_m

    def profile(self, points: int = 400) -> npt.NDArray[np.complex128]:
        """Profile points z = x + iy in the foil frame, m, counter-clockwise from the trailing edge."""
        return self.map.profile(points)

    def added_mass_per_span(self, rho_kg_m3: float) -> AddedMass:
        """m11, m22, m26, m66 per metre of span, about the map origin."""
        return self.map.added_mass_per_span(rho_kg_m3)

    def added_mass(self, rho_kg_m3: float) -> AddedMass:
        """m11, m22, m26, m66 of the whole span (the M_A of eq. 41 and eq. 46)."""
        return self.added_mass_per_span(rho_kg_m3).scaled(self.span_m)

    def __repr__(self) -> str:
        m = self.map
        return (f"JoukowskiFoil(chord_m={self.chord_m}, thickness_m={self.thickness_m}, span_m={self.span_m}; "
                f"a={m.a_m:.6g} m, zeta_c={m.zeta_c_m:.6g} m, r_c={m.r_c_m:.6g} m)")


def ellipse_map(semi_axis_x_m: float, semi_axis_y_m: float) -> JoukowskiMap:
    """The centred Joukowski map (zeta_c = 0) whose image is the ellipse with these semi-axes."""
    if not semi_axis_x_m > semi_axis_y_m > 0.0:
        raise FoilGeometryError("an ellipse map needs semi_axis_x_m > semi_axis_y_m > 0")
    r_c = 0.5 * (semi_axis_x_m + semi_axis_y_m)
    return JoukowskiMap(a_m=math.sqrt(r_c * 0.5 * (semi_axis_x_m - semi_axis_y_m)), zeta_c_m=0.0, r_c_m=r_c)
