"""Optimal-control motion primitives, their library, the lane/energy graph and the maneuver planner node.

Public API (ROS-free; planner_node wraps it):
    PrimitiveSpec, PrimitiveType, Primitive, PlanningLimits, SolverSettings   what a primitive is (primitives)
    solve_primitive(model, spec, limits, start, end, guess, settings)         its optimal-control problem, solved
    PrimitiveLibrary.load(path, rig, flow_model) / .create_or_open(...)       the library on disk, verified
    concatenate(library, rig, sequence, time_scale, start_alpha_rad)          a plan (a Trajectory) from primitives
    expand_sequence, check_plan_size, PlanBounds, vary_time_scale             requests, their bounds, re-timing
    PlannerError and its subclasses                                           what a user can get wrong

The optimizer's names (primitive_solver: solve_primitive, primitive_nlp, continuation_bounds, PrimitiveNlp) load
on first use, so what serves plans (library, graph, maneuvers, planner_node) never loads the NLP
(test/test_module_layering.py).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from swim_planner.errors import LibraryError, ManeuverError, PlannerError, PrimitiveSolveError
from swim_planner.library import PrimitiveLibrary, verify_all
from swim_planner.maneuver import (
    DEFAULT_BOUNDS,
    JUNCTION_TOLERANCE,
    DisturbanceBounds,
    PlanBounds,
    PlanLibrary,
    check_plan_size,
    concatenate,
    expand_sequence,
    flow_model_of,
    junction_mismatch,
    vary_time_scale,
)
from swim_planner.primitives import (
    PlanningLimits,
    Primitive,
    PrimitiveSpec,
    PrimitiveType,
    SolverSettings,
    cruise_mean_speed_m_s,
    cruise_strouhal_number,
    rest_boundary_state,
    rest_state,
)
from swim_ros.exports import lazy_exports

if TYPE_CHECKING:
    from swim_planner.primitive_solver import PrimitiveNlp, continuation_bounds, primitive_nlp, solve_primitive

__all__ = [
    "DEFAULT_BOUNDS", "DisturbanceBounds", "JUNCTION_TOLERANCE", "LibraryError", "ManeuverError", "PlanBounds",
    "PlanLibrary", "PlannerError", "PlanningLimits", "Primitive", "PrimitiveLibrary", "PrimitiveNlp",
    "PrimitiveSolveError", "PrimitiveSpec", "PrimitiveType", "SolverSettings", "check_plan_size", "concatenate",
    "continuation_bounds", "cruise_mean_speed_m_s", "cruise_strouhal_number", "expand_sequence", "flow_model_of",
    "junction_mismatch", "primitive_nlp", "rest_boundary_state", "rest_state", "solve_primitive", "vary_time_scale",
    "verify_all",
]

#: the optimizer's names, loading swim_planner.primitive_solver on first use (swim_ros.exports)
_, __getattr__ = lazy_exports(__name__, {
    "primitive_solver": ("PrimitiveNlp", "continuation_bounds", "primitive_nlp", "solve_primitive"),
})
