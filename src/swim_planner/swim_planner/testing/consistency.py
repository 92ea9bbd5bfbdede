"""Open-loop replay: whether a primitive's torques, integrated through swim_model, reproduce its states.

The torque signal a primitive stands for is tau(t) = Mio(q) u + Cio(q, qdot) qdot (eqs. 15, 22-23)
along its continuous trajectory: q(t), qdot(t) cubic Hermite through the samples (with qdot and qddot as
slopes) and u(t) quadratic on each collocation interval, as Hermite-Simpson collocation represents them.
The replay integrates the forward dynamics (eqs. 6-7) under that torque with a tight adaptive integrator
and compares with the stored states.

The torque-driven dynamics are open-loop unstable at cruise amplitudes (a deviation of 3 mrad after
1.25 s grew to 8 rad after 5 s on the E = 0.1 cruise), so a replay over a whole primitive measures that
instability, not the primitive's consistency. The replay therefore restarts from the primitive's own state
every ``window_s`` seconds (multiple shooting) and reports the largest deviation within a window.
REPLAY_TOLERANCE is the deviation our default constrained primitives stay within over 0.5 s windows on their
default grids (measured: 0.2 to 22 mrad). Cruises use 80 intervals per cycle: with 40 the largest deviation is
135 mrad (measured without the input-smoothness term).

With the circulatory flow (``lag`` given) the lag states z join the replayed state: the torque signal is
tau(t) = shape_dynamics(q(t), qdot(t), u(t), z(t)) with z(t) cubic Hermite through the stored lag states (with
their rates as slopes), and the integrated state is (q, qdot, z), restarted from the primitive's own (q, qdot, z)
at every window.
"""
from __future__ import annotations

import dataclasses
from typing import Callable

import numpy as np
import numpy.typing as npt
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicHermiteSpline

from swim_model import VehicleModel

Array = npt.NDArray[np.float64]

#: largest open-loop deviation accepted within a replay window: rad (alpha, phi, theta) or m (R)
REPLAY_TOLERANCE = 0.05
REPLAY_WINDOW_S = 0.5


@dataclasses.dataclass(frozen=True)
class ReplayResult:
    """The largest deviation of an open-loop replay from the primitive, over windows of window_s (s)."""

    max_position_error: float     # rad or m, largest over all windows and coordinates
    max_velocity_error: float     # rad/s or m/s
    window_s: float


def quadratic_on_intervals(time_s: Array, values: Array, t: float) -> Array:
    """Interpolate samples at knots and midpoints (2N + 1 of them) quadratically on each interval."""
    intervals = (len(time_s) - 1) // 2
    k = min(max(int(np.searchsorted(time_s[::2], t, side="right")) - 1, 0), intervals - 1)
    t0, tm, t1 = time_s[2 * k], time_s[2 * k + 1], time_s[2 * k + 2]
    l0 = (t - tm) * (t - t1) / ((t0 - tm) * (t0 - t1))
    lm = (t - t0) * (t - t1) / ((tm - t0) * (tm - t1))
    l1 = (t - t0) * (t - tm) / ((t1 - t0) * (t1 - tm))
    return l0 * values[2 * k] + lm * values[2 * k + 1] + l1 * values[2 * k + 2]


def replay_open_loop(model: VehicleModel, time_s: Array, q: Array, qdot: Array, foil_acceleration: Array,
                     window_s: float = REPLAY_WINDOW_S, lag: Array | None = None) -> ReplayResult:
    """Integrate the primitive's torque signal window by window; compare with its states.

    lag: the stored lag states (samples, 2), m/s, for a model of the circulatory flow (required there).
    """
    if model.n_lag:
        if lag is None:
            raise ValueError("replay_open_loop: a circulatory-flow model needs the primitive's lag states")
        return _replay_circulatory(model, time_s, q, qdot, foil_acceleration, lag, window_s)
    nq = model.nq
    qddot = np.array([model.shape_dynamics(a, b, c)[0] for a, b, c in zip(q, qdot, foil_acceleration)])
    position, velocity = CubicHermiteSpline(time_s, q, qdot), CubicHermiteSpline(time_s, qdot, qddot)

    def torque(t: float) -> Array:
        u = quadratic_on_intervals(time_s, foil_acceleration, t)
        return model.shape_dynamics(position(t), velocity(t), u)[1]

    def rhs(t: float, x: Array) -> Array:
        return np.concatenate([x[nq:], model.forward_dynamics(x[:nq], x[nq:], torque(t))])

    return _windows(rhs, lambda t: np.concatenate([position(t), velocity(t)]), time_s, q, qdot, window_s)


def _windows(rhs: Callable[[float, Array], Array], state_at: Callable[[float], Array], time_s: Array, q: Array,
             qdot: Array, window_s: float) -> ReplayResult:
    """Integrate x' = rhs(t, x) from state_at(start) over each window.

    The largest deviation of (q, qdot), the first 2 nq entries of x.
    """
    nq = q.shape[1]
    worst_position = worst_velocity = 0.0
    starts = np.arange(time_s[0], time_s[-1] - 1e-9, window_s)
    for start in starts:
        stop = min(start + window_s, time_s[-1])
        inside = (time_s >= start - 1e-12) & (time_s <= stop + 1e-12)
        solution = solve_ivp(rhs, (start, stop), state_at(start), method="DOP853", t_eval=time_s[inside],
                             rtol=1e-10, atol=1e-12)
        replayed = solution.y.T
        worst_position = max(worst_position, float(np.abs(replayed[:, :nq] - q[inside]).max()))
        worst_velocity = max(worst_velocity, float(np.abs(replayed[:, nq:2 * nq] - qdot[inside]).max()))
    return ReplayResult(worst_position, worst_velocity, window_s)


def _replay_circulatory(model: VehicleModel, time_s: Array, q: Array, qdot: Array, foil_acceleration: Array,
                        lag: Array, window_s: float) -> ReplayResult:
    nq = model.nq
    qddot = np.array([model.shape_dynamics(a, b, c, z)[0] for a, b, c, z in zip(q, qdot, foil_acceleration, lag)])
    lag_rate = np.array([model.lag_rate(a, b, z) for a, b, z in zip(q, qdot, lag)])
    position, velocity = CubicHermiteSpline(time_s, q, qdot), CubicHermiteSpline(time_s, qdot, qddot)
    lag_path = CubicHermiteSpline(time_s, lag, lag_rate)

    def torque(t: float) -> Array:
        u = quadratic_on_intervals(time_s, foil_acceleration, t)
        return model.shape_dynamics(position(t), velocity(t), u, lag_path(t))[1]

    def rhs(t: float, x: Array) -> Array:
        positions, rates, lags = x[:nq], x[nq:2 * nq], x[2 * nq:]
        return np.concatenate([rates, model.forward_dynamics(positions, rates, torque(t), lags),
                               model.lag_rate(positions, rates, lags)])

    return _windows(rhs, lambda t: np.concatenate([position(t), velocity(t), lag_path(t)]), time_s, q, qdot,
                    window_s)
