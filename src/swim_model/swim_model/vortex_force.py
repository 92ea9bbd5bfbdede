"""Point vortices around the Joukowski foil in the circle plane: flow, Kutta condition, impulse and force.

Streitlien & Triantafyllou, "Force and moment on a Joukowski profile in the presence of point vortices",
AIAA J. 33(4), 1995; Streitlien, PhD thesis, MIT 1994, Ch. 2-3; Milne-Thomson, Theoretical Hydrodynamics,
Sec. 6.21 (circle theorem) and 13.3 (Routh's rule); Saffman, Vortex Dynamics (1992), Sec. 3.2 (impulse).

Notation (foil frame of ``joukowski.py``: origin at the map origin, x along the chord toward the leading edge):

* Map (paper eq. 1): ``z = F(zeta) = s + a^2/s``, ``s = zeta + zeta_c``, exterior of ``|zeta| = r`` (``r = r_c``)
  onto the exterior of the foil. ``F'(zeta) = 1 - a^2/s^2``, ``F''(zeta) = 2 a^2/s^3``. The trailing edge (cusp,
  ``F' = 0``) is ``zeta_TE = -r``, ``z_TE = -2a``. Inverse: ``s = (z +- sqrt(z^2 - 4a^2))/2``, the root with
  ``|s| >= a`` (the other root lies inside the circle).
* Complex potential ``w = phi + i psi`` of the absolute fluid velocity, written in foil-frame coordinates:
  ``dw/dz = u - i v`` (u, v along the foil axes). Circulation Gamma counter-clockwise positive.
* Foil motion ``nu = (U, V, Omega)``: velocity of the frame origin along the foil axes, ``u_b = U + iV``, and the
  angular rate (the U, V, Omega of paper eq. 40).

Potential (Kelvin: the circulation of the whole flow is zero, so the bound circulation ``-sum Gamma_k`` is
carried by the images alone and no vortex sits at the circle's centre)::

    w(zeta) = w_body(zeta) + sum_k Gamma_k/(2 pi i) [log(zeta - zeta_k) - log(zeta - zeta_k*)],
    zeta_k* = r^2 / conj(zeta_k)                                  (image by the circle theorem)
    w_body  = -u_b r^2/zeta + conj(u_b) a^2/s - i Omega (A/zeta + B/s),
    A = r^2 F(0),   B = a^2 F(-r^2/zeta_c).

``w_body`` satisfies the body's kinematic condition ``psi = Im(conj(u_b) z) - Omega |z|^2/2`` on
``|zeta| = r``: the translation part directly (``Im(conj(u_b) zeta) = Im(-u_b r^2/zeta)`` on the circle); the
rotation part because ``|z|^2 = G(zeta) = F(zeta) F(r^2/zeta)`` there, and ``G``'s principal parts at its poles
inside the circle (``zeta = 0`` with residue A, ``zeta = -zeta_c`` with residue B) give ``G = 2 Re(A/zeta +
B/s) + const`` on the circle. (A symmetric Joukowski foil has ``zeta_c > 0``; the two poles merge for the
ellipse ``zeta_c = 0``, which this module does not handle.)

Velocity of free vortex j (Routh's rule, the self-induced term a point vortex has in a mapped plane)::

    conj(u_j) = W_j'(zeta_j) / F'(zeta_j) - Gamma_j F''(zeta_j) / (4 pi i F'(zeta_j)^2),

``W_j'`` being ``dw/dzeta`` without vortex j's own singular term (its image kept). Vortex-vortex terms use a
Krasny (1986) blob, ``1/Delta -> conj(Delta)/(|Delta|^2 + delta_k^2)``, with the physical core radius delta
scaled to the circle plane by ``delta_k = delta/|F'(zeta_k)|``; the image and body terms stay exact so that the
foil stays impermeable.

Kutta condition at the cusp: ``dw/dzeta(zeta_TE) = 0``. Its real part (normal velocity in the circle plane,
``|F'|`` times the foil's normal velocity) vanishes identically at the cusp; the imaginary part (tangential) fixes
the strength of the vortex shed in the step, linearly.

Force and moment (impulse, Saffman Sec. 3.2; Streitlien & Triantafyllou 1995). The flow's total impulse, with
the foil's interior counted as fluid moving rigidly, is ``I_tot = -2 pi rho A_1`` where A_1 is the ``1/z``
coefficient of w at infinity; it splits into the ideal-flow part of the foil's motion and a vortical part::

    I_tot = [M_A nu]_translation + rho S u_centroid + I_v,     I_v = -i rho sum_k Gamma_k (zeta_k - zeta_k*).

The first term is the Kirchhoff impulse of added_mass.py (``-2 pi rho A_1`` of ``w_body``: ``m11 + rho S =
2 pi rho (r^2 - a^2)``, ``m22 + rho S = 2 pi rho (r^2 + a^2)``; tested), the second the interior fluid's
momentum, which cancels in ``F = -dI_tot/dt + rho S du_centroid/dt``. So the force on the foil is exactly

    F = F_Kirchhoff(M_A, nu, nu_dot)  [the ideal-flow model, already in swim_model]  +  F_v,   F_v = -dI_v/dt,

the time derivative taken in the inertial frame (``I_v`` rotates with the foil). Likewise the angular impulse
about the frame origin, ``L = -(rho/2) int |z|^2 omega dA`` over the free vortices and the vortex sheet that
the vortices induce on the foil (sheet strength ``dphi_v`` along the contour), is, by residues inside the circle::

    L_v = -(rho/2) sum_k Gamma_k [ |z_k|^2 + Re( -F(zeta_k*) conj(z_k) + A (1/zeta_k* - 1/zeta_k)
                                                 + B (1/(zeta_k* + zeta_c) - 1/(zeta_k + zeta_c)) ) ],

and the vortical moment about the frame origin ``X_0`` is ``M_v = -dL_v/dt - Xdot_0 x I_v`` (the second term
because the reference point moves; Kirchhoff's ``-u x P`` for the vortical impulse). Everything else --
the added-mass force and moment, including Munk's moment -- is the ideal-flow model's and is not counted here.
For a steady Kutta flow this split puts the circulatory lift ``rho U Gamma`` at ``x = zeta_c`` (tested).
"""
from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from swim_model.errors import FoilGeometryError
from swim_model.joukowski import JoukowskiMap

Complex = npt.NDArray[np.complex128]

MIN_OFFSET_RATIO = 1e-6  # zeta_c / a below this: the rotation potential's two poles merge (an ellipse); refused


class CirclePlane:
    """The Joukowski map of one foil and the closed forms of this module's docstring evaluated on it."""

    def __init__(self, conformal_map: JoukowskiMap) -> None:
        if conformal_map.zeta_c_m < MIN_OFFSET_RATIO * conformal_map.a_m:
            raise FoilGeometryError("the vortex wake needs a Joukowski foil with zeta_c > 0 (not an ellipse map)")
        self.map = conformal_map
        self.a_m = conformal_map.a_m
        self.zeta_c_m = conformal_map.zeta_c_m
        self.r_m = conformal_map.r_c_m
        self.zeta_te = complex(-self.r_m)
        self.z_te = complex(-2.0 * self.a_m)
        a2, r2, zc = self.a_m ** 2, self.r_m ** 2, self.zeta_c_m
        self.rotation_pole_origin_m3 = r2 * (zc + a2 / zc)                       # A = r^2 F(0)
        far = -r2 / zc + zc
        self.rotation_pole_offset_m3 = a2 * (far + a2 / far)                     # B = a^2 F(-r^2/zeta_c)

    # --- the map ------------------------------------------------------------------------------------------
    def to_foil(self, zeta: Complex) -> Complex:
        """z = F(zeta)."""
        s = zeta + self.zeta_c_m
        return s + self.a_m ** 2 / s

    def map_derivatives(self, zeta: Complex) -> tuple[Complex, Complex]:
        """(F'(zeta), F''(zeta))."""
        s = zeta + self.zeta_c_m
        a2_over_s2 = self.a_m ** 2 / (s * s)
        return 1.0 - a2_over_s2, 2.0 * a2_over_s2 / s

    def to_circle(self, z: Complex) -> Complex:
        """zeta = F^{-1}(z), the branch outside the circle (``|s| >= a``)."""
        root: Complex = np.sqrt(z * z - 4.0 * self.a_m ** 2)
        s_plus, s_minus = 0.5 * (z + root), 0.5 * (z - root)
        s: Complex = np.where(np.abs(s_plus) >= np.abs(s_minus), s_plus, s_minus)
        return s - self.zeta_c_m

    def image(self, zeta: Complex) -> Complex:
        """zeta* = r^2 / conj(zeta) (circle theorem)."""
        conjugate: Complex = np.conj(zeta)
        return self.r_m ** 2 / conjugate

    # --- flow -----------------------------------------------------------------------------------------------
    def body_potential_derivative(self, zeta: Complex, velocity: tuple[float, float, float]) -> Complex:
        """d w_body / d zeta = u_b r^2/zeta^2 - conj(u_b) a^2/s^2 + i Omega (A/zeta^2 + B/s^2)."""
        u_b = complex(velocity[0], velocity[1])
        omega = velocity[2]
        s = zeta + self.zeta_c_m
        inv_zeta2, inv_s2 = 1.0 / (zeta * zeta), 1.0 / (s * s)
        return (u_b * self.r_m ** 2 * inv_zeta2 - u_b.conjugate() * self.a_m ** 2 * inv_s2
                + 1j * omega * (self.rotation_pole_origin_m3 * inv_zeta2 + self.rotation_pole_offset_m3 * inv_s2))

    def body_dipole(self, velocity: tuple[float, float, float]) -> complex:
        """A_1 of w_body at infinity: -u_b r^2 + conj(u_b) a^2 - i Omega (A + B), m^3/s."""
        u_b = complex(velocity[0], velocity[1])
        return (-u_b * self.r_m ** 2 + u_b.conjugate() * self.a_m ** 2
                - 1j * velocity[2] * (self.rotation_pole_origin_m3 + self.rotation_pole_offset_m3))

    def vortex_potential_derivative(self, zeta: Complex, zeta_k: Complex, gamma_k: npt.NDArray[np.float64]) -> Complex:
        """sum_k Gamma_k/(2 pi i) [1/(zeta - zeta_k) - 1/(zeta - zeta_k*)], exact kernel, at points zeta."""
        zeta = np.atleast_1d(zeta)
        if zeta_k.size == 0:
            return np.zeros(zeta.shape, dtype=complex)
        images = self.image(zeta_k)
        kernel: Complex = 1.0 / (zeta[:, None] - zeta_k[None, :]) - 1.0 / (zeta[:, None] - images[None, :])
        # a sum, not kernel @ gamma_k: the complex-by-real product goes to multi-threaded BLAS, which on a loaded
        # machine spin-waits for its threads (measured 9 ms instead of 0.2 ms for 64 points and 300 vortices)
        total: Complex = (kernel * gamma_k[None, :]).sum(axis=1)
        return total / (2j * math.pi)

    def vortex_velocities(self, zeta_k: Complex, gamma_k: npt.NDArray[np.float64],
                          velocity: tuple[float, float, float], core_radius_m: float) -> Complex:
        """Fluid velocity u + iv (foil axes) at each free vortex: blob mutual terms, exact images, Routh term."""
        n = zeta_k.size
        if n == 0:
            return np.zeros(0, dtype=complex)
        d1, d2 = self.map_derivatives(zeta_k)
        core_zeta2 = (core_radius_m / np.maximum(np.abs(d1), 1e-12)) ** 2
        # real arithmetic on N x N arrays (the cost of a step): sum_k Gamma_k conj(D)/(|D|^2 + delta_k^2);
        # the diagonal (D = 0) contributes nothing, so a vortex's own blob term drops out by itself
        dx = zeta_k.real[:, None] - zeta_k.real[None, :]
        dy = zeta_k.imag[:, None] - zeta_k.imag[None, :]
        weight = gamma_k / (dx * dx + dy * dy + core_zeta2[None, :])
        mutual = (weight * dx).sum(axis=1) - 1j * (weight * dy).sum(axis=1)
        images = self.image(zeta_k)
        dx = zeta_k.real[:, None] - images.real[None, :]
        dy = zeta_k.imag[:, None] - images.imag[None, :]
        weight = gamma_k / (dx * dx + dy * dy)
        mutual -= (weight * dx).sum(axis=1) - 1j * (weight * dy).sum(axis=1)
        dw_dzeta = mutual / (2j * math.pi) + self.body_potential_derivative(zeta_k, velocity)
        conj_u: Complex = dw_dzeta / d1 - gamma_k * d2 / (4j * math.pi * d1 * d1)
        return np.conj(conj_u)

    def kutta_strength(self, zeta_new: complex, zeta_k: Complex, gamma_k: npt.NDArray[np.float64],
                       velocity: tuple[float, float, float]) -> float:
        """Strength of a vortex at zeta_new that makes Im(dw/dzeta) vanish at the trailing edge."""
        te = np.array([self.zeta_te])
        known = self.body_potential_derivative(te, velocity)[0] + self.vortex_potential_derivative(
            te, zeta_k, gamma_k)[0]
        unit = self.vortex_potential_derivative(te, np.array([zeta_new]), np.ones(1))[0]
        return float(-known.imag / unit.imag)

    def far_field_circulation(self, zeta_k: Complex, gamma_k: npt.NDArray[np.float64],
                              velocity: tuple[float, float, float], samples: int = 256) -> float:
        """Re of the contour integral of dw/dzeta on a circle enclosing every vortex: the flow's total circulation.

        The integrand is analytic outside all vortices, so the trapezoidal rule converges geometrically on a
        circle twice as large as the farthest vortex.
        """
        radius = 2.0 * max(self.r_m, float(np.max(np.abs(zeta_k))) if zeta_k.size else 0.0)
        zeta = radius * np.exp(2j * math.pi * np.arange(samples) / samples)
        dw = self.body_potential_derivative(zeta, velocity) + self.vortex_potential_derivative(zeta, zeta_k, gamma_k)
        return float(np.real(np.sum(dw * 1j * zeta) * 2.0 * math.pi / samples))

    # --- impulse ----------------------------------------------------------------------------------------------
    def vortex_impulse(self, zeta_k: Complex, gamma_k: npt.NDArray[np.float64], rho_kg_m3: float) -> complex:
        """I_v = -i rho sum_k Gamma_k (zeta_k - zeta_k*), foil axes, kg/s per metre of span."""
        return complex(-1j * rho_kg_m3 * np.sum(gamma_k * (zeta_k - self.image(zeta_k))))

    def vortex_angular_impulse(self, zeta_k: Complex, gamma_k: npt.NDArray[np.float64], rho_kg_m3: float) -> float:
        """L_v about the frame origin (module docstring), kg m/s per metre of span."""
        if zeta_k.size == 0:
            return 0.0
        images = self.image(zeta_k)
        z_k = self.to_foil(zeta_k)
        zc = self.zeta_c_m
        sheet = (-self.to_foil(images) * np.conj(z_k)
                 + self.rotation_pole_origin_m3 * (1.0 / images - 1.0 / zeta_k)
                 + self.rotation_pole_offset_m3 * (1.0 / (images + zc) - 1.0 / (zeta_k + zc)))
        return float(-0.5 * rho_kg_m3 * np.sum(gamma_k * (np.abs(z_k) ** 2 + sheet.real)))


def steady_kutta_circulation(plane: CirclePlane, speed_m_s: float, angle_of_attack_rad: float) -> float:
    """Gamma = 4 pi r U sin(alpha): the steady Kutta circulation of the foil moving at U, angle of attack alpha.

    Relative stream ``W = -u_b`` past the circle: ``dw/dzeta = conj(W) - W r^2/zeta^2 + Gamma/(2 pi i zeta)``
    vanishes at ``zeta = -r`` when ``Gamma = 4 pi r Im(W)``; with ``u_b = U e^{-i alpha}``, ``Im W = U sin alpha``.
    The lift is ``rho U Gamma`` (Kutta-Joukowski); r = c/4 (flat plate) gives ``pi rho c U^2 sin alpha``.
    """
    return 4.0 * math.pi * plane.r_m * speed_m_s * math.sin(angle_of_attack_rad)
