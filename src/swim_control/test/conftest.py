"""Fixtures: the rig, its vehicle models and smooth strokes to linearize about (swim_control.testing.strokes)."""
from swim_control.testing.strokes import make_trajectory, model_for, rig, strokes  # noqa: F401
