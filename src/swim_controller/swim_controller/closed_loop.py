"""A closed loop in one process, for tests and benchmarks: the tracker at its sample period and a plant with the
torque held over each period (zero-order hold), plus an optional torque disturbance d(t) on the motors.

The plant is swim_model's ideal vehicle integrated by RK4 substeps, or any ``Stepper`` at the same period (such
as swim_sim's Plant, with its disturbances and the vortex wake).
"""
from __future__ import annotations

import dataclasses
from typing import Callable, Optional, Protocol

import numpy as np
import numpy.typing as npt

from swim_controller.tracker import CascadeTracker, Reference
from swim_model import VehicleModel

Array = npt.NDArray[np.float64]


class SampledPlan(Protocol):
    """What reference_of reads of a plan (swim_planner.maneuver.Plan is one)."""

    @property
    def time_s(self) -> Array: ...
    @property
    def q(self) -> Array: ...
    @property
    def qdot(self) -> Array: ...
    @property
    def foil_acceleration(self) -> Array: ...
    @property
    def torque(self) -> Array: ...
    @property
    def lqr_gain(self) -> Array: ...
    @property
    def sliding_gain(self) -> Array: ...


def reference_of(plan: SampledPlan) -> Reference:
    """The tracker's Reference of a plan (swim_planner.maneuver.Plan: samples, torques and time-scaled gains)."""
    return Reference(plan.time_s, plan.q, plan.qdot, plan.foil_acceleration, plan.torque, plan.lqr_gain,
                     plan.sliding_gain)


class SteppedState(Protocol):
    """The state a Stepper reaches at a period's end (swim_sim.plant.PlantState is one)."""

    @property
    def q(self) -> Array: ...
    @property
    def qdot(self) -> Array: ...


class Stepper(Protocol):
    """A plant stepped by control periods (swim_sim.plant.Plant is one)."""

    def reset(self, q: Array, qdot: Array) -> None: ...

    def step(self, torque: Array) -> SteppedState: ...


@dataclasses.dataclass
class Run:
    time_s: Array
    q: Array
    q_reference: Array
    torque: Array
    saturated: npt.NDArray[np.bool_]

    @property
    def error(self) -> Array:
        return self.q - self.q_reference

    def two_norm(self, column: int, until_s: Optional[float] = None) -> float:
        """sqrt(int e^2 dt) of one coordinate's error (the paper's measure, Sec. 7), over the run or its start."""
        step = self.time_s[1] - self.time_s[0]
        error = self.error[:, column] if until_s is None else self.error[self.time_s < until_s, column]
        return float(np.sqrt(np.sum(error ** 2) * step))


def simulate(model: VehicleModel, tracker: CascadeTracker, reference: Reference, sample_period_s: float = 0.008,
             substeps: int = 8, q0: Optional[npt.ArrayLike] = None, qdot0: Optional[npt.ArrayLike] = None,
             disturbance: Callable[[float], Array] = lambda t: np.zeros(2), extra_time_s: float = 0.0,
             plant: Optional[Stepper] = None) -> Run:
    tracker.start(reference)
    q = reference.q[0].copy() if q0 is None else np.array(q0, dtype=float)
    qdot = reference.qdot[0].copy() if qdot0 is None else np.array(qdot0, dtype=float)
    if plant is not None:
        plant.reset(q, qdot)
    periods = int(round((reference.duration_s + extra_time_s) / sample_period_s))
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
        trajectory_q, trajectory_qdot = model.integrate_rk4(q, qdot, applied, sample_period_s / substeps)
        q, qdot = trajectory_q[-1], trajectory_qdot[-1]
    return Run(np.array(times), np.array(qs), np.array(refs), np.array(torques), np.array(saturations))
