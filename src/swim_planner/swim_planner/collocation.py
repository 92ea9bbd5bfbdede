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

    def all_states(self) -> ca.MX:
        """States on the fine grid (knots and midpoints interleaved), 2N + 1 columns."""
        return _interleave(self.x, self.x_mid)

    def all_inputs(self) -> ca.MX:
        return _interleave(self.u, self.u_mid)


def _interleave(knots: ca.MX, mids: ca.MX) -> ca.MX:
    columns = []
    for k in range(mids.shape[1]):
        columns += [knots[:, k], mids[:, k]]
    columns.append(knots[:, -1])
    return ca.horzcat(*columns)


def hermite_simpson(opti: ca.Opti, dynamics: ca.Function, nx: int, nu: int, intervals: int,
                    duration_s: float) -> Transcription:
    """Add the grid variables and the collocation constraints of ``xdot = dynamics(x, u)``."""
    x = opti.variable(nx, intervals + 1)
    u = opti.variable(nu, intervals + 1)
    x_mid = opti.variable(nx, intervals)
    u_mid = opti.variable(nu, intervals)
    h = duration_s / intervals
    f_knots = dynamics.map(intervals + 1)(x, u)
    f_mid = dynamics.map(intervals)(x_mid, u_mid)
    f_start, f_end = f_knots[:, :-1], f_knots[:, 1:]
    opti.subject_to(x_mid == 0.5 * (x[:, :-1] + x[:, 1:]) + h / 8.0 * (f_start - f_end))
    opti.subject_to(x[:, 1:] - x[:, :-1] == h / 6.0 * (f_start + 4.0 * f_mid + f_end))
    return Transcription(opti=opti, x=x, u=u, x_mid=x_mid, u_mid=u_mid, step_s=h)


def simpson_integral(transcription: Transcription, integrand: ca.Function) -> ca.MX:
    """Integral over [0, T] of integrand(x, u) by Simpson's rule on each interval."""
    n = transcription.x_mid.shape[1]
    at_knots = integrand.map(n + 1)(transcription.x, transcription.u)
    at_mid = integrand.map(n)(transcription.x_mid, transcription.u_mid)
    return transcription.step_s / 6.0 * (ca.sum2(at_knots[:, :-1]) + 4.0 * ca.sum2(at_mid) + ca.sum2(at_knots[:, 1:]))


def fine_grid_times(duration_s: float, intervals: int) -> Array:
    """Times of the fine grid (knots and midpoints), 2N + 1 samples."""
    return np.linspace(0.0, duration_s, 2 * intervals + 1)
