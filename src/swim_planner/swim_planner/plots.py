"""Figures of a primitive like the paper's Figs. 3-8 and 13-16.

Also a primitive of the ideal flow model beside the circulatory one's (its traces and their summary numbers).
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

import casadi as ca
import numpy as np
import numpy.typing as npt

from swim_model import VehicleModel
from swim_model.towed_foil import kirchhoff_force
from swim_planner.errors import PlannerError
from swim_planner.primitives import Primitive, PrimitiveType, cruise_mean_speed_m_s

Array = npt.NDArray[np.float64]


def plot_primitive(primitive: Primitive, path: Path) -> None:
    """Displacement and velocity, heave and pitch, their phase portrait, and the torques."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    spec = primitive.spec
    t = primitive.time_s
    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
    axes[0, 0].plot(t, primitive.q[:, 0], label="alpha (rad)")
    axes[0, 0].plot(t, primitive.qdot[:, 0], label="alphadot (rad/s)")
    if not spec.constrained:
        axes[0, 0].plot(t, primitive.q[:, 1] - spec.lane_radius_m, label="R - R_lane (m)")
    axes[0, 1].plot(t, np.degrees(primitive.q[:, -2]), label="heave phi")
    axes[0, 1].plot(t, np.degrees(primitive.q[:, -1]), label="pitch theta")
    axes[1, 0].plot(np.degrees(primitive.q[:, -2]), np.degrees(primitive.q[:, -1]))
    axes[1, 0].plot(np.degrees(primitive.q[0, -2]), np.degrees(primitive.q[0, -1]), "o", label="start")
    axes[1, 1].plot(t, primitive.torque[:, 0], label="heave")
    axes[1, 1].plot(t, primitive.torque[:, 1], label="pitch")
    axes[0, 0].set(xlabel="time (s)", title="Displacement and velocity")
    axes[0, 1].set(xlabel="time (s)", ylabel="deg", title="Heave and pitch")
    axes[1, 0].set(xlabel="heave phi (deg)", ylabel="pitch theta (deg)", title="Heave-pitch phase portrait")
    axes[1, 1].set(xlabel="time (s)", ylabel="N m", title="Torques")
    for axis in axes.flat:
        axis.grid(True, alpha=0.3)
        axis.legend(fontsize=8)
    fig.suptitle(f"{spec.primitive_id}  (J = {primitive.index_j:.4f})")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


@dataclasses.dataclass(frozen=True)
class FlowTraces:
    """One primitive's motion and the fluid's force on its foil, sample by sample.

    Every array has shape (n,), n the samples shown (a cruise: its first solved cycle; else all), except ``fluid_force``
    (n, 3).

    thrust_n: the fluid's force on the foil along the direction of travel, N. The direction of travel is that of the
    foil frame origin F when only the hub turns (the alpha column of eq. 40's Q2, in foil axes: the hub's tangent at
    F, forward for alphadot > 0). The force is the ideal model's added-mass (Kirchhoff, eq. 46) force, plus with
    the circulatory flow swim_model.flow's force (lift, suction, profile drag, stall); the foil's moment does not
    enter. circulatory_thrust_n is that circulatory part alone (zero with the ideal flow). Its mean over a cruise
    need not be zero: the lever arm of F about the hub and the foil's moment change along the stroke.
    hub_torque_n_m: the same force and moment as a torque about the hub (the generalized force on alpha, Q2' f,
    first entry); the only torque on the hub, so its integral is the change of the rigid bodies' hub momentum and
    its mean over a periodic cruise is zero.
    """

    flow_model: str
    time_s: Array
    speed_m_s: Array             # alphadot x lane radius: speed along the lane
    heave_rad: Array             # phi
    pitch_rad: Array             # theta
    angle_of_attack_rad: Array   # atan2(-V, U) at F (VehicleModel.angle_of_attack)
    fluid_force: Array           # (fx, fy, mz) on the foil in foil axes at F, N, N, N m: added mass + circulatory
    thrust_n: Array
    circulatory_thrust_n: Array
    hub_torque_n_m: Array
    power_w: Array               # tau . psidot, the heave and pitch motors' power
    #: A0, the leading-edge suction parameter of the circulatory flow before its cap (swim_model.flow: past
    #: FlowParameters.critical_leading_edge_suction the leading edge separates); None for the ideal flow
    leading_edge_suction_parameter: Array | None = None
    #: the model's FlowParameters.critical_leading_edge_suction; None for the ideal flow
    critical_leading_edge_suction: float | None = None


def shown_samples(primitive: Primitive) -> slice:
    """The samples a side-by-side figure shows.

    A cruise's first solved cycle (its stored cycles repeat it), or the whole primitive.
    """
    if primitive.spec.primitive_type is PrimitiveType.CRUISE:
        return slice(0, 2 * primitive.spec.intervals + 1)
    return slice(0, len(primitive.time_s))


def _foil_velocity_rate_bias(model: VehicleModel) -> ca.Function:
    """(q, qdot) -> Q2dot qdot, 3-vector.

    The part of the foil frame's acceleration (Udot, Vdot, Omegadot) that does not come from qddot (eq. 40
    differentiated, as swim_model.hydrodynamics does).
    """
    s = model.symbolic
    return ca.Function("foil_velocity_rate_bias", [s.q, s.qdot],
                       [ca.jtimes(s.foil_velocity_map @ s.qdot, s.q, s.qdot)])


def flow_traces(primitive: Primitive, model: VehicleModel) -> FlowTraces:
    """The traces of ``primitive`` on ``model`` (its flow model, constrained or free, lane radius).

    The qddot come from the model with the planned foil accelerations u (VehicleModel.shape_dynamics), the lag states
    from the primitive (circulatory flow).
    """
    rows = shown_samples(primitive)
    q, qdot, u = primitive.q[rows], primitive.qdot[rows], primitive.foil_acceleration[rows]
    lag = None if primitive.lag is None else primitive.lag[rows]
    circulatory = model.circulatory_flow is not None
    if circulatory != (lag is not None):
        raise PlannerError(f"{primitive.spec.primitive_id}: a primitive {'without' if circulatory else 'with'} lag "
                           f"states does not belong to the {model.flow} flow model")
    rate_bias = _foil_velocity_rate_bias(model)
    n = len(q)
    velocity, acceleration, hub_column = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
    for k in range(n):
        lag_k = None if lag is None else lag[k]
        q2 = model.foil_velocity_map(q[k])
        qddot, _ = model.shape_dynamics(q[k], qdot[k], u[k], lag_k)
        velocity[k] = q2 @ qdot[k]
        acceleration[k] = q2 @ qddot + np.asarray(rate_bias(q[k], qdot[k])).reshape(-1)
        hub_column[k] = q2[:, 0]
    # the circulatory flow's force and suction parameter at every sample, in one call
    flow = model.circulatory_flow
    terms = None if flow is None or lag is None else flow.evaluate(velocity, lag)
    circulatory_force = np.zeros((n, 3)) if terms is None else np.atleast_2d(terms["f"])
    suction_parameter = None if terms is None else np.atleast_1d(terms["lesp"])
    force = kirchhoff_force(model.added_mass, velocity, acceleration) + circulatory_force
    travel = hub_column[:, :2] / np.hypot(hub_column[:, 0], hub_column[:, 1])[:, None]
    return FlowTraces(
        flow_model=model.flow, time_s=primitive.time_s[rows] - primitive.time_s[0],
        speed_m_s=qdot[:, 0] * primitive.spec.lane_radius_m, heave_rad=q[:, -2], pitch_rad=q[:, -1],
        angle_of_attack_rad=np.arctan2(-velocity[:, 1], velocity[:, 0]), fluid_force=force,
        thrust_n=np.einsum("ij,ij->i", force[:, :2], travel),
        circulatory_thrust_n=np.einsum("ij,ij->i", circulatory_force[:, :2], travel),
        hub_torque_n_m=np.einsum("ij,ij->i", force, hub_column),
        power_w=np.einsum("ij,ij->i", primitive.torque[rows], qdot[:, -2:]),
        leading_edge_suction_parameter=suction_parameter,
        critical_leading_edge_suction=None if flow is None else flow.params.critical_leading_edge_suction)


def _time_mean(values: Array, time_s: Array) -> float:
    """Time average over the samples (knots and midpoints) by Simpson's rule on each interval.

    The collocation's own quadrature.
    """
    from scipy.integrate import simpson
    return float(simpson(values, x=time_s) / (time_s[-1] - time_s[0]))


def flow_summary(primitive: Primitive, traces: FlowTraces) -> dict:
    """The numbers of one side of the figure.

    Mean speed along the lane (``cruise_mean_speed_m_s``: alpha's advance over the duration x lane radius), heave and
    pitch ranges over the samples shown (rad), the 95th percentile of |angle of attack| over them (deg), and the time
    averages of the motors' power (W) and of the thrust and its circulatory part (N) and of the fluid's torque about the
    hub (N m), as ``FlowTraces``. With the circulatory flow, the 95th percentile of |A0| and the share of the time it
    spends past the critical value, where the leading edge separates (``time_past_critical_suction``, 0-1; both None
    for the ideal flow).
    """
    suction, critical = traces.leading_edge_suction_parameter, traces.critical_leading_edge_suction
    return {
        "flow_model": traces.flow_model,
        "duration_s": float(traces.time_s[-1]),
        "mean_speed_m_s": cruise_mean_speed_m_s(primitive),
        "heave_range_rad": [float(traces.heave_rad.min()), float(traces.heave_rad.max())],
        "pitch_range_rad": [float(traces.pitch_rad.min()), float(traces.pitch_rad.max())],
        "angle_of_attack_p95_deg": float(np.degrees(np.percentile(np.abs(traces.angle_of_attack_rad), 95.0))),
        "mean_power_w": _time_mean(traces.power_w, traces.time_s),
        "mean_thrust_n": _time_mean(traces.thrust_n, traces.time_s),
        "mean_circulatory_thrust_n": _time_mean(traces.circulatory_thrust_n, traces.time_s),
        "mean_fluid_hub_torque_n_m": _time_mean(traces.hub_torque_n_m, traces.time_s),
        "leading_edge_suction_parameter_p95": (None if suction is None
                                               else float(np.percentile(np.abs(suction), 95.0))),
        "time_past_critical_suction": (None if suction is None or critical is None else
                                       _time_mean((np.abs(suction) > critical).astype(float), traces.time_s)),
    }


def plot_flows(sides: list[FlowTraces], title: str, path: Path) -> None:
    """The primitive of each flow model on the same axes, time on x.

    Speed along the lane, heave, pitch, angle of attack, thrust (``FlowTraces``; the circulatory part dashed) and the
    motors' power.
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 2, figsize=(12, 10), sharex=True)
    panels = [("speed_m_s", "speed along the lane alphadot R (m/s)"), ("heave_rad", "heave phi (rad)"),
              ("pitch_rad", "pitch theta (rad)"), ("angle_of_attack_rad", "angle of attack at F (deg)"),
              ("thrust_n", "fluid force on the foil along the hub's tangent at F (N)"),
              ("power_w", "motors' power tau . psidot (W)")]
    for traces, colour in zip(sides, ("tab:blue", "tab:red")):
        for axis, (name, _) in zip(axes.flat, panels):
            values = getattr(traces, name)
            if name == "angle_of_attack_rad":
                values = np.degrees(values)
            axis.plot(traces.time_s, values, color=colour, label=traces.flow_model)
        if traces.flow_model == "circulatory":
            axes[2, 0].plot(traces.time_s, traces.circulatory_thrust_n, "--", color=colour,
                            label="circulatory part")
    for axis, (_, label) in zip(axes.flat, panels):
        axis.set_title(label, fontsize=10)
        axis.grid(True, alpha=0.3)
        axis.legend(fontsize=8)
    for axis in axes[-1]:
        axis.set_xlabel("time (s)")
    fig.suptitle(f"{title}: ideal and circulatory flow")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
