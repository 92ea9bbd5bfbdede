"""The paper's own primitive method, for reproduction and comparison (Sec. 5, docs/model_and_method.md section 3).

Accelerate (eq. 11): phi = A1(t) sin(A2(t)), theta = B1(t) sin(B2(t)) with A1, A2, B1, B2 polynomials
in t, all 18 coefficients at once (the paper found this "did not converge" with MATLAB's fmin and split
the 4 s into two 2 s segments of 9). The boundary conditions (rest at t = 0, the cruise's start state at
Tf) become penalties, as for the cruise.

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
from typing import Optional, cast

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
    """A cruise by the paper's method: a Fourier series per shape angle, its index, energy error and cost."""

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


def shape_driven_batch(model: VehicleModel, samples: int) -> ca.Function:
    """(q, psidot rows of qdot, u) at many samples -> (alphadot, tau, T) with p_alpha = 0 (constrained)."""
    if not model.constrained:
        raise ValueError("the paper's parameterizations are implemented for the constrained vehicle")
    s = model.symbolic
    mass = s.functions["mass_matrix"](s.q)
    alpha_rate = -(mass[0, 1:] @ s.qdot[1:]) / mass[0, 0]       # p_alpha = 0
    qdot = ca.vertcat(alpha_rate, s.qdot[1:])
    _, tau = s.functions["shape_dynamics"](s.q, qdot, s.u)
    energy = s.functions["kinetic_energy"](s.q, qdot)
    return ca.Function("point", [s.q, s.qdot, s.u], [alpha_rate, tau, energy]).map(samples)


class _CruiseObjective:
    """Index, energy and torques of a Fourier cruise of the constrained vehicle, evaluated in one call."""

    def __init__(self, model: VehicleModel, spec: PrimitiveSpec, samples: int) -> None:
        self.batch = shape_driven_batch(model, samples)
        self.samples = samples
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


def solve_fourier_cruise(model: VehicleModel, spec: PrimitiveSpec, limits: Optional[PlanningLimits] = None,
                         harmonics: int = 2, samples: int = 200, max_evaluations: int = 20000) -> FourierCruise:
    """The paper's cruise: Fourier coefficients by Nelder-Mead from a 90-deg-lead stroke."""
    if spec.primitive_type is not PrimitiveType.CRUISE:
        raise ValueError("solve_fourier_cruise solves cruises")
    energy_j = spec.energy_j
    if energy_j is None:
        raise ValueError(f"{spec.primitive_id}: a cruise needs energy_j")
    objective = _CruiseObjective(model, spec, samples)
    limits = PlanningLimits.of(model.rig) if limits is None else limits
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
        return -index + PENALTY * ((energy - energy_j) ** 2 + excess ** 2 + out_of_range ** 2)

    started = time.perf_counter()
    result = optimize.minimize(cost, start.ravel(), method="Nelder-Mead",
                               options={"maxfev": max_evaluations, "xatol": 1e-8, "fatol": 1e-10,
                                        "adaptive": True})
    coefficients = result.x.reshape(2, -1)
    index, energy, tau = objective.evaluate(coefficients)
    return FourierCruise(coefficients=coefficients, index_j=index, energy_error_j=energy - energy_j,
                         max_torque_fraction=float((np.abs(tau) / model.torque_limits()[:, None]).max()),
                         evaluations=int(result.nfev), wall_s=time.perf_counter() - started)


@dataclasses.dataclass(frozen=True)
class PolynomialSineSegment:
    """One segment of eq. 11 on [start_s, start_s + duration_s], in the segment's own time t - start_s."""

    coefficients: Array         # (4, 5): A1, A2, B1, B2, lowest power first (unused powers 0)
    start_s: float
    duration_s: float
    index_j: float              # alpha advance - effort over the segment
    boundary_error: float       # largest |psi| or |psidot| mismatch at the segment's imposed ends, rad or rad/s
    evaluations: int


@dataclasses.dataclass(frozen=True)
class PolynomialSineAccelerate:
    """The paper's accelerate: one segment of eq. 11, or segments joined where the foil velocity may jump."""

    segments: tuple[PolynomialSineSegment, ...]
    wall_s: float

    @property
    def index_j(self) -> float:
        """With p_alpha = 0 from rest, alphadot depends on (psi, psidot) only: segment indices add up."""
        return float(sum(s.index_j for s in self.segments))

    @property
    def boundary_error(self) -> float:
        """The largest mismatch at a segment's imposed ends, rad or rad/s."""
        return float(max(s.boundary_error for s in self.segments))

    @property
    def evaluations(self) -> int:
        """The model evaluations of all segments together."""
        return int(sum(s.evaluations for s in self.segments))


def polynomial_sine_shape(coefficients: Array, times: Array) -> tuple[Array, Array, Array]:
    """psi, psidot, psiddot of eq. 11: phi = A1 sin(A2), theta = B1 sin(B2)."""
    out = []
    for amplitude_c, phase_c in ((coefficients[0], coefficients[1]), (coefficients[2], coefficients[3])):
        amplitude, phase = np.polynomial.Polynomial(amplitude_c), np.polynomial.Polynomial(phase_c)
        a, da, dda = amplitude(times), amplitude.deriv(1)(times), amplitude.deriv(2)(times)
        b, db, ddb = phase(times), phase.deriv(1)(times), phase.deriv(2)(times)
        sin_b, cos_b = np.sin(b), np.cos(b)
        out.append((a * sin_b, da * sin_b + a * db * cos_b,
                    dda * sin_b + 2 * da * db * cos_b + a * ddb * cos_b - a * db * db * sin_b))
    return cast(tuple[Array, Array, Array], tuple(np.column_stack([out[0][i], out[1][i]]) for i in range(3)))


#: which of the (4, 5) coefficients are free: amplitudes A1, B1 of degree 4, phases A2, B2 of degree 3,
#: 9 per angle and 18 in all, the paper's count for its direct 4 s accelerate that "did not converge"
EIGHTEEN_COEFFICIENTS = np.array([[True] * 5, [True] * 4 + [False]] * 2)
#: the paper's 9 per segment (Sec. 5) without saying which; assumed: heave amplitude A1 of degree 2, pitch
#: amplitude B1 and both phases A2, B2 of degree 1 (a stroke whose amplitudes and frequency change linearly)
NINE_COEFFICIENTS = np.array([[True] * 3 + [False] * 2] + [[True] * 2 + [False] * 3] * 3)


def _stroke_start(free: Array, duration_s: float) -> Array:
    """Amplitudes growing linearly from 0, phases advancing at 2 pi rad/s, pitch 90 deg ahead.

    A swimming stroke to start the search from, not the answer.
    """
    start = np.zeros(free.shape)
    start[0, 1], start[2, 1] = 0.3 / duration_s, 0.5 / duration_s
    start[1, 1], start[3, 0], start[3, 1] = 2 * math.pi, math.pi / 2, 2 * math.pi
    return np.where(free, start, 0.0)


def _solve_segment(batch: ca.Function, samples: int, spec: PrimitiveSpec, tau_max: Array, start_s: float,
                   duration_s: float, free: Array, start: tuple[Array, Optional[Array]],
                   end: Optional[tuple[Array, Array]], max_evaluations: int) -> PolynomialSineSegment:
    """Nelder-Mead on one segment of eq. 11; imposed end values are penalties (fmin takes no constraints).

    start: (psi, psidot) at the segment's start, psidot None where the foil velocity may jump;
    end: (psi, psidot) to reach, or None for a free end.
    """
    times = np.linspace(0.0, duration_s, samples)
    weights = np.array([spec.heave_effort_weight, spec.pitch_effort_weight])

    def evaluate(coefficients: Array) -> tuple[float, float, float]:
        psi, psidot, psiddot = polynomial_sine_shape(coefficients, times)
        q = np.vstack([np.zeros(samples), psi.T])
        qdot = np.vstack([np.zeros(samples), psidot.T])
        alpha_rate, tau, _ = (np.asarray(v) for v in batch(q, qdot, psiddot.T))
        advance = float(np.trapezoid(alpha_rate.ravel(), times))
        effort = float(np.trapezoid((weights[:, None] * tau ** 2).sum(axis=0), times))
        errors = [np.abs(psi[0] - start[0])]
        if start[1] is not None:
            errors.append(np.abs(psidot[0] - start[1]))
        if end is not None:
            errors += [np.abs(psi[-1] - end[0]), np.abs(psidot[-1] - end[1])]
        excess = float(np.maximum(np.abs(tau) / tau_max[:, None] - 1.0, 0.0).sum())
        return advance - effort, float(np.concatenate(errors).max()), excess

    def unpack(values: Array) -> Array:
        coefficients = np.zeros(free.shape)
        coefficients[free] = values
        return coefficients

    def cost(values: Array) -> float:
        index, boundary, excess = evaluate(unpack(values))
        return -index + PENALTY * (boundary ** 2 + excess ** 2)

    def violation(values: Array) -> float:
        _, boundary, excess = evaluate(unpack(values))
        return boundary ** 2 + excess ** 2

    options = {"maxfev": max_evaluations // 2, "xatol": 1e-8, "fatol": 1e-12, "adaptive": True}
    # first the boundary conditions alone, then the index from there: from a plain stroke the penalized index
    # leaves Nelder-Mead far from the ends
    feasible = optimize.minimize(violation, _stroke_start(free, duration_s)[free], method="Nelder-Mead",
                                 options=options)
    result = optimize.minimize(cost, feasible.x, method="Nelder-Mead", options=options)
    index, boundary, _ = evaluate(unpack(result.x))
    return PolynomialSineSegment(unpack(result.x), start_s, duration_s, index, boundary,
                                 int(feasible.nfev + result.nfev))


def solve_polynomial_sine_accelerate(model: VehicleModel, spec: PrimitiveSpec, end_state: tuple[Array, Array],
                                     limits: Optional[PlanningLimits] = None, samples: int = 200,
                                     max_evaluations: int = 20000, segments: int = 1,
                                     free: Optional[Array] = None) -> PolynomialSineAccelerate:
    """The paper's accelerate (eq. 11) from rest to the cruise start ``end_state``, by Nelder-Mead.

    segments = 1: all coefficients at once (``free`` defaults to the 18 of EIGHTEEN_COEFFICIENTS);
    segments = 2: the paper's composite, two halves of ``free`` (default NINE_COEFFICIENTS) each, solved in
    turn: the first from rest with a free end, the second from the first's end configuration (its foil
    velocity may jump there, Sec. 4.3) to the cruise's start state. With p_alpha = 0 the halves' indices
    add up, so solving them in turn is the paper's "suboptimal" composite, not a joint optimum.
    """
    if spec.primitive_type is not PrimitiveType.ACCELERATE:
        raise ValueError("solve_polynomial_sine_accelerate solves accelerates")
    if segments not in (1, 2):
        raise ValueError(f"segments must be 1 or 2, not {segments}")
    if free is None:
        free = EIGHTEEN_COEFFICIENTS if segments == 1 else NINE_COEFFICIENTS
    batch = shape_driven_batch(model, samples)
    limits = PlanningLimits.of(model.rig) if limits is None else limits
    tau_max = limits.torque_fraction * model.torque_limits()
    target = (end_state[0][-2:], end_state[1][-2:])
    rest = (np.zeros(2), np.zeros(2))
    started = time.perf_counter()
    solved: tuple[PolynomialSineSegment, ...]
    if segments == 1:
        solved = (_solve_segment(batch, samples, spec, tau_max, 0.0, spec.duration_s, free, rest, target,
                                 max_evaluations),)
    else:
        half = spec.duration_s / 2.0
        first = _solve_segment(batch, samples, spec, tau_max, 0.0, half, free, rest, None, max_evaluations)
        joint = polynomial_sine_shape(first.coefficients, np.array([half]))[0][0]
        second = _solve_segment(batch, samples, spec, tau_max, half, half, free, (joint, None), target, max_evaluations)
        solved = (first, second)
    return PolynomialSineAccelerate(solved, time.perf_counter() - started)
