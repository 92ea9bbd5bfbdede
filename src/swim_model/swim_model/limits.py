"""The rig's joint limits: the record planner, tracker, simulator and bridge all read."""
from __future__ import annotations

#: ((heave lower, upper), (pitch lower, upper)) joint stops, rad
HardLimits = tuple[tuple[float, float], tuple[float, float]]
