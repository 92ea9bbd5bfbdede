"""Shape-driven swimming: prescribe the foil motion psi(t) = (phi, theta), integrate the rest.

With u = psiddot given, the unactuated rows (eq. 14) fix yddot and the actuated rows (eq. 15) give
the torques that produce the motion (``VehicleModel.shape_dynamics``). Starting with zero momentum
of the unactuated coordinates (``p_y = Mm11 ydot + Mm12 psidot = 0``), p_alpha stays zero (Prop. 1)
and the vehicle moves only by changing shape: self-propulsion in a perfect fluid.
"""
from __future__ import annotations

import dataclasses
import math
from typing import cast

import numpy as np
import numpy.typing as npt
from scipy.integrate import solve_ivp

from swim_model.vehicle import VehicleModel

Array = npt.NDArray[np.float64]


@dataclasses.dataclass(frozen=True)
class SinusoidalGait:
    """phi = phi0 + A sin(w t), theta = B sin(w t + lead): pitch leads heave by ``pitch_lead_rad``.

    ``mirrored`` gives the gait that runs the same (phi, theta) loop the other way round.

    Attributes
    ----------
    heave_amplitude_rad : float
        A, the heave's swing about its bias, rad.
    pitch_amplitude_rad : float
        B, rad (the pitch swings about zero).
    frequency_hz : float
        w / (2 pi), Hz.
    pitch_lead_rad : float
        Phase by which pitch leads heave, rad.
    heave_bias_rad : float
        phi0, the heave's mean, rad.
    """

    heave_amplitude_rad: float = 0.35
    pitch_amplitude_rad: float = 0.6
    frequency_hz: float = 1.0
    pitch_lead_rad: float = math.pi / 2.0
    heave_bias_rad: float = 0.0

    def mirrored(self) -> "SinusoidalGait":
        """The same loop run the other way round (pitch lags heave by the same angle).

        Returns
        -------
        SinusoidalGait
            This gait with ``pitch_lead_rad`` negated.
        """
        return dataclasses.replace(self, pitch_lead_rad=-self.pitch_lead_rad)

    def shape(self, time_s: float) -> tuple[Array, Array, Array]:
        """The foil's shape coordinates psi = (phi, theta) and their rates at one time.

        Parameters
        ----------
        time_s : float
            Time, s.

        Returns
        -------
        tuple of three (2,) ndarray
            (psi rad, psidot rad/s, psiddot rad/s^2).
        """
        w = 2.0 * math.pi * self.frequency_hz
        phases = np.array([w * time_s, w * time_s + self.pitch_lead_rad])
        amplitude = np.array([self.heave_amplitude_rad, self.pitch_amplitude_rad])
        psi = amplitude * np.sin(phases) + np.array([self.heave_bias_rad, 0.0])
        return psi, amplitude * w * np.cos(phases), -amplitude * w * w * np.sin(phases)


@dataclasses.dataclass(frozen=True)
class ShapeDrivenRun:
    """Samples of a shape-driven run.

    Attributes
    ----------
    time_s : (n,) ndarray
        Sample times, s.
    q : (n, nq) ndarray
        Configuration, rad and m.
    qdot : (n, nq) ndarray
        Velocity, rad/s and m/s.
    tau : (n, 2) ndarray
        Joint torques (heave, pitch), N m.
    joint_names : tuple of str
        Names of q's columns.
    """

    time_s: Array
    q: Array
    qdot: Array
    tau: Array
    joint_names: tuple[str, ...]


def zero_momentum_velocity(model: VehicleModel, q: Array, psi_dot: Array) -> Array:
    """Ydot with Mm11 ydot + Mm12 psidot = 0: the unactuated momenta vanish.

    Parameters
    ----------
    model : VehicleModel
        The vehicle.
    q : (nq,) ndarray
        Configuration, rad and m.
    psi_dot : (2,) ndarray
        (phidot, thetadot), rad/s.

    Returns
    -------
    (ny,) ndarray
        ydot, rad/s (and m/s for R), ny = nq - 2.
    """
    ny = model.n_unactuated
    mass = model.mass_matrix(q)
    return cast(Array, -np.linalg.solve(mass[:ny, :ny], mass[:ny, ny:] @ psi_dot))


def simulate_gait(model: VehicleModel, gait: SinusoidalGait, duration_s: float, sample_period_s: float = 0.01,
                  initial_y: npt.ArrayLike | None = None, rtol: float = 1e-10) -> ShapeDrivenRun:
    """Integrate the unactuated coordinates under the prescribed gait, from zero momentum.

    Parameters
    ----------
    model : VehicleModel
        The vehicle (free or constrained).
    gait : SinusoidalGait
        The prescribed foil motion.
    duration_s : float
        Length of the run, s.
    sample_period_s : float, optional
        Spacing of the returned samples, s.
    initial_y : array_like, optional
        Starting (alpha) or (alpha, R), rad and m; default alpha = 0 and R = the rig's lane 1.
    rtol : float, optional
        Relative tolerance of the DOP853 integrator (absolute tolerance rtol / 100).

    Returns
    -------
    ShapeDrivenRun
        The samples, with the torques that produce the motion.

    References
    ----------
    Saimek & Li (2004), eqs. 14-15 and Prop. 1.
    """
    ny = model.n_unactuated
    y0 = np.asarray(initial_y if initial_y is not None else
                    ([0.0] if model.constrained else [0.0, model.rig.lane_1_radius_m]), dtype=float)
    psi0, psidot0, _ = gait.shape(0.0)
    ydot0 = zero_momentum_velocity(model, np.concatenate([y0, psi0]), psidot0)

    def state(time_s: float, x: Array) -> tuple[Array, Array, Array]:
        psi, psidot, psiddot = gait.shape(time_s)
        return np.concatenate([x[:ny], psi]), np.concatenate([x[ny:], psidot]), psiddot

    def rhs(time_s: float, x: Array) -> Array:
        q, qdot, psiddot = state(time_s, x)
        qddot, _ = model.shape_dynamics(q, qdot, psiddot)
        return np.concatenate([x[ny:], qddot[:ny]])

    times = np.arange(0.0, duration_s + 0.5 * sample_period_s, sample_period_s)
    solution = solve_ivp(rhs, (0.0, times[-1]), np.concatenate([y0, ydot0]), method="DOP853",
                         t_eval=times, rtol=rtol, atol=rtol * 1e-2)
    qs, qdots, taus = [], [], []
    for time_s, x in zip(solution.t, solution.y.T):
        q, qdot, psiddot = state(time_s, x)
        qs.append(q)
        qdots.append(qdot)
        taus.append(model.shape_dynamics(q, qdot, psiddot)[1])
    return ShapeDrivenRun(solution.t, np.array(qs), np.array(qdots), np.array(taus), model.joint_names)
