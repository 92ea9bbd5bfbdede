"""The cascade tracker: time-varying LQR with time-scaled gains, input-output linearization and sliding mode.

Public API (ROS-free; tracker_node wraps it):
    CascadeTracker(io_linearization, torque_limits_n_m, ...)   the law for one plan at a time; .step -> ControlOutput
    model_io_linearization(model), model_lag_rate(model)       a VehicleModel's compiled I/O linearization, lag rate
    LagEstimator, FoilRangeGuard                               the flow's lag estimate; the bound near the stops
    SlidingMode                                                the sliding-mode term (eqs. 24-25)
    Supervisor, Tolerances, Step, Mode, Outcome                modes, tolerances and outcomes around the law
    StaleStateWatch                                            is the newest state too old?
"""
from swim_controller.sliding_mode import SlidingMode
from swim_controller.supervisor import Mode, Outcome, StaleStateWatch, Step, Supervisor, Tolerances
from swim_controller.tracker import (
    CascadeTracker,
    ControlOutput,
    FoilRangeGuard,
    IoLinearization,
    LagEstimator,
    LagRate,
    hold_acceleration,
    model_io_linearization,
    model_lag_rate,
    saturate,
)

__all__ = [
    "CascadeTracker", "ControlOutput", "FoilRangeGuard", "IoLinearization", "LagEstimator", "LagRate", "Mode",
    "Outcome", "SlidingMode", "StaleStateWatch", "Step", "Supervisor", "Tolerances", "hold_acceleration",
    "model_io_linearization", "model_lag_rate", "saturate",
]
