"""The paper's own primitive method, for reproduction and comparison (Sec. 5, SPEC.md section 3).

Cruise: the foil motion is a Fourier series with the cycle's period T,

    phi(t)   = a_0 + sum_{k=1..K} (a_k cos(k w t) + b_k sin(k w t)),   w = 2 pi / T
    theta(t) = c_0 + sum_{k=1..K} (c_k cos(k w t) + d_k sin(k w t)),

so psi, psidot and psiddot are analytic. With p_alpha = 0 (reachable from rest) the constrained vehicle's
alphadot follows from the shape velocity alone (alphadot = -Mm11^-1 Mm12 psidot, eq. 14 integrated once),
the torques from eq. 15, and the index of eq. 10 is evaluated on a fine grid. The coefficients are found by
Nelder-Mead (MATLAB's fminsearch, the 'fmin' of the paper), with the cycle-mean kinetic energy E and the
torque limits as quadratic penalties, since that method takes no constraints.
"""
from __future__ import annotations

import dataclasses
import math
import time

import casadi as ca
import numpy as np
import numpy.typing as npt
from scipy import optimize

from swim_model import VehicleModel
from swim_planner.primitives import PlanningLimits, PrimitiveSpec, PrimitiveType

Array = npt.NDArray[np.float64]
PENALTY = 1e5   # weight of the squared constraint violations (assumed: 1 mJ of energy error costs 0.1 in J)


@dataclasses.dataclass(frozen=True)
class FourierCruise:
    coefficients: Array        # (2, 2K + 1): rows phi, theta; columns a_0, a_1, b_1, ..., a_K, b_K
    index_j: float             # alpha(T) - effort over one cycle (eq. 10)
    energy_error_j: float      # mean kinetic energy - E
    max_torque_fraction: float # largest |tau| / limit
    evaluations: int
    wall_s: float


def fourier_shape(coefficients: Array, period_s: float, times: Array) -> tuple[Array, Array, Array]:
    """psi, psidot, psiddot (each (n, 2)) of the series at the given times."""
    harmonics = (coefficients.shape[1] - 1) // 2
    w = 2.0 * math.pi / period_s
    psi = np.tile(coefficients[:, 0], (len(times), 1))
    psidot, psiddot = np.zeros_like(psi), np.zeros_like(psi)
    for k in range(1, harmonics + 1):
        cos_k, sin_k = np.cos(k * w * times)[:, None], np.sin(k * w * times)[:, None]
        a, b = coefficients[:, 2 * k - 1], coefficients[:, 2 * k]
        psi += a * cos_k + b * sin_k
        psidot += k * w * (-a * sin_k + b * cos_k)
        psiddot += -(k * w) ** 2 * (a * cos_k + b * sin_k)
    return psi, psidot, psiddot


class _CruiseObjective:
    """Index, energy and torques of a Fourier cruise of the constrained vehicle, evaluated in one call."""

    def __init__(self, model: VehicleModel, spec: PrimitiveSpec, samples: int) -> None:
        if not model.constrained:
            raise ValueError("the paper's Fourier cruise is implemented for the constrained vehicle")
        s = model.symbolic
        mass = s.functions["mass_matrix"](s.q)
        alpha_rate = -(mass[0, 1:] @ s.qdot[1:]) / mass[0, 0]       # p_alpha = 0
        qdot = ca.vertcat(alpha_rate, s.qdot[1:])
        qddot_y, tau = s.functions["shape_dynamics"](s.q, qdot, s.u)
        energy = s.functions["kinetic_energy"](s.q, qdot)
        point = ca.Function("point", [s.q, s.qdot, s.u], [alpha_rate, tau, energy])
        self.batch = point.map(samples)
        self.model, self.spec, self.samples = model, spec, samples
        self.period = spec.solved_duration_s
        self.times = np.linspace(0.0, self.period, samples, endpoint=False)
        self.step = self.period / samples
        self.weights = np.array([spec.heave_effort_weight, spec.pitch_effort_weight])

    def evaluate(self, coefficients: Array) -> tuple[float, float, Array]:
        psi, psidot, psiddot = fourier_shape(coefficients, self.period, self.times)
        q = np.vstack([np.zeros(self.samples), psi.T])   # alpha does not enter (Prop. 1)
        qdot = np.vstack([np.zeros(self.samples), psidot.T])
        alpha_rate, tau, energy = (np.asarray(v) for v in self.batch(q, qdot, psiddot.T))
        advance = float(alpha_rate.sum() * self.step)      # periodic: the rectangle rule is spectral
        effort = float((self.weights[:, None] * tau ** 2).sum() * self.step)
        return advance - effort, float(energy.mean()), tau


def solve_fourier_cruise(model: VehicleModel, spec: PrimitiveSpec, limits: PlanningLimits = PlanningLimits(),
                         harmonics: int = 2, samples: int = 200, max_evaluations: int = 20000) -> FourierCruise:
    """The paper's cruise: Fourier coefficients by Nelder-Mead from a 90-deg-lead stroke."""
    if spec.primitive_type is not PrimitiveType.CRUISE:
        raise ValueError("solve_fourier_cruise solves cruises")
    objective = _CruiseObjective(model, spec, samples)
    tau_max = limits.torque_fraction * model.torque_limits()
    ranges = np.array([limits.heave_range_rad, limits.pitch_range_rad])
    start = np.zeros((2, 2 * harmonics + 1))
    start[0, 2], start[1, 1] = 0.3, 0.5          # phi = 0.3 sin(w t), theta = 0.5 cos(w t): pitch leads

    def cost(flat: Array) -> float:
        coefficients = flat.reshape(2, -1)
        index, energy, tau = objective.evaluate(coefficients)
        psi, _, _ = fourier_shape(coefficients, objective.period, objective.times)
        excess = np.maximum(np.abs(tau) / tau_max[:, None] - 1.0, 0.0).sum()
        out_of_range = np.maximum(np.abs(psi) / ranges - 1.0, 0.0).sum()
        return -index + PENALTY * ((energy - spec.energy_j) ** 2 + excess ** 2 + out_of_range ** 2)

    started = time.perf_counter()
    result = optimize.minimize(cost, start.ravel(), method="Nelder-Mead",
                               options={"maxfev": max_evaluations, "xatol": 1e-8, "fatol": 1e-10,
                                        "adaptive": True})
    coefficients = result.x.reshape(2, -1)
    index, energy, tau = objective.evaluate(coefficients)
    return FourierCruise(coefficients=coefficients, index_j=index, energy_error_j=energy - spec.energy_j,
                         max_torque_fraction=float((np.abs(tau) / model.torque_limits()[:, None]).max()),
                         evaluations=int(result.nfev), wall_s=time.perf_counter() - started)
