"""A closed loop in one process, for tests and benchmarks.

The tracker at its sample period and a plant with the torque held over each period (zero-order hold), plus an optional
torque disturbance d(t) on the motors.

The plant is swim_model's vehicle integrated by RK4 substeps (with the circulatory flow, its lag states too,
starting from the plan's, or from still water under an ideal-flow plan), or any ``Stepper`` at the same period
(such as swim_sim's Plant, with its disturbances and the vortex wake).
"""
from __future__ import annotations

import dataclasses
from typing import Callable, Optional, Protocol

import numpy as np
import numpy.typing as npt

from swim_control.measures import two_norm
from swim_control.trajectory import Trajectory
from swim_controller.tracker import CascadeTracker
from swim_model import VehicleModel

Array = npt.NDArray[np.float64]


class SteppedState(Protocol):
    """The state a Stepper reaches at a period's end (swim_model.plant.PlantState is one)."""

    @property
    def q(self) -> Array:
        """Positions (nq,), rad or m."""
    @property
    def qdot(self) -> Array:
        """Velocities (nq,), rad/s or m/s."""


class Stepper(Protocol):
    """A plant stepped by control periods (swim_model.plant.Plant is one)."""

    def reset(self, q: Array, qdot: Array) -> None:
        """Put the plant at (q, qdot)."""

    def step(self, torque: Array) -> SteppedState:
        """Apply torque (2,), N m, over one control period; the state at its end."""


@dataclasses.dataclass
class Run:
    """A closed-loop run: per control period its time (s), state, reference, torque (N m) and saturation."""

    time_s: Array
    q: Array
    q_reference: Array
    torque: Array
    saturated: npt.NDArray[np.bool_]

    @property
    def error(self) -> Array:
        """The tracking error q - q_reference per sample, rad or m."""
        return self.q - self.q_reference

    def two_norm(self, column: int, until_s: Optional[float] = None) -> float:
        """The paper's measure sqrt(int e^2 dt) of one coordinate's error (Sec. 7; measures.two_norm).

        Over the run, or over its samples before until_s.
        """
        kept = slice(None) if until_s is None else self.time_s < until_s
        return two_norm(self.time_s[kept], self.error[kept, column])


def simulate(model: VehicleModel, tracker: CascadeTracker, trajectory: Trajectory, sample_period_s: float = 0.008,
             substeps: int = 8, q0: Optional[npt.ArrayLike] = None, qdot0: Optional[npt.ArrayLike] = None,
             disturbance: Callable[[float], Array] = lambda t: np.zeros(2), extra_time_s: float = 0.0,
             plant: Optional[Stepper] = None) -> Run:
    """Run the tracker on the plan from (q0, qdot0), by default the plan's start, for its duration plus extra_time_s.

    The plant is plant if given, else model integrated by RK4 with substeps steps per period (its lag states from the
    plan's, or still water's); disturbance(t) (N m) adds to the torque.
    """
    tracker.start(trajectory)
    q = trajectory.q[0].copy() if q0 is None else np.array(q0, dtype=float)
    qdot = trajectory.qdot[0].copy() if qdot0 is None else np.array(qdot0, dtype=float)
    lag = None
    if model.n_lag:   # the plan's lag states, or still water's (zero) under a plan made without them
        lag = trajectory.lag[0].copy() if trajectory.lag is not None else np.zeros(model.n_lag)
    if plant is not None:
        plant.reset(q, qdot)
    periods = int(round((trajectory.duration_s + extra_time_s) / sample_period_s))
    times, qs, refs, torques, saturations = [], [], [], [], []
    for k in range(periods):
        t = k * sample_period_s
        out = tracker.step(t, q, qdot)
        times.append(t)
        qs.append(q.copy())
        refs.append(out.reference.q.copy())
        torques.append(out.torque.copy())
        saturations.append(out.saturated)
        if plant is not None:
            state = plant.step(out.torque + disturbance(t))
            q, qdot = state.q, state.qdot
            continue
        applied = np.tile(out.torque + disturbance(t), (substeps, 1))
        if lag is None:
            trajectory_q, trajectory_qdot = model.integrate_rk4(q, qdot, applied, sample_period_s / substeps)
        else:
            trajectory_q, trajectory_qdot, trajectory_lag = model.integrate_rk4(
                q, qdot, applied, sample_period_s / substeps, lag=lag)
            lag = trajectory_lag[-1]
        q, qdot = trajectory_q[-1], trajectory_qdot[-1]
    return Run(np.array(times), np.array(qs), np.array(refs), np.array(torques), np.array(saturations))
