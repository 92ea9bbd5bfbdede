"""Errors a user of swim_model can cause, each with a message that says what to fix."""


class SwimModelError(Exception):
    """Base class of every error raised by swim_model."""


class RigConfigError(SwimModelError, ValueError):
    """A rig parameter file is missing a key, names a wrong unit, or holds an impossible value."""


class FoilGeometryError(SwimModelError, ValueError):
    """A foil's chord, thickness or span cannot describe a symmetric Joukowski profile."""


class StateError(SwimModelError, ValueError):
    """A state, velocity or torque vector has the wrong shape or a non-finite entry."""


class FlowModelError(SwimModelError, ValueError):
    """A flow model's name, coefficients or experiment settings are not valid."""
