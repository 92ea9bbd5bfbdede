"""Errors a user of swim_control can cause, each with a message that says what is wrong."""


class ControllerError(Exception):
    """Base class of swim_control's errors."""


class GainComputationError(ControllerError):
    """The LQ gains of a trajectory could not be computed (no Riccati solution, bad time grid)."""


class PlanError(ControllerError, ValueError):
    """A plan handed to the tracker is malformed (shapes, non-finite values, missing gains)."""


class StateMessageError(ControllerError, ValueError):
    """A state measurement is unusable (wrong joint names or lengths, NaN)."""
