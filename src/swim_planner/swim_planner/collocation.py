"""Direct collocation (Hermite-Simpson, separated form) of an optimal control problem.

For xdot = f(x, u) on [0, T] with N equal intervals of length h = T/N, the decision variables are
the states and inputs at the N + 1 knots and at the N interval midpoints. Each interval imposes

    x_m = (x_k + x_{k+1}) / 2 + h/8 (f_k - f_{k+1})            (Hermite interpolation)
    x_{k+1} - x_k = h/6 (f_k + 4 f_m + f_{k+1})               (Simpson quadrature)

and integral costs use Simpson's rule, so states are fourth-order accurate in h.
Reference: Betts, Practical Methods for Optimal Control (2010), Sec. 4.6; Kelly, SIAM Review 59(4), 2017.
"""
from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]


@dataclasses.dataclass
class Transcription:
    """The NLP's variables on the grid: knots (columns 0..N) and midpoints (columns 0..N-1)."""

    opti: ca.Opti
    x: ca.MX
    u: ca.MX
    x_mid: ca.MX
    u_mid: ca.MX
    step_s: float

    @property
    def intervals(self) -> int:
        """The number of collocation intervals N."""
        return self.x_mid.shape[1]

    def all_states(self) -> ca.MX:
        """States on the fine grid (knots and midpoints interleaved), 2N + 1 columns."""
        return _interleave(self.x, self.x_mid)

    def all_inputs(self) -> ca.MX:
        """Inputs on the fine grid (knots and midpoints interleaved), 2N + 1 columns."""
        return _interleave(self.u, self.u_mid)

    def variables(self) -> ca.MX:
        """All the grid's variables in one column."""
        return ca.vertcat(*(ca.vec(v) for v in (self.x, self.u, self.x_mid, self.u_mid)))

    def points(self) -> ca.MX:
        """(x; u) at the knots, then at the midpoints.

        The 2N + 1 points where a pointwise function is evaluated (``knots`` and ``midpoints`` split its values).
        """
        return ca.horzcat(ca.vertcat(self.x, self.u), ca.vertcat(self.x_mid, self.u_mid))

    def knots(self, values: ca.MX) -> ca.MX:
        """The columns of values over ``points`` that belong to the knots."""
        return values[:, :self.intervals + 1]

    def midpoints(self, values: ca.MX) -> ca.MX:
        """The columns of values over ``points`` that belong to the midpoints."""
        return values[:, self.intervals + 1:]

    def fine(self, values: ca.MX) -> ca.MX:
        """Values over ``points`` in the fine grid's order (knots and midpoints interleaved)."""
        return _interleave(self.knots(values), self.midpoints(values))


def _interleave(knots: ca.MX, mids: ca.MX) -> ca.MX:
    columns = []
    for k in range(mids.shape[1]):
        columns += [knots[:, k], mids[:, k]]
    columns.append(knots[:, -1])
    return ca.horzcat(*columns)


def collocation_grid(opti: ca.Opti, nx: int, nu: int, intervals: int, duration_s: float) -> Transcription:
    """The grid's variables: states and inputs at the N + 1 knots and the N midpoints."""
    return Transcription(opti=opti, x=opti.variable(nx, intervals + 1), u=opti.variable(nu, intervals + 1),
                         x_mid=opti.variable(nx, intervals), u_mid=opti.variable(nu, intervals),
                         step_s=duration_s / intervals)


def hermite_simpson(grid: Transcription, state_derivative: ca.MX) -> None:
    """Add the collocation constraints of xdot = f(x, u), given f's values over ``grid.points()``."""
    x, h = grid.x, grid.step_s
    f_knots, f_mid = grid.knots(state_derivative), grid.midpoints(state_derivative)
    f_start, f_end = f_knots[:, :-1], f_knots[:, 1:]
    grid.opti.subject_to(grid.x_mid == 0.5 * (x[:, :-1] + x[:, 1:]) + h / 8.0 * (f_start - f_end))
    grid.opti.subject_to(x[:, 1:] - x[:, :-1] == h / 6.0 * (f_start + 4.0 * f_mid + f_end))


def simpson_integral(grid: Transcription, integrand: ca.MX) -> ca.MX:
    """Integral over [0, T] by Simpson's rule on each interval.

    The integrand is given over ``grid.points()`` (a row; several rows give several integrals).
    """
    at_knots, at_mid = grid.knots(integrand), grid.midpoints(integrand)
    return grid.step_s / 6.0 * (ca.sum2(at_knots[:, :-1]) + 4.0 * ca.sum2(at_mid) + ca.sum2(at_knots[:, 1:]))


def fine_grid_times(duration_s: float, intervals: int) -> Array:
    """Times of the fine grid (knots and midpoints), 2N + 1 samples."""
    return np.linspace(0.0, duration_s, 2 * intervals + 1)
