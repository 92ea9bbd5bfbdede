"""Between ROS messages and the tracker's types: checked, so a bad message is refused, never used."""
from __future__ import annotations

from typing import Optional, Sequence

import numpy as np
import numpy.typing as npt

from swim_controller.errors import PlanError, StateMessageError
from swim_controller.riccati import error_state_size
from swim_controller.tracker import Reference
from swim_model.velocity_filter import VelocityEstimator
from swim_model.vehicle import JOINT_NAMES_CONSTRAINED, JOINT_NAMES_UNCONSTRAINED
from swim_ros.codecs import MessageError, joint_state_arrays, seconds_of

Array = npt.NDArray[np.float64]
SUPPORTED_INTERFACE_VERSION = 2


def reference_from_message(plan, joint_names: Sequence[str]) -> Reference:
    """A swim_interfaces/PlannedTrajectory as a Reference; raises PlanError naming what is wrong."""
    if plan.interface_version != SUPPORTED_INTERFACE_VERSION:
        raise PlanError(f"plan interface version {plan.interface_version}, this tracker reads "
                        f"{SUPPORTED_INTERFACE_VERSION}")
    if tuple(plan.joint_names) != tuple(joint_names):
        raise PlanError(f"plan joints {list(plan.joint_names)} do not match the vehicle's {list(joint_names)}")
    samples, nq = len(plan.time_from_start_s), len(joint_names)
    n = error_state_size(nq, nq - 2)

    def array(name: str, shape: tuple[int, ...]) -> Array:
        values = np.asarray(getattr(plan, name), dtype=float)
        if values.size != int(np.prod(shape)):
            raise PlanError(f"plan {name} has {values.size} values, expected {int(np.prod(shape))} for "
                            f"{samples} samples")
        return values.reshape(shape)
    return Reference(
        time_s=np.asarray(plan.time_from_start_s, dtype=float), q=array("positions", (samples, nq)),
        qdot=array("velocities", (samples, nq)), foil_acceleration=array("foil_accelerations", (samples, 2)),
        torque=array("feedforward_torques", (samples, 2)), lqr_gain=array("lqr_gains", (samples, 2, n)),
        sliding_gain=array("sliding_gains", (samples, 2, n)), joint_names=tuple(joint_names),
        segment_start_s=tuple(s.start_time_s for s in plan.segments),
        time_scale=plan.segments[0].time_scale if plan.segments else 1.0)


def state_from_message(message, joint_names: Optional[Sequence[str]], velocity: VelocityEstimator,
                       receipt_time_s: float) -> tuple[float, Array, Array]:
    """(time_s, q, qdot) from a sensor_msgs/JointState, in joint_names' order (any order in the message).

    The time is the message's stamp, or receipt_time_s when the stamp is zero (a source that does not stamp).
    Velocities come from the message, or, when it has none, from the filtered differences of positions.
    joint_names None (no plan yet): either vehicle's joints are accepted.
    Raises StateMessageError for unknown or missing joints, wrong lengths and non-finite values."""
    if joint_names is None:
        joint_names = JOINT_NAMES_UNCONSTRAINED if len(message.name) == len(JOINT_NAMES_UNCONSTRAINED) \
            else JOINT_NAMES_CONSTRAINED
    try:
        q, qdot = joint_state_arrays(message.name, message.position, message.velocity, joint_names)
    except MessageError as err:
        raise StateMessageError(str(err)) from err
    time_s = seconds_of(message.header.stamp) or receipt_time_s
    return time_s, q, (qdot if qdot is not None else velocity.update(time_s, q))
