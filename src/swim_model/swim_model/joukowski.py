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

    For the whole span unless stated otherwise.

    Attributes
    ----------
    m11 : float
        Surge, kg.
    m22 : float
        Sway, kg.
    m26 : float
        Sway-yaw coupling m26 = m62, kg m.
    m66 : float
        Yaw, kg m^2.
    """

    m11: float
    m22: float
    m26: float
    m66: float

    def matrix(self) -> npt.NDArray[np.float64]:
        """M_A = [[m11, 0, 0], [0, m22, m26], [0, m62, m66]] (eq. 41).

        Returns
        -------
        (3, 3) ndarray
            M_A, kg, kg m and kg m^2 by entry.
        """
        return np.array([[self.m11, 0.0, 0.0], [0.0, self.m22, self.m26], [0.0, self.m26, self.m66]])

    @classmethod
    def from_matrix(cls, matrix: npt.ArrayLike) -> "AddedMass":
        """The coefficients of a 3 x 3 added-mass matrix (its sway-yaw entries averaged).

        Parameters
        ----------
        matrix : (3, 3) array_like
            M_A, kg, kg m and kg m^2 by entry.

        Returns
        -------
        AddedMass
            The coefficients.
        """
        m = np.asarray(matrix, dtype=float)
        return cls(m11=float(m[0, 0]), m22=float(m[1, 1]), m26=float(0.5 * (m[1, 2] + m[2, 1])),
                   m66=float(m[2, 2]))

    def scaled(self, factor: float) -> "AddedMass":
        """Every coefficient times a factor (per-span values times the span, for instance).

        Parameters
        ----------
        factor : float
            The factor (m for a span).

        Returns
        -------
        AddedMass
            The scaled coefficients.
        """
        return AddedMass(self.m11 * factor, self.m22 * factor, self.m26 * factor, self.m66 * factor)


@dataclasses.dataclass(frozen=True)
class JoukowskiMap:
    """The map ``z = zeta + zeta_c + a^2/(zeta + zeta_c)`` of the circle ``|zeta| = r_c`` (eq. 1).

    Attributes
    ----------
    a_m : float
        a, m.
    zeta_c_m : float
        zeta_c, the circle's offset (real for a symmetric foil), m.
    r_c_m : float
        r_c, the circle's radius, m.
    """

    a_m: float
    zeta_c_m: float
    r_c_m: float

    def __call__(self, zeta: npt.NDArray[np.complex128]) -> npt.NDArray[np.complex128]:
        """Map circle-plane points to the foil plane.

        Parameters
        ----------
        zeta : ndarray of complex
            Points of the circle plane, m.

        Returns
        -------
        ndarray of complex
            z = F(zeta), m, of zeta's shape.
        """
        shifted = zeta + self.zeta_c_m
        return shifted + self.a_m ** 2 / shifted

    def profile(self, points: int = 400) -> npt.NDArray[np.complex128]:
        """Body points z, counter-clockwise, starting at the angle of the trailing edge.

        Parameters
        ----------
        points : int, optional
            Number of points.

        Returns
        -------
        (points,) ndarray of complex
            z = x + iy, m.
        """
        start = math.pi if self.zeta_c_m > 0.0 else 0.0
        angle = start + 2.0 * np.pi * np.arange(points) / points
        return self(self.r_c_m * np.exp(1j * angle))

    def max_thickness(self) -> float:
        """Largest extent of the profile normal to the chord (2 max y: the profile is symmetric).

        Returns
        -------
        float
            Thickness, m.
        """
        def negative_half_thickness(angle: float) -> float:
            return -float(self(np.array([self.r_c_m * np.exp(1j * angle)]))[0].imag)
        grid = np.linspace(0.0, np.pi, 721)
        best = grid[np.argmin([negative_half_thickness(t) for t in grid])]
        result = optimize.minimize_scalar(negative_half_thickness,
                                          bounds=(max(best - 0.01, 0.0), min(best + 0.01, np.pi)),
                                          method="bounded", options={"xatol": 1e-12})
        return -2.0 * float(result.fun)

    def chord(self) -> float:
        """Extent along x, from the point of smallest x to the point of largest x.

        Returns
        -------
        float
            Chord, m.
        """
        x = self.profile(4096).real
        return float(x.max() - x.min())

    def added_mass_per_span(self, density_kg_m3: float) -> AddedMass:
        """Added mass per metre of span about the map origin (Appendix A.1).

        Parameters
        ----------
        density_kg_m3 : float
            Fluid density, kg/m^3.

        Returns
        -------
        AddedMass
            Per span: kg/m, kg, kg m.
        """
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

    The map parameters follow from the two lengths: the thickness ratio fixes ``zeta_c / a`` (solved
    numerically), the chord then fixes ``a``.

    Parameters
    ----------
    chord_m : float
        Chord, m, > 0.
    thickness_m : float
        Largest thickness, m, below half the chord.
    span_m : float, optional
        Span, m.

    Raises
    ------
    FoilGeometryError
        For a length that is not positive and finite, or a thickness of half the chord or more.
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
        """The leading edge's x in the foil frame, m."""
        return float(self.map(np.array([self.map.r_c_m + 0j]))[0].real)

    @property
    def trailing_edge_x_m(self) -> float:
        """The trailing edge's (cusp's) x in the foil frame, -2a, m."""
        return -2.0 * self.map.a_m

    def profile(self, points: int = 400) -> npt.NDArray[np.complex128]:
        """Profile points in the foil frame, counter-clockwise from the trailing edge.

        Parameters
        ----------
        points : int, optional
            Number of points, as for ``JoukowskiMap.profile``, which gives them.

        Returns
        -------
        (points,) ndarray of complex
            The map's profile z = x + iy, m.
        """
        return self.map.profile(points)

    def added_mass_per_span(self, rho_kg_m3: float) -> AddedMass:
        """m11, m22, m26, m66 per metre of span, about the map origin.

        Parameters
        ----------
        rho_kg_m3 : float
            Water density, kg/m^3 (``JoukowskiMap.added_mass_per_span``'s density).

        Returns
        -------
        AddedMass
            The map's coefficients per metre of span.
        """
        return self.map.added_mass_per_span(rho_kg_m3)

    def added_mass(self, rho_kg_m3: float) -> AddedMass:
        """m11, m22, m26, m66 of the whole span (the M_A of eq. 41 and eq. 46).

        Parameters
        ----------
        rho_kg_m3 : float
            Density of the water around the foil, kg/m^3.

        Returns
        -------
        AddedMass
            kg, kg m and kg m^2.
        """
        return self.added_mass_per_span(rho_kg_m3).scaled(self.span_m)

    def __repr__(self) -> str:
        """The foil's lengths and its map's parameters."""
        m = self.map
        return (f"JoukowskiFoil(chord_m={self.chord_m}, thickness_m={self.thickness_m}, span_m={self.span_m}; "
                f"a={m.a_m:.6g} m, zeta_c={m.zeta_c_m:.6g} m, r_c={m.r_c_m:.6g} m)")


def ellipse_map(semi_axis_x_m: float, semi_axis_y_m: float) -> JoukowskiMap:
    """The centred Joukowski map (zeta_c = 0) whose image is the ellipse with these semi-axes.

    Parameters
    ----------
    semi_axis_x_m : float
        Semi-axis along x, m.
    semi_axis_y_m : float
        Semi-axis along y, m, with 0 < semi_axis_y_m < semi_axis_x_m.

    Returns
    -------
    JoukowskiMap
        The map.

    Raises
    ------
    FoilGeometryError
        Unless semi_axis_x_m > semi_axis_y_m > 0.
    """
    if not semi_axis_x_m > semi_axis_y_m > 0.0:
        raise FoilGeometryError("an ellipse map needs semi_axis_x_m > semi_axis_y_m > 0")
    r_c = 0.5 * (semi_axis_x_m + semi_axis_y_m)
    return JoukowskiMap(a_m=math.sqrt(r_c * 0.5 * (semi_axis_x_m - semi_axis_y_m)), zeta_c_m=0.0, r_c_m=r_c)
