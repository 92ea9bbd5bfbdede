"""Errors a user of swim_planner can cause, each with a message that says what is wrong."""


class PlannerError(Exception):
    """Base class of swim_planner's errors."""


class PrimitiveSolveError(PlannerError):
    """The optimizer did not converge on a primitive."""


class LibraryError(PlannerError):
    """A primitive library is missing, corrupt, of another format, or built for another rig or model."""


class ManeuverError(PlannerError, ValueError):
    """A maneuver request cannot be planned (unknown primitive, no connection, torque limit, ...)."""
