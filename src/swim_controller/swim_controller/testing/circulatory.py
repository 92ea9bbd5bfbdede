"""Runs and plans of the circulatory vehicle made without a planner, for tests and benchmarks.

swim_model's vehicle with the circulatory flow (n_lag = 2 lag states) integrated by RK4 under torques that make the foil
follow a sinusoidal gait, and a plan (a circulatory Trajectory) sampled from such a run, whose q, qdot, lag states, foil
accelerations and torques are the model's own.
"""
from __future__ import annotations

import dataclasses
from typing import Optional

import numpy as np
import numpy.typing as npt

from swim_control.riccati import error_state_size
from swim_control.trajectory import Segment, Trajectory
from swim_model import SinusoidalGait, VehicleModel

Array = npt.NDArray[np.float64]

#: how the torques make the foil follow the gait: u = psiddot_gait + kp e + kd edot through the model's inverse
#: dynamics; assumed: a 20 rad/s, critically damped correction, fast beside a 1 Hz gait
FOLLOW_STIFFNESS_PER_S2, FOLLOW_DAMPING_PER_S = 400.0, 40.0
#: the rig's size of stroke at 1 Hz (about half the heave motor's limit at most)
DEFAULT_GAIT = SinusoidalGait(heave_amplitude_rad=0.3, pitch_amplitude_rad=0.4, frequency_hz=1.0)


@dataclasses.dataclass(frozen=True)
class CirculatoryRun:
    """The circulatory vehicle every step_s.

    q (n + 1, nq), qdot, lag (n + 1, 2) m/s, and the torque (N m) held over each period of period_s = substeps * step_s.
    """

    model: VehicleModel
    step_s: float
    substeps: int
    time_s: Array
    q: Array
    qdot: Array
    lag: Array
    period_torque: Array   # (periods, 2): held over [k period_s, (k + 1) period_s)

    @property
    def period_s(self) -> float:
        """The control period, s: substeps integration steps of step_s."""
        return self.substeps * self.step_s


def gait_run(model: VehicleModel, duration_s: float, gait: SinusoidalGait = DEFAULT_GAIT, step_s: float = 0.001,
             substeps: int = 8) -> CirculatoryRun:
    """The circulatory model driven along the gait from the gait's shape at t = 0, in still water.

    Its unactuated coordinates start at rest (alpha = 0, R on the model's lane) and the water still (lag = 0). The
    torques are chosen period by period to follow the gait from the state reached, then the whole run is integrated
    again from the start by integrate_rk4 with those torques (the run returned: the model's own motion under known
    torques).
    """
    ny = model.n_unactuated
    psi0, psidot0, _ = gait.shape(0.0)
    q0 = np.concatenate([[0.0] if ny == 1 else [0.0, model.lane_radius_m], psi0])
    qdot0 = np.concatenate([np.zeros(ny), psidot0])
    lag0 = np.zeros(model.n_lag)
    q, qdot, lag = q0, qdot0, lag0
    period_s = substeps * step_s
    torques = []
    for k in range(round(duration_s / period_s)):
        psi, psidot, psiddot = gait.shape(k * period_s)
        u = psiddot + FOLLOW_STIFFNESS_PER_S2 * (psi - q[ny:]) + FOLLOW_DAMPING_PER_S * (psidot - qdot[ny:])
        torque = model.shape_dynamics(q, qdot, u, lag)[1]
        qs, qdots, lags = model.integrate_rk4(q, qdot, np.tile(torque, (substeps, 1)), step_s, lag=lag)
        q, qdot, lag = qs[-1], qdots[-1], lags[-1]
        torques.append(torque)
    period_torque = np.array(torques)
    qs, qdots, lags = model.integrate_rk4(q0, qdot0, np.repeat(period_torque, substeps, axis=0), step_s, lag=lag0)
    time_s = np.arange(len(qs), dtype=float) * step_s
    return CirculatoryRun(model, step_s, substeps, time_s, qs, qdots, lags, period_torque)


def plan_from_run(run: CirculatoryRun, duration_s: float, sample_stride: int = 4,
                  gains: Optional[tuple[Array, Array]] = None, seed: int = 4) -> Trajectory:
    """A circulatory plan of the run's first duration_s.

    A sample every sample_stride steps, u = psiddot of the model under the torque held there, tau that torque, the run's
    lag states. gains: (K, G'P), each (N, 2, ny + 2 nq + n_lag); default arbitrary (normal, seeded): the plan's shape,
    not tuned gains.
    """
    model = run.model
    index = np.arange(0, round(duration_s / run.step_s) + 1, sample_stride)
    torque = run.period_torque[np.minimum(index // run.substeps, len(run.period_torque) - 1)]
    u = np.array([model.forward_dynamics(run.q[k], run.qdot[k], tau, run.lag[k])[-2:]
                  for k, tau in zip(index, torque)])
    if gains is None:
        rng = np.random.default_rng(seed)
        n = error_state_size(model.nq, model.n_unactuated, model.n_lag)
        gains = rng.normal(size=(len(index), 2, n)), rng.normal(size=(len(index), 2, n))
    time_s = run.time_s[index]
    segment = Segment("test/circulatory_gait", "cruise", 0, 0.0, float(time_s[-1]), 1.0, 0.0, 0, len(index))
    return Trajectory(time_s, run.q[index], run.qdot[index], u, torque, gains[0], gains[1], (segment,),
                      lane_radius_m=model.lane_radius_m, flow_model="circulatory", lag=run.lag[index])
