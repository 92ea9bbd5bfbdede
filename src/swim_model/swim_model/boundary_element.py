"""Added mass of a 2-D body by a boundary-element solution in the physical plane.

An independent check of :mod:`swim_model.added_mass`: it uses no conformal map, only the body's
polygon. For each unit motion j the exterior Neumann problem ``Laplace(phi_j) = 0``,
``d phi_j / dn = n_j`` on the body (n out of the body into the fluid; n_1 = n_x, n_2 = n_y,
n_3 = x n_y - y n_x), ``phi_j -> 0`` at infinity, is solved from Green's third identity on the
boundary,

    1/2 phi(x) = oint [ G(x, y) dphi/dn(y) - phi(y) dG/dn_y(x, y) ] ds_y,   G = ln|x - y| / (2 pi),

with straight panels, phi and dphi/dn constant on each, collocation at panel midpoints, and the
panel integrals of G and dG/dn in closed form. Then ``M_A[i, j] = -rho oint phi_i n_j ds``.
Convergence is first order in the panel length near the cusp; 1500 panels give about 0.1 %.
"""
from __future__ import annotations

import numpy as np
import numpy.typing as npt


def _panel_integrals(mid: npt.NDArray[np.float64], start: npt.NDArray[np.float64],
                     tangent: npt.NDArray[np.float64], normal: npt.NDArray[np.float64],
                     length: npt.NDArray[np.float64]) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Integrals over panel j, seen from midpoint i, of G (single layer) and dG/dn_y (double layer)."""
    offset = mid[:, None, :] - start[None, :, :]
    xi = np.einsum("ijk,jk->ij", offset, tangent)
    eta = np.einsum("ijk,jk->ij", offset, normal)
    # points on a panel's own line (its own midpoint, up to round-off) see no double layer from it
    on_line = (np.abs(eta) < 1e-10 * length[None, :]) | np.eye(len(mid), dtype=bool)
    eta_safe = np.where(on_line, 1.0, eta)
    upper, lower = length[None, :] - xi, -xi

    def log_antiderivative(u: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        # integral of ln(u^2 + eta^2) du, with the eta -> 0 limit u ln u^2 - 2u
        r2 = u * u + eta * eta
        u_log = np.where(r2 > 0.0, u * np.log(np.where(r2 > 0.0, r2, 1.0)), 0.0)
        angle = np.where(on_line, 0.0, 2.0 * eta * np.arctan(u / eta_safe))
        return u_log - 2.0 * u + angle

    single = (log_antiderivative(upper) - log_antiderivative(lower)) / (4.0 * np.pi)
    # dG/dn_y = (y - x).n_y / (2 pi |y - x|^2) = -eta / (2 pi ((s - xi)^2 + eta^2))
    subtended = np.arctan(upper / eta_safe) - np.arctan(lower / eta_safe)
    double = np.where(on_line, 0.0, -subtended / (2.0 * np.pi))
    return single, double


def added_mass_from_polygon(z_nodes: npt.NDArray[np.complex128], density_kg_m3: float) -> npt.NDArray[np.float64]:
    """Added-mass matrix (per unit span) about z = 0 of a closed polygon, by boundary elements.

    Parameters
    ----------
    z_nodes : (n,) ndarray of complex
        Polygon vertices x + iy, m, counter-clockwise, not repeating the first.
    density_kg_m3 : float
        Fluid density rho, kg/m^3.

    Returns
    -------
    (3, 3) ndarray
        M_A with rows/columns (U, V, Omega): kg/m, kg/m, kg, kg m^2/m.
    """
    nodes = np.column_stack([z_nodes.real, z_nodes.imag])
    start, end = nodes, np.roll(nodes, -1, axis=0)
    chord = end - start
    length = np.hypot(chord[:, 0], chord[:, 1])
    tangent = chord / length[:, None]
    normal = np.column_stack([tangent[:, 1], -tangent[:, 0]])  # counter-clockwise: outward is t rotated -90 deg
    mid = 0.5 * (start + end)
    single, double = _panel_integrals(mid, start, tangent, normal, length)
    flux = np.column_stack([normal[:, 0], normal[:, 1],
                            mid[:, 0] * normal[:, 1] - mid[:, 1] * normal[:, 0]])
    potential = np.linalg.solve(0.5 * np.eye(len(mid)) + double, single @ flux)
    matrix = -density_kg_m3 * (potential * length[:, None]).T @ flux
    return 0.5 * (matrix + matrix.T)
