"""The cascade tracker (paper Sec. 6, Fig. 18): LQ feedback on u = psiddot, I/O linearization, sliding mode.

At each control period, with the plan (a trajectory.Trajectory) sampled at the current plan time t (gains
already time-scaled and concatenated by the planner, see time_scaling):

    x     = (int (y - y_des) dt, q - q_des, qdot - qdot_des)            error state (riccati)
    u     = u_des(t + h/2) - K(t) x,    K = R_l^-1 G_l' P_l             LQ stage (eqs. 19, 33)
    tau1  = Mio(q) u + Cio(q, qdot) qdot                                I/O linearization (eqs. 22-23)
    s     = Mio^-1 G_l' P_l x,  eps = -D s / max(||s||, phi)            sliding mode (eqs. 24-25)
    tau   = sat(tau1 + eps)                                             motor limits, saturation reported

After the plan ends the tracker holds the foil still at the plan's last heave and pitch: a PD law on psi
through the same I/O linearization. The torque is held over the period h (zero-order hold), so the feed-forward
u_des is taken at the period's midpoint (on the ideal model: worst pitch error 0.041 rad, 0.043 with u_des at the
period's start).
The hold law: (u = -kp (psi - psi_end) - kd psidot), alpha and R left free.
"""
from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, Callable, Optional

import numpy as np
import numpy.typing as npt

from swim_controller.errors import PlanError
from swim_controller.sliding_mode import SlidingMode
from swim_controller.trajectory import Trajectory, TrajectoryPoint

if TYPE_CHECKING:
    from swim_model import VehicleModel

Array = npt.NDArray[np.float64]
#: (q, qdot) -> (Mio 2x2, Cio qdot 2): the I/O linearization of the vehicle model (eqs. 22-23)
IoLinearization = Callable[[Array, Array], tuple[Array, Array]]

HOLD_STIFFNESS_PER_S2 = 100.0   # assumed: kp of the hold law, a 10 rad/s, critically damped foil
HOLD_DAMPING_PER_S = 20.0       # assumed: kd = 2 sqrt(kp)


@dataclasses.dataclass
class ControlOutput:
    """One period's result: the command and what went into it."""

    torque: Array               # commanded (heave, pitch) after saturation, N m
    saturated: tuple[bool, bool]
    unsaturated_torque: Array   # tau1 + eps before saturation, N m
    sliding_torque: Array       # eps, N m (zero when the sliding mode is off)
    error_state: Array          # x
    reference: TrajectoryPoint   # the plan at this period
    holding: bool               # the plan has ended: the hold law is in charge


class CascadeTracker:
    """The tracking law for one plan at a time; no ROS (the tracker node wraps it)."""

    def __init__(self, io_linearization: IoLinearization, torque_limits_n_m: Array,
                 sliding_mode: SlidingMode = SlidingMode(), sliding_mode_enabled: bool = True,
                 sample_period_s: float = 0.008) -> None:
        self._io = io_linearization
        if not (math.isfinite(sample_period_s) and sample_period_s > 0.0):
            raise ValueError(f"sample period must be positive and finite, got {sample_period_s!r}")
        self.sample_period_s = sample_period_s
        self.torque_limits_n_m = np.asarray(torque_limits_n_m, dtype=float)
        sliding_mode.validate()
        self.sliding_mode = sliding_mode
        self.sliding_mode_enabled = sliding_mode_enabled
        self.trajectory: Optional[Trajectory] = None
        self._integral = np.zeros(0)
        self._last_time_s: Optional[float] = None

    def start(self, trajectory: Trajectory) -> None:
        """Track ``trajectory`` from plan time 0; the integral error restarts at zero."""
        self.trajectory = trajectory
        self._integral = np.zeros(trajectory.ny)
        self._last_time_s = None

    def step(self, plan_time_s: float, q: Array, qdot: Array) -> ControlOutput:
        """The torque for the period starting at plan_time_s, from the measured q and qdot."""
        trajectory = self.trajectory
        if trajectory is None:
            raise PlanError("no plan: call start() first")
        ref = trajectory.sample(plan_time_s)
        holding = plan_time_s > trajectory.duration_s
        ny, nq = trajectory.ny, trajectory.nq
        error_q = q - ref.q
        if self._last_time_s is not None and not holding:
            self._integral = self._integral + error_q[:ny] * max(plan_time_s - self._last_time_s, 0.0)
        self._last_time_s = plan_time_s
        error_state = np.concatenate([self._integral, error_q, qdot - ref.qdot])
        mio, cio_qdot = self._io(q, qdot)
        if holding:
            u = hold_acceleration(q[nq - 2:], qdot[nq - 2:], trajectory.q[-1, nq - 2:])
        else:
            # the torque is held for one period: feed forward u_des at the period's midpoint
            u_des = trajectory.sample(plan_time_s + 0.5 * self.sample_period_s).foil_acceleration
            u = u_des - ref.lqr_gain @ error_state
        torque = mio @ u + cio_qdot
        sliding = np.zeros(2)
        if self.sliding_mode_enabled and not holding:
            sliding = self.sliding_mode.term(np.linalg.solve(mio, ref.riccati_input_gain @ error_state))
            torque = torque + sliding
        command, saturated = saturate(torque, self.torque_limits_n_m)
        return ControlOutput(torque=command, saturated=saturated, unsaturated_torque=torque,
                             sliding_torque=sliding, error_state=error_state, reference=ref, holding=holding)


    def hold(self, q: Array, qdot: Array, psi_target: Array) -> tuple[Array, tuple[bool, bool]]:
        """The torque that holds the foil still at psi_target (heave, pitch), with no plan involved."""
        mio, cio_qdot = self._io(q, qdot)
        torque = mio @ hold_acceleration(q[-2:], qdot[-2:], psi_target) + cio_qdot
        return saturate(torque, self.torque_limits_n_m)


def model_io_linearization(model: VehicleModel) -> IoLinearization:
    """The I/O linearization of a swim_model VehicleModel, called on its compiled C entry point directly
    (VehicleModel.native_function: the same numbers; the checked numpy API costs ~15 us more per call and CasADi's
    own call ~45 us, too much at 1 kHz; the tracker validates states itself)."""
    function = model.native_function("io_linearization")
    (q_input, qdot_input), (mio_output, cio_output) = function.inputs, function.outputs
    mio_shape = function.function.size_out(0)

    def evaluate(q: Array, qdot: Array) -> tuple[Array, Array]:
        q_input[:], qdot_input[:] = q, qdot
        function()
        return mio_output.reshape(mio_shape, order="F").copy(), cio_output.copy()
    return evaluate


def hold_acceleration(psi: Array, psi_rate: Array, psi_target: Array) -> Array:
    """u = -kp (psi - psi_target) - kd psidot: a critically damped return to psi_target."""
    return -HOLD_STIFFNESS_PER_S2 * (psi - psi_target) - HOLD_DAMPING_PER_S * psi_rate


def saturate(torque: Array, limits: Array) -> tuple[Array, tuple[bool, bool]]:
    """Clip to +-limits; a non-finite torque becomes zero and counts as saturated."""
    if not (math.isfinite(torque[0]) and math.isfinite(torque[1])):
        return np.zeros(2), (True, True)
    command = np.clip(torque, -limits, limits)
    return command, (bool(abs(torque[0]) > limits[0]), bool(abs(torque[1]) > limits[1]))
