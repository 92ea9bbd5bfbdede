"""The trajectory core under the planner and the tracker.

The one trajectory type, time scaling (Theorem 1), the LQ stage's Riccati gains, the paper's tracking measure and the
plan errors. Pure Python on swim_model, no ROS.

Public API:
    Trajectory, Segment, TrajectoryPoint, motor_limit_fraction   a plan and its samples (trajectory)
    LqrWeights -> primitive_gains(...) -> TrackingGains           the LQ stage's gains (riccati)
    scale_riccati, scale_weights, lqr_gain_from, retime_feedback  time scaling of gains (time_scaling, Theorem 1)
    two_norm                                                      the paper's tracking measure (measures)
    ControllerError and its subclasses                            what a plan or a computation can get wrong
"""
from swim_control.errors import ControllerError, GainComputationError, PlanError, StateMessageError
from swim_control.measures import two_norm
from swim_control.riccati import LqrWeights, TrackingGains, error_state_size, primitive_gains, solve_riccati
from swim_control.time_scaling import lqr_gain_from, retime_feedback, scale_riccati, scale_weights
from swim_control.trajectory import (
    MAX_ABS_START_ALPHA_RAD,
    MAX_TRACKED_SAMPLES,
    Segment,
    Trajectory,
    TrajectoryPoint,
    motor_limit_fraction,
)

__all__ = [
    "ControllerError", "GainComputationError", "LqrWeights", "MAX_ABS_START_ALPHA_RAD", "MAX_TRACKED_SAMPLES",
    "PlanError", "Segment", "StateMessageError", "TrackingGains", "Trajectory", "TrajectoryPoint",
    "error_state_size", "lqr_gain_from", "motor_limit_fraction", "primitive_gains", "retime_feedback",
    "scale_riccati", "scale_weights", "solve_riccati", "two_norm",
]
