"""Point vortices around the Joukowski foil in the circle plane: flow, Kutta condition, impulse and force.

The closed forms the wake (swim_model.wake) evaluates: the map and its inverse, the body's and the vortices'
complex potentials (circle theorem), each free vortex's velocity (Routh's rule, Krasny blob), the Kutta condition
at the cusp, the leading-edge suction parameter, and the vortical impulse and angular impulse whose rates are the
vortical force and moment. Notation and derivations: docs/wake_study.md, Sec. 1.1 (after Streitlien &
Triantafyllou, AIAA J. 33(4), 1995; Milne-Thomson, Theoretical Hydrodynamics, Sec. 6.21 and 13.3; Saffman,
Vortex Dynamics, 1992, Sec. 3.2). Complex positions are in metres on the circle plane (zeta) or in the foil frame
(z); circulations are counter-clockwise, m^2/s; a foil velocity is (U m/s, V m/s, Omega rad/s) in foil axes.
"""
from __future__ import annotations

import cmath
import math
import sys
from typing import Any, Callable, TypeVar, cast

import numpy as np
import numpy.typing as npt

from swim_model.errors import FoilGeometryError
from swim_model.joukowski import JoukowskiMap

Complex = npt.NDArray[np.complex128]

MIN_OFFSET_RATIO = 1e-6  # zeta_c / a below this: the rotation potential's two poles merge (an ellipse); refused

_Function = TypeVar("_Function", bound=Callable[..., object])
_Points = TypeVar("_Points", Complex, complex)   # an array of points in the circle plane, or one


class _Kernel:
    """A function of this package's that numba compiles, numba imported only when a kernel is first called.

    A process that never steps a wake does not pay numba's import, about 0.6 s.
    """

    registered: list["_Kernel"] = []

    def __init__(self, function: Callable[..., Any]) -> None:
        self.function = function
        self.dispatcher: Callable[..., Any] | None = None
        _Kernel.registered.append(self)

    def __call__(self, *args: Any) -> Any:
        if self.dispatcher is None:
            _Kernel.load_all()
        return cast(Callable[..., Any], self.dispatcher)(*args)

    @staticmethod
    def load_all() -> None:
        """Wrap every registered kernel in numba's dispatcher.

        Each dispatcher goes into its module's namespace in place of this object, so that a kernel calling another
        compiles against the other's dispatcher and module code calls the dispatcher directly. numba compiles a kernel
        at its first call for the argument types.
        """
        import numba  # here, not at the module top: the point of the lazy load
        for kernel in _Kernel.registered:
            if kernel.dispatcher is None:
                # error_model "numpy": a division by zero gives inf or nan as in numpy, not an exception (whose
                # check would keep the loops out of SIMD lanes)
                kernel.dispatcher = numba.njit(cache=True, error_model="numpy")(kernel.function)
                setattr(sys.modules[kernel.function.__module__], kernel.function.__name__, kernel.dispatcher)


def compiled(function: _Function) -> _Function:
    """The function compiled to machine code by numba (nopython mode) at its first call.

    Cached on disk beside the module: the first call in a fresh environment compiles it (about a second), later
    processes load it. numba itself is imported at the first call of any such function (``_Kernel``).

    Parameters
    ----------
    function : callable
        A function numba can compile in nopython mode.

    Returns
    -------
    callable
        A stand-in with the function's signature that compiles and calls it.
    """
    return cast(_Function, _Kernel(function))


@compiled
def _blob_sums(x: npt.NDArray[np.float64], y: npt.NDArray[np.float64], source_x: npt.NDArray[np.float64],
               source_y: npt.NDArray[np.float64], gamma: npt.NDArray[np.float64], core2: npt.NDArray[np.float64],
               sum_x: npt.NDArray[np.float64], sum_y: npt.NDArray[np.float64]) -> None:
    """(sum_x, sum_y)[j] = sum_k (w_jk dx_jk, w_jk dy_jk): the blob sums of a wake step.

    dx_jk + i dy_jk = (x_j + i y_j) - (source_x_k + i source_y_k), w_jk = gamma_k / (dx_jk^2 + dy_jk^2 + core2_k): O(N
    M), the cost of a wake step. Summed in index order k; the loop over the points j is the inner one, so that it runs
    in SIMD lanes.
    """
    sum_x[:] = 0.0
    sum_y[:] = 0.0
    for k in range(source_x.size):
        for j in range(x.size):
            dx = x[j] - source_x[k]
            dy = y[j] - source_y[k]
            weight = gamma[k] / (dx * dx + dy * dy + core2[k])
            sum_x[j] += weight * dx
            sum_y[j] += weight * dy


@compiled
def _vortex_potential_sums(points: Complex, zeta: Complex, gamma: npt.NDArray[np.float64], r_m: float,
                           sums: Complex) -> None:
    """sum_k Gamma_k [1/(p - zeta_k) - 1/(p - zeta_k*)] at the points p into sums.

    Exact kernel, summed in index order (1/D = conj(D)/|D|^2, the loop over the points inner, so that it runs in SIMD
    lanes).
    """
    r2 = r_m * r_m
    x, y = points.real.copy(), points.imag.copy()
    real, imag = np.zeros(points.size), np.zeros(points.size)
    for k in range(zeta.size):
        image = r2 / zeta[k].conjugate()
        vortex_x, vortex_y, image_x, image_y = zeta[k].real, zeta[k].imag, image.real, image.imag
        for j in range(x.size):
            dx, dy = x[j] - vortex_x, y[j] - vortex_y
            image_dx, image_dy = x[j] - image_x, y[j] - image_y
            weight = gamma[k] / (dx * dx + dy * dy)
            image_weight = gamma[k] / (image_dx * image_dx + image_dy * image_dy)
            real[j] += weight * dx - image_weight * image_dx
            imag[j] += image_weight * image_dy - weight * dy
    for j in range(x.size):
        sums[j] = complex(real[j], imag[j])


@compiled
def _to_circle(z: Complex, a_m: float, zeta_c_m: float, zeta: Complex) -> None:
    """Zeta = F^{-1}(z) into zeta, the branch outside the circle (``CirclePlane.to_circle``)."""
    four_a2 = 4.0 * a_m * a_m
    for k in range(z.size):
        root = cmath.sqrt(z[k] * z[k] - four_a2)
        s_plus, s_minus = 0.5 * (z[k] + root), 0.5 * (z[k] - root)
        zeta[k] = (s_plus if abs(s_plus) >= abs(s_minus) else s_minus) - zeta_c_m


@compiled
def _vortex_velocities(zeta: Complex, gamma: npt.NDArray[np.float64], u_b: complex, omega: float,
                       core_radii_m: npt.NDArray[np.float64], a_m: float, zeta_c_m: float, r_m: float,
                       pole_origin_m3: float, pole_offset_m3: float, velocities: Complex) -> None:
    """``CirclePlane.vortex_velocities`` into velocities (N).

    The map's derivatives, each blob's core (N) in the circle plane and the images per vortex, the O(N^2) sums
    (``_blob_sums``), then the body and Routh terms.
    """
    n = zeta.size
    a2, r2 = a_m * a_m, r_m * r_m
    x, y = np.empty(n), np.empty(n)
    image_x, image_y = np.empty(n), np.empty(n)
    core2, no_core = np.empty(n), np.zeros(n)
    d1, d2 = np.empty(n, dtype=np.complex128), np.empty(n, dtype=np.complex128)
    for k in range(n):
        x[k], y[k] = zeta[k].real, zeta[k].imag
        s = zeta[k] + zeta_c_m
        a2_over_s2 = a2 / (s * s)
        d1[k], d2[k] = 1.0 - a2_over_s2, 2.0 * a2_over_s2 / s
        core2[k] = (core_radii_m[k] / max(abs(d1[k]), 1e-12)) ** 2
        image = r2 / zeta[k].conjugate()
        image_x[k], image_y[k] = image.real, image.imag
    sums = np.empty((4, n))
    _blob_sums(x, y, x, y, gamma, core2, sums[0], sums[1])
    _blob_sums(x, y, image_x, image_y, gamma, no_core, sums[2], sums[3])
    for k in range(n):
        mutual = complex(sums[0, k] - sums[2, k], sums[3, k] - sums[1, k])
        s = zeta[k] + zeta_c_m
        inv_zeta2, inv_s2 = 1.0 / (zeta[k] * zeta[k]), 1.0 / (s * s)
        body = (u_b * r2 * inv_zeta2 - u_b.conjugate() * a2 * inv_s2
                + 1j * omega * (pole_origin_m3 * inv_zeta2 + pole_offset_m3 * inv_s2))
        dw_dzeta = mutual / (2j * math.pi) + body
        conj_u = dw_dzeta / d1[k] - gamma[k] * d2[k] / (4j * math.pi * d1[k] * d1[k])
        velocities[k] = conj_u.conjugate()


@compiled
def _impulse_terms_kernel(zeta: Complex, gamma: npt.NDArray[np.float64], a_m: float, zeta_c_m: float, r_m: float,
                   pole_origin_m3: float, pole_offset_m3: float, impulse_terms: Complex,
                   angular_terms: npt.NDArray[np.float64]) -> None:
    """``CirclePlane.vortex_impulse_terms`` and ``vortex_angular_impulse_terms`` into the two arrays (N)."""
    a2, r2 = a_m * a_m, r_m * r_m
    for k in range(zeta.size):
        image = r2 / zeta[k].conjugate()
        impulse_terms[k] = gamma[k] * (zeta[k] - image)
        s, image_s = zeta[k] + zeta_c_m, image + zeta_c_m
        z_k, image_z = s + a2 / s, image_s + a2 / image_s
        sheet = (-image_z * z_k.conjugate() + pole_origin_m3 * (1.0 / image - 1.0 / zeta[k])
                 + pole_offset_m3 * (1.0 / image_s - 1.0 / s))
        angular_terms[k] = gamma[k] * (z_k.real * z_k.real + z_k.imag * z_k.imag + sheet.real)

class CirclePlane:
    """The Joukowski map of one foil and the closed forms of docs/wake_study.md, Sec. 1.1, evaluated on it.

    Parameters
    ----------
    conformal_map : JoukowskiMap
        The foil's map, with zeta_c > 0.

    Raises
    ------
    FoilGeometryError
        For an ellipse map (zeta_c / a below MIN_OFFSET_RATIO), whose rotation poles merge.
    """

    def __init__(self, conformal_map: JoukowskiMap) -> None:
        if conformal_map.zeta_c_m < MIN_OFFSET_RATIO * conformal_map.a_m:
            raise FoilGeometryError("the vortex wake needs a Joukowski foil with zeta_c > 0 (not an ellipse map)")
        self.map = conformal_map
        self.a_m = conformal_map.a_m
        self.zeta_c_m = conformal_map.zeta_c_m
        self.r_m = conformal_map.r_c_m
        self.zeta_te = complex(-self.r_m)
        self.zeta_le = complex(self.r_m)
        leading = self.r_m + self.zeta_c_m                                       # s at the leading edge
        self.z_le = complex(leading + self.a_m ** 2 / leading)
        self.map_derivative_le = 1.0 - self.a_m ** 2 / leading ** 2              # F'(zeta_le), real
        self.z_te = complex(-2.0 * self.a_m)
        a2, r2, zc = self.a_m ** 2, self.r_m ** 2, self.zeta_c_m
        self.rotation_pole_origin_m3 = r2 * (zc + a2 / zc)                       # A = r^2 F(0)
        far = -r2 / zc + zc
        self.rotation_pole_offset_m3 = a2 * (far + a2 / far)                     # B = a^2 F(-r^2/zeta_c)

    # --- the map ------------------------------------------------------------------------------------------
    def to_foil(self, zeta: Complex) -> Complex:
        """Z = F(zeta).

        Parameters
        ----------
        zeta : ndarray of complex
            Circle-plane points, m.

        Returns
        -------
        ndarray of complex
            Foil-frame points, m, of zeta's shape.
        """
        s = zeta + self.zeta_c_m
        return s + self.a_m ** 2 / s

    def map_derivatives(self, zeta: Complex) -> tuple[Complex, Complex]:
        """(F'(zeta), F''(zeta)).

        Parameters
        ----------
        zeta : ndarray of complex
            Circle-plane points where F' and F'' are evaluated, m.

        Returns
        -------
        tuple of two ndarray of complex
            F' (dimensionless) and F'' (1/m), of zeta's shape.
        """
        s = zeta + self.zeta_c_m
        a2_over_s2 = self.a_m ** 2 / (s * s)
        return 1.0 - a2_over_s2, 2.0 * a2_over_s2 / s

    def to_circle(self, z: Complex) -> Complex:
        """Zeta = F^{-1}(z), the branch outside the circle (``|s| >= a``).

        Parameters
        ----------
        z : ndarray of complex
            Foil-frame points to map back, m.

        Returns
        -------
        ndarray of complex
            Circle-plane points, m, of z's shape.
        """
        points = np.ascontiguousarray(z, dtype=complex).reshape(-1)
        zeta: Complex = np.empty_like(points)
        _to_circle(points, self.a_m, self.zeta_c_m, zeta)
        return zeta.reshape(np.shape(z))

    def image(self, zeta: Complex) -> Complex:
        """zeta* = r^2 / conj(zeta) (circle theorem).

        Parameters
        ----------
        zeta : ndarray of complex
            Circle-plane points, m, off the circle's centre.

        Returns
        -------
        ndarray of complex
            Their images, m.
        """
        conjugate: Complex = np.conj(zeta)
        return self.r_m ** 2 / conjugate

    # --- flow -----------------------------------------------------------------------------------------------
    def body_potential_derivative(self, zeta: _Points, velocity: tuple[float, float, float]) -> _Points:
        """D w_body / d zeta = u_b r^2/zeta^2 - conj(u_b) a^2/s^2 + i Omega (A/zeta^2 + B/s^2).

        Parameters
        ----------
        zeta : complex or ndarray of complex
            Circle-plane points, m.
        velocity : tuple of 3 floats
            Foil velocity (U m/s, V m/s, Omega rad/s).

        Returns
        -------
        complex or ndarray of complex
            dw_body/dzeta, m/s, of zeta's shape.
        """
        u_b = complex(velocity[0], velocity[1])
        omega = velocity[2]
        s = zeta + self.zeta_c_m
        inv_zeta2, inv_s2 = 1.0 / (zeta * zeta), 1.0 / (s * s)
        return (u_b * self.r_m ** 2 * inv_zeta2 - u_b.conjugate() * self.a_m ** 2 * inv_s2
                + 1j * omega * (self.rotation_pole_origin_m3 * inv_zeta2 + self.rotation_pole_offset_m3 * inv_s2))

    def body_dipole(self, velocity: tuple[float, float, float]) -> complex:
        """A_1 of w_body at infinity: -u_b r^2 + conj(u_b) a^2 - i Omega (A + B).

        Parameters
        ----------
        velocity : tuple of 3 floats
            Foil velocity (U m/s, V m/s, Omega rad/s).

        Returns
        -------
        complex
            A_1, m^3/s.
        """
        u_b = complex(velocity[0], velocity[1])
        return (-u_b * self.r_m ** 2 + u_b.conjugate() * self.a_m ** 2
                - 1j * velocity[2] * (self.rotation_pole_origin_m3 + self.rotation_pole_offset_m3))

    def vortex_potential_derivative(self, zeta: Complex, zeta_k: Complex, gamma_k: npt.NDArray[np.float64]) -> Complex:
        """sum_k Gamma_k/(2 pi i) [1/(zeta - zeta_k) - 1/(zeta - zeta_k*)], exact kernel, at points zeta.

        Parameters
        ----------
        zeta : ndarray of complex
            Circle-plane points where it is evaluated, m.
        zeta_k, gamma_k : (N,) ndarray of complex and (N,) ndarray
            The free vortices' circle-plane positions, m, and their circulations, m^2/s.

        Returns
        -------
        ndarray of complex
            dw/dzeta of the vortices and their images, m/s, one per point (1-D).
        """
        points = np.ascontiguousarray(np.atleast_1d(zeta), dtype=complex)
        sums: Complex = np.zeros(points.size, dtype=complex)
        _vortex_potential_sums(points, np.ascontiguousarray(zeta_k, dtype=complex),
                               np.ascontiguousarray(gamma_k, dtype=float), self.r_m, sums)
        total: Complex = sums / (2j * math.pi)
        return total

    def vortex_velocities(self, zeta_k: Complex, gamma_k: npt.NDArray[np.float64],
                          velocity: tuple[float, float, float],
                          core_radius_m: float | npt.NDArray[np.float64]) -> Complex:
        """Fluid velocity u + iv (foil axes) at each free vortex: blob mutual terms, exact images, Routh term.

        Parameters
        ----------
        zeta_k, gamma_k : (N,) ndarray of complex and (N,) ndarray
            The free vortices (positions, m; circulations, m^2/s), each moved by the others and by the images.
        velocity : tuple of 3 floats
            Foil velocity (U m/s, V m/s, Omega rad/s).
        core_radius_m : float or (N,) ndarray
            The blobs' core radius in the physical plane, m: one for all, or one per vortex, the source vortex's core
            desingularizing each pair's term.

        Returns
        -------
        (N,) ndarray of complex
            u + iv at each vortex, m/s.
        """
        velocities: Complex = np.empty(zeta_k.size, dtype=complex)
        cores = np.ascontiguousarray(np.broadcast_to(np.asarray(core_radius_m, dtype=float), np.shape(zeta_k)))
        _vortex_velocities(np.ascontiguousarray(zeta_k, dtype=complex), np.ascontiguousarray(gamma_k, dtype=float),
                           complex(velocity[0], velocity[1]), float(velocity[2]), cores, self.a_m,
                           self.zeta_c_m, self.r_m, self.rotation_pole_origin_m3, self.rotation_pole_offset_m3,
                           velocities)
        return velocities

    def kutta_strength(self, zeta_new: complex, zeta_k: Complex, gamma_k: npt.NDArray[np.float64],
                       velocity: tuple[float, float, float]) -> float:
        """Strength of a vortex at zeta_new that makes Im(dw/dzeta) vanish at the trailing edge.

        Parameters
        ----------
        zeta_new : complex
            The new vortex's circle-plane position, m.
        zeta_k, gamma_k : (N,) ndarray of complex and (N,) ndarray
            The vortices shed before it: positions, m, and circulations, m^2/s.
        velocity : tuple of 3 floats
            Foil velocity (U m/s, V m/s, Omega rad/s).

        Returns
        -------
        float
            The new vortex's circulation, m^2/s.
        """
        known = self._trailing_edge_tangential_velocity(zeta_k, gamma_k, velocity)
        return float(-known / self.unit_vortex_potential_derivative(self.zeta_te, zeta_new).imag)

    def separated_kutta_strength(self, zeta_new: complex, zeta_k: Complex, gamma_k: npt.NDArray[np.float64],
                                 velocity: tuple[float, float, float], attached_share: float) -> float:
        """Strength of a vortex at zeta_new that leaves the trailing edge's flow K times the attached circulation's.

        The condition: Im(dw/dzeta) at the trailing edge is (1 - K) times that of the same flow without its bound
        circulation (the free vortices' images carry -sum(gamma) about the circle; a vortex of +sum(gamma) at the
        centre takes it off). K = 1 is the Kutta condition (``kutta_strength``). In steady flow the bound
        circulation settles at K times the Kutta circulation whatever the step, since the condition holds the edge's
        whole velocity rather than the new vortex's share of it: Kirchhoff's flow with K = ((1 + sqrt f)/2)^2
        (swim_model.separation.kirchhoff_share; docs/flow_model.md, Sec. 6).

        Parameters
        ----------
        zeta_new, zeta_k, gamma_k, velocity
            As for ``kutta_strength``.
        attached_share : float
            K > 0.

        Returns
        -------
        float
            The new vortex's circulation, m^2/s.
        """
        if attached_share == 1.0:
            return self.kutta_strength(zeta_new, zeta_k, gamma_k, velocity)
        known = self._trailing_edge_tangential_velocity(zeta_k, gamma_k, velocity)
        unit = self.unit_vortex_potential_derivative(self.zeta_te, zeta_new).imag
        per_bound_circulation = 1.0 / (2.0 * math.pi * self.r_m)   # Im(dw/dzeta) at -r of a unit vortex at the centre
        shed = float(np.sum(gamma_k))
        detached = 1.0 - attached_share
        return float((detached * shed * per_bound_circulation - attached_share * known)
                     / (attached_share * unit - detached * per_bound_circulation))

    def _trailing_edge_tangential_velocity(self, zeta_k: Complex, gamma_k: npt.NDArray[np.float64],
                                           velocity: tuple[float, float, float]) -> float:
        """Im(dw/dzeta) at the trailing edge of the body's flow and the free vortices' with their images, m/s."""
        te = self.zeta_te
        known = self.body_potential_derivative(te, velocity) + self.vortex_potential_derivative(
            np.array([te]), zeta_k, gamma_k)[0]
        return float(known.imag)

    def unit_vortex_potential_derivative(self, point: complex, zeta_new: complex) -> complex:
        """dw/dzeta at a point of a vortex of unit strength at zeta_new with its image.

        Parameters
        ----------
        point : complex
            Where it is evaluated, circle plane, m.
        zeta_new : complex
            The vortex's circle-plane position, m.

        Returns
        -------
        complex
            dw/dzeta per unit circulation, 1/m.
        """
        image_new = self.r_m ** 2 / zeta_new.conjugate()
        return (1.0 / (point - zeta_new) - 1.0 / (point - image_new)) / (2j * math.pi)

    def edge_potential_derivatives(self, zeta_k: Complex, gamma_k: npt.NDArray[np.float64],
                                   velocity: tuple[float, float, float]) -> tuple[complex, complex]:
        """dw/dzeta (body and free vortices with their images) at the trailing edge and at the leading edge.

        Parameters
        ----------
        zeta_k, gamma_k : (N,) ndarray of complex and (N,) ndarray
            The free vortices whose flow is added at both edges, as for ``vortex_potential_derivative``.
        velocity : tuple of 3 floats
            Foil velocity (U m/s, V m/s, Omega rad/s).

        Returns
        -------
        tuple of two complex
            (at the trailing edge, at the leading edge), m/s.
        """
        edges = np.array([self.zeta_te, self.zeta_le])
        total = self.body_potential_derivative(edges, velocity) + self.vortex_potential_derivative(edges, zeta_k,
                                                                                                   gamma_k)
        return complex(total[0]), complex(total[1])

    def leading_edge_suction_parameter(self, leading_edge_derivative: complex,
                                       velocity: tuple[float, float, float], speed_m_s: float) -> float:
        """LESP = q_LE / (4 |u|) of the flow at the leading edge.

        q_LE is the flow's tangential velocity relative to the foil at the circle's leading-edge point (circle plane,
        counter-clockwise positive): dw/dzeta - conj(u_LE) F'(zeta_LE), u_LE the leading edge's own velocity. In the
        steady Kutta flow at angle of attack alpha it is sin(alpha) for every thickness, the thin aerofoil's A0
        (swim_model.flow: the suction 4 pi rho r (LESP |u|)^2).

        Parameters
        ----------
        leading_edge_derivative : complex
            dw/dzeta at the leading edge (``edge_potential_derivatives``), m/s.
        velocity : tuple of 3 floats
            Foil velocity (U m/s, V m/s, Omega rad/s).
        speed_m_s : float
            The foil's speed |u|, m/s, > 0.

        Returns
        -------
        float
            LESP, dimensionless.
        """
        u, v, omega = velocity
        leading_edge_velocity = complex(u, v) + 1j * omega * self.z_le
        relative = leading_edge_derivative - leading_edge_velocity.conjugate() * self.map_derivative_le
        return -relative.imag / (4.0 * speed_m_s)

    def far_field_circulation(self, zeta_k: Complex, gamma_k: npt.NDArray[np.float64],
                              velocity: tuple[float, float, float], samples: int = 256) -> float:
        """Re of the contour integral of dw/dzeta on a circle enclosing every vortex: the flow's total circulation.

        The integrand is analytic outside all vortices, so the trapezoidal rule converges geometrically on a circle
        twice as large as the farthest vortex.

        Parameters
        ----------
        zeta_k, gamma_k : (N,) ndarray of complex and (N,) ndarray
            The free vortices (``vortex_potential_derivative``); the contour encloses them all.
        velocity : tuple of 3 floats
            Foil velocity (U m/s, V m/s, Omega rad/s).
        samples : int, optional
            Points of the trapezoidal rule.

        Returns
        -------
        float
            Total circulation, m^2/s (Kelvin: zero).
        """
        radius = 2.0 * max(self.r_m, float(np.max(np.abs(zeta_k))) if zeta_k.size else 0.0)
        zeta = radius * np.exp(2j * math.pi * np.arange(samples) / samples)
        dw = self.body_potential_derivative(zeta, velocity) + self.vortex_potential_derivative(zeta, zeta_k, gamma_k)
        return float(np.real(np.sum(dw * 1j * zeta) * 2.0 * math.pi / samples))

    # --- impulse ----------------------------------------------------------------------------------------------
    def vortex_impulse(self, zeta_k: Complex, gamma_k: npt.NDArray[np.float64], rho_kg_m3: float) -> complex:
        """I_v = -i rho sum_k Gamma_k (zeta_k - zeta_k*), foil axes, per metre of span.

        Parameters
        ----------
        zeta_k, gamma_k
            The free vortices, as for ``impulse_terms``.
        rho_kg_m3 : float
            Water density, kg/m^3.

        Returns
        -------
        complex
            I_v, kg/s per metre of span (x + iy in foil axes).
        """
        return impulse_from_terms(self.impulse_terms(zeta_k, gamma_k)[0], rho_kg_m3)

    def vortex_angular_impulse(self, zeta_k: Complex, gamma_k: npt.NDArray[np.float64], rho_kg_m3: float) -> float:
        """L_v about the frame origin (docs/wake_study.md, Sec. 1.1), per metre of span.

        Parameters
        ----------
        zeta_k, gamma_k
            The free vortices (``impulse_terms``' arguments).
        rho_kg_m3 : float
            Water density, kg/m^3.

        Returns
        -------
        float
            L_v, kg m/s per metre of span, counter-clockwise positive.
        """
        return angular_impulse_from_terms(self.impulse_terms(zeta_k, gamma_k)[1], rho_kg_m3)

    def impulse_terms(self, zeta_k: Complex,
                      gamma_k: npt.NDArray[np.float64]) -> tuple[Complex, npt.NDArray[np.float64]]:
        """Each vortex's terms of the impulse sums.

        Parameters
        ----------
        zeta_k, gamma_k : (N,) ndarray of complex and (N,) ndarray
            The free vortices' circle-plane positions, m, and circulations, m^2/s, one term of each sum per vortex.

        Returns
        -------
        impulse : (N,) ndarray of complex
            Gamma_k (zeta_k - zeta_k*), m^3/s: I_v = -i rho times their sum.
        angular : (N,) ndarray
            Gamma_k [|z_k|^2 + Re(...)], m^4/s, the bracket of L_v (docs/wake_study.md, Sec. 1.1): L_v = -rho/2 times
            their sum.
        """
        zeta = np.ascontiguousarray(np.atleast_1d(zeta_k), dtype=complex)
        impulse: Complex = np.empty_like(zeta)
        angular: npt.NDArray[np.float64] = np.empty(zeta.size)
        _impulse_terms_kernel(zeta, np.ascontiguousarray(np.atleast_1d(gamma_k), dtype=float), self.a_m,
                              self.zeta_c_m, self.r_m, self.rotation_pole_origin_m3, self.rotation_pole_offset_m3,
                              impulse, angular)
        return impulse, angular


def impulse_from_terms(impulse_terms: Complex, rho_kg_m3: float) -> complex:
    """I_v = -i rho times the sum of the vortices' impulse terms (``CirclePlane.impulse_terms``).

    Parameters
    ----------
    impulse_terms : (N,) ndarray of complex
        The terms, m^3/s, in foil axes.
    rho_kg_m3 : float
        Water density, kg/m^3.

    Returns
    -------
    complex
        I_v in the axes of the terms, kg/s per metre of span.
    """
    return -1j * rho_kg_m3 * complex(np.sum(impulse_terms))


def angular_impulse_from_terms(angular_terms: npt.NDArray[np.float64], rho_kg_m3: float) -> float:
    """L_v about the foil frame's origin: -rho/2 times the sum of the vortices' angular terms.

    Parameters
    ----------
    angular_terms : (N,) ndarray
        The terms (``CirclePlane.impulse_terms``), m^4/s.
    rho_kg_m3 : float
        Water density, kg/m^3.

    Returns
    -------
    float
        L_v, kg m/s per metre of span.
    """
    return -0.5 * rho_kg_m3 * float(np.sum(angular_terms))


def steady_kutta_circulation(plane: CirclePlane, speed_m_s: float, angle_of_attack_rad: float) -> float:
    """Gamma = 4 pi r U sin(alpha): the steady Kutta circulation of the foil moving at U, angle of attack alpha.

    Relative stream ``W = -u_b`` past the circle: ``dw/dzeta = conj(W) - W r^2/zeta^2 + Gamma/(2 pi i zeta)``
    vanishes at ``zeta = -r`` when ``Gamma = 4 pi r Im(W)``; with ``u_b = U e^{-i alpha}``, ``Im W = U sin alpha``.
    The lift is ``rho U Gamma`` (Kutta-Joukowski); r = c/4 (flat plate) gives ``pi rho c U^2 sin alpha``.

    Parameters
    ----------
    plane : CirclePlane
        The foil's circle plane (its radius r).
    speed_m_s : float
        U, m/s.
    angle_of_attack_rad : float
        alpha, rad.

    Returns
    -------
    float
        Gamma, m^2/s.
    """
    return 4.0 * math.pi * plane.r_m * speed_m_s * math.sin(angle_of_attack_rad)
