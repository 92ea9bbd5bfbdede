"""Between ROS messages and the tracker's types: checked, so a bad message is refused, never used.

PlannedTrajectory (swim_interfaces v5; v4 plans are read too) <-> trajectory.Trajectory: ``trajectory_to_message``
(the planner's encoder) and ``trajectory_from_message`` (the tracker's decoder) side by side, so the layout is
written once.
"""
from __future__ import annotations

import dataclasses
from typing import Optional, Sequence

import numpy as np
import numpy.typing as npt
from swim_interfaces.msg import PlannedTrajectory, PrimitiveSegment

from swim_control.errors import PlanError, StateMessageError
from swim_control.riccati import error_state_size
from swim_control.trajectory import MAX_TRACKED_SAMPLES, Segment, Trajectory
from swim_model.flow import FLOW_MODELS, LAG_STATE_NAMES
from swim_model.vehicle import JOINT_NAMES_CONSTRAINED, JOINT_NAMES_UNCONSTRAINED
from swim_model.velocity_filter import VelocityEstimator
from swim_ros.codecs import MessageError, float_array, joint_state_arrays, seconds_of

Array = npt.NDArray[np.float64]
#: the interface version this module writes into a PlannedTrajectory (swim_interfaces' INTERFACE_VERSION)
SUPPORTED_INTERFACE_VERSION = 5
#: the versions whose PlannedTrajectory layout is this one's, so their plans are read as they are (version 5 added
#: the maneuver action and the primitive list, not plan fields)
READABLE_INTERFACE_VERSIONS = (4, SUPPORTED_INTERFACE_VERSION)
#: what the plans of older interface versions lack (named when one is refused)
OLDER_PLAN_VERSIONS = {
    2: "does not say which flow model it was made with nor carry the flow's lag states",
    3: "does not carry the sliding mode's disturbance bound",
}
#: the largest magnitude a plan's time, values and their changes per second between samples may have (SI units):
#: far past any plan a vehicle can follow, and small enough that the product of two (a gain times an error, a rate
#: times a time step, in the tracker's interpolation and law) stays finite in float64 (largest 1.8e308)
MAX_PLAN_MAGNITUDE = 1e150


def trajectory_to_message(trajectory: Trajectory, stamp) -> PlannedTrajectory:
    """A Trajectory as a swim_interfaces/PlannedTrajectory stamped ``stamp`` (builtin_interfaces/Time)."""
    message = PlannedTrajectory()
    message.header.stamp = stamp
    message.interface_version = SUPPORTED_INTERFACE_VERSION
    message.constrained = trajectory.constrained
    message.lane_radius_m = float(trajectory.lane_radius_m)
    message.joint_names = list(trajectory.joint_names)
    message.time_from_start_s = float_array(trajectory.time_s)
    message.positions = float_array(trajectory.q)
    message.velocities = float_array(trajectory.qdot)
    message.foil_accelerations = float_array(trajectory.foil_acceleration)
    message.feedforward_torques = float_array(trajectory.torque)
    message.lqr_gains = float_array(trajectory.lqr_gain)
    message.sliding_gains = float_array(trajectory.riccati_input_gain)
    message.segments = [PrimitiveSegment(**dataclasses.asdict(s)) for s in trajectory.segments]
    message.library_digest = trajectory.library_digest
    message.flow_model = trajectory.flow_model
    message.lag_states = float_array(trajectory.lag if trajectory.lag is not None else np.zeros(0))
    message.disturbance_bounds_n_m = float_array(trajectory.disturbance_bound if trajectory.disturbance_bound
                                                 is not None else np.zeros(0))
    return message


def trajectory_from_message(plan: PlannedTrajectory) -> Trajectory:
    """A swim_interfaces/PlannedTrajectory as a Trajectory.

    Raises PlanError naming what is wrong: another interface version, more than MAX_TRACKED_SAMPLES samples, joints that
    are not the vehicle's, a flow model that is not swim_model's, arrays of the wrong length (the lag states: N x n_lag,
    none for the ideal flow; the disturbance bounds: N or none), non-finite or (the disturbance bounds) negative values,
    times out of order or not from 0, values or their rates past MAX_PLAN_MAGNITUDE, segments that do not tile the
    samples.
    """
    if plan.interface_version not in READABLE_INTERFACE_VERSIONS:
        missing = OLDER_PLAN_VERSIONS.get(plan.interface_version)
        older = f" (a version {plan.interface_version} plan {missing}: plan it again with this version's planner)" \
            if missing else ""
        readable = " and ".join(map(str, READABLE_INTERFACE_VERSIONS))
        raise PlanError(f"plan interface version {plan.interface_version}, this tracker reads versions "
                        f"{readable}{older}")
    samples = len(plan.time_from_start_s)
    if samples > MAX_TRACKED_SAMPLES:
        raise PlanError(f"the plan has {samples} samples, more than the largest plan this tracker accepts "
                        f"({MAX_TRACKED_SAMPLES}, swim_control.trajectory.MAX_TRACKED_SAMPLES)")
    joint_names = JOINT_NAMES_CONSTRAINED if plan.constrained else JOINT_NAMES_UNCONSTRAINED
    if tuple(plan.joint_names) != joint_names:
        vehicle = "constrained" if plan.constrained else "free"
        raise PlanError(f"plan joints {list(plan.joint_names)} are not the {vehicle} vehicle's {list(joint_names)}")
    nq = len(joint_names)
    if plan.flow_model not in FLOW_MODELS:
        raise PlanError(f"plan flow model {plan.flow_model!r} is not one of {', '.join(FLOW_MODELS)}")
    n_lag = len(LAG_STATE_NAMES) if plan.flow_model == "circulatory" else 0
    n = error_state_size(nq, nq - 2, n_lag)

    def array(name: str, shape: tuple[int, ...]) -> Array:
        values = np.asarray(getattr(plan, name), dtype=float)
        if values.size != int(np.prod(shape)):
            raise PlanError(f"plan {name} has {values.size} values, expected {int(np.prod(shape))} for "
                            f"{samples} samples")
        return values.reshape(shape)
    fields = [field.name for field in dataclasses.fields(Segment)]   # PrimitiveSegment's, by name
    segments = tuple(Segment(**{name: getattr(s, name) for name in fields}) for s in plan.segments)
    lag = array("lag_states", (samples, n_lag))   # an ideal-flow plan carries none
    # none: the tracker's constant bound; else one a sample
    bound = array("disturbance_bounds_n_m", (samples,)) if len(plan.disturbance_bounds_n_m) else None
    with np.errstate(over="ignore", invalid="ignore"):   # rates that overflow are refused by check_plan_range
        trajectory = Trajectory(
            time_s=np.asarray(plan.time_from_start_s, dtype=float), q=array("positions", (samples, nq)),
            qdot=array("velocities", (samples, nq)), foil_acceleration=array("foil_accelerations", (samples, 2)),
            torque=array("feedforward_torques", (samples, 2)), lqr_gain=array("lqr_gains", (samples, 2, n)),
            riccati_input_gain=array("sliding_gains", (samples, 2, n)), segments=segments,
            lane_radius_m=plan.lane_radius_m, library_digest=plan.library_digest, flow_model=plan.flow_model,
            lag=lag if n_lag else None, disturbance_bound=bound)
        check_plan_range(trajectory)
    return trajectory


def check_plan_range(trajectory: Trajectory) -> None:
    """PlanError unless the plan's times and values, and their rates, are within MAX_PLAN_MAGNITUDE.

    The sample times run from 0 to at most MAX_PLAN_MAGNITUDE s and every value of the plan and its change per second
    between two samples is within MAX_PLAN_MAGNITUDE: then the tracker's references, its errors and its law's products
    are finite (a Trajectory checks only that the values are).
    """
    time_s = trajectory.time_s
    if not (time_s[0] == 0.0 and time_s[-1] <= MAX_PLAN_MAGNITUDE):
        raise PlanError(f"plan sample times must run from 0 s to at most {MAX_PLAN_MAGNITUDE:g} s, got "
                        f"{float(time_s[0])!r} to {float(time_s[-1])!r} s")
    step_s = np.diff(time_s)[:, None]
    names: tuple[str, ...] = ("q", "qdot", "foil_acceleration", "torque", "lqr_gain", "riccati_input_gain")
    names += ("lag",) if trajectory.lag is not None else ()
    names += ("disturbance_bound",) if trajectory.disturbance_bound is not None else ()
    for name in names:
        values = getattr(trajectory, name).reshape(len(time_s), -1)
        rates = np.diff(values, axis=0) / step_s
        if not (np.abs(values).max() <= MAX_PLAN_MAGNITUDE and np.abs(rates).max() <= MAX_PLAN_MAGNITUDE):
            raise PlanError(f"plan {name} has values or changes per second past {MAX_PLAN_MAGNITUDE:g} (SI): "
                            f"not a plan a vehicle can follow")


def state_from_message(message, joint_names: Optional[Sequence[str]], velocity: VelocityEstimator,
                       receipt_time_s: float) -> tuple[float, Array, Array]:
    """(time_s, q, qdot) from a sensor_msgs/JointState, in joint_names' order (any order in the message).

    The time is the message's stamp, or receipt_time_s when the stamp is zero (a source that does not stamp).
    Velocities come from the message, or, when it has none, from the filtered differences of positions.
    joint_names None (no plan yet): either vehicle's joints are accepted.
    Raises StateMessageError for unknown or missing joints, wrong lengths and non-finite values.
    """
    if joint_names is None:
        joint_names = JOINT_NAMES_UNCONSTRAINED if len(message.name) == len(JOINT_NAMES_UNCONSTRAINED) \
            else JOINT_NAMES_CONSTRAINED
    try:
        q, qdot = joint_state_arrays(message.name, message.position, message.velocity, joint_names)
    except MessageError as err:
        raise StateMessageError(str(err)) from err
    time_s = seconds_of(message.header.stamp) or receipt_time_s
    return time_s, q, (qdot if qdot is not None else velocity.update(time_s, q))
