"""Added mass of a 2-D body in potential flow from its conformal map (paper Appendix A.1, eqs. 41-43).

The body moves with velocity (U, V) of a reference point (the origin of the body frame z = x + iy)
and angular velocity Omega, in fluid at rest at infinity. The fluid's kinetic energy is
``T_f = 1/2 nu' M_A nu`` with ``nu = (U, V, Omega)`` (eq. 41's second term, per unit span).

With complex potentials ``w_j = phi_j + i psi_j`` of the unit motions (``dw/dz = u - i v``),
the kinematic boundary condition fixes the stream functions on the body (up to constants):

    psi_1 = y,   psi_2 = -x,   psi_3 = -(x^2 + y^2) / 2,

and Green's identity (the area theorem of eqs. 42-43) gives ``M_A[i, j] = -rho oint phi_i dpsi_j``,
counter-clockwise around the body.

A conformal map ``z = F(zeta)`` from the exterior of the circle ``|zeta| = r_c`` carries the
potentials over unchanged, so the problem is solved on the circle. There, with the Fourier series
``psi_j(vartheta) = sum_m psihat_{j,m} e^{i m vartheta}``, the decaying exterior potential has
``phihat_{j,m} = -i sign(m) psihat_{j,m}`` (a Hilbert transform), and Parseval turns the contour
integral into

    M_A[i, j] = 4 pi rho sum_{m >= 1} m Re(psihat_{i,m} conj(psihat_{j,m})).

Every function involved is analytic in an annulus around the circle, so the sampled Fourier
coefficients converge geometrically; 1024 samples reach round-off for the foils of this rig.
References: Milne-Thomson, Theoretical Hydrodynamics (1968), Ch. IX; Streitlien (1994), Ch. 2.
"""
from __future__ import annotations

from typing import Callable

import numpy as np
import numpy.typing as npt

ComplexMap = Callable[[npt.NDArray[np.complex128]], npt.NDArray[np.complex128]]


def body_stream_functions(z_body: npt.NDArray[np.complex128]) -> npt.NDArray[np.float64]:
    """Stream functions (psi_1, psi_2, psi_3) of unit surge, sway and yaw on the body points z.

    Parameters
    ----------
    z_body : (n,) ndarray of complex
        Body points x + iy, m.

    Returns
    -------
    (3, n) ndarray
        psi_1 and psi_2 in m, psi_3 in m^2 (per unit velocity and rate).
    """
    x, y = z_body.real, z_body.imag
    return np.stack([y, -x, -(x * x + y * y) / 2.0])


def added_mass_from_circle_map(conformal_map: ComplexMap, circle_radius: float, density_kg_m3: float,
                               samples: int = 1024) -> npt.NDArray[np.float64]:
    """Added-mass matrix (per unit span) of the body ``F(|zeta| = circle_radius)``.

    Parameters
    ----------
    conformal_map : callable
        F, vectorised over complex arrays, analytic outside the circle.
    circle_radius : float
        r_c of the circle in the zeta plane, m.
    density_kg_m3 : float
        Fluid density rho, kg/m^3.
    samples : int, optional
        Points on the circle (even); the result converges geometrically in it.

    Returns
    -------
    (3, 3) ndarray
        M_A with rows/columns (U, V, Omega): kg/m, kg/m, kg m/m (= kg), kg m^2/m.
    """
    angle = 2.0 * np.pi * np.arange(samples) / samples
    z_body = conformal_map(circle_radius * np.exp(1j * angle))
    psi_hat = np.fft.fft(body_stream_functions(z_body), axis=1) / samples
    harmonic = np.arange(1, samples // 2)
    positive = psi_hat[:, 1:samples // 2]
    gram = (positive * harmonic) @ positive.conj().T
    return 4.0 * np.pi * density_kg_m3 * gram.real
