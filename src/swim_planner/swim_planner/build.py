"""Building a primitive library: dependency order, parallel solves, resumable.

Cruises depend on nothing; every other primitive needs the states of the cruises it joins. Jobs go to any
``concurrent.futures.Executor`` (a process pool by default, or a Dask ``distributed.Client``'s executor),
each as soon as the primitives it depends on are in the library. Primitives already in the library are
not solved again, so an interrupted build resumes where it stopped.
"""
from __future__ import annotations

import concurrent.futures
from typing import Callable, Optional, Sequence

from swim_model import RigParameters, VehicleModel
from swim_planner.errors import PrimitiveSolveError
from swim_planner.library import PrimitiveLibrary
from swim_planner.primitives import PlanningLimits, Primitive, PrimitiveSpec, SolverSettings, solve_primitive

Progress = Callable[[str, str], None]


def solve_job(rig: RigParameters, spec: PrimitiveSpec, limits: PlanningLimits, settings: SolverSettings,
              start, end, guess: Optional[Primitive] = None) -> Primitive:
    """One primitive, in a worker process: picklable arguments in, a Primitive out."""
    model = VehicleModel(rig, constrained=spec.constrained, lane_radius_m=spec.lane_radius_m)
    return solve_primitive(model, spec, limits, start=start, end=end, guess=guess, settings=settings)


def dependencies(spec: PrimitiveSpec) -> list[str]:
    return [d for d in (spec.start_from, spec.end_at) if d is not None]


def build_library(library: PrimitiveLibrary, specs: Sequence[PrimitiveSpec], executor: concurrent.futures.Executor,
                  limits: PlanningLimits = PlanningLimits(), progress: Progress = lambda i, s: None) -> list[str]:
    """Solve every spec not yet in the library; returns the ids that failed (with their reasons reported)."""
    known = {s.primitive_id for s in specs} | set(library.ids())
    for spec in specs:
        missing = [d for d in dependencies(spec) if d not in known]
        if missing:
            raise ValueError(f"{spec.primitive_id} depends on unknown primitives: {', '.join(missing)}")
    pending = [s for s in specs if s.primitive_id not in library]
    for spec in specs:
        if spec.primitive_id in library:
            progress(spec.primitive_id, "cached")
    failed: list[str] = []
    running: dict[concurrent.futures.Future, PrimitiveSpec] = {}
    while pending or running:
        for spec in list(pending):
            deps = dependencies(spec)
            if any(d in failed for d in deps):
                pending.remove(spec)
                failed.append(spec.primitive_id)
                progress(spec.primitive_id, "skipped: a primitive it joins failed")
            elif all(d in library for d in deps):
                pending.remove(spec)
                start = library.get(spec.start_from).end_state if spec.start_from else None
                end = library.get(spec.end_at).start_state if spec.end_at else None
                running[executor.submit(solve_job, library.rig, spec, limits, library.solver, start, end)] = spec
        if not running:
            break
        done, _ = concurrent.futures.wait(running, return_when=concurrent.futures.FIRST_COMPLETED)
        for future in done:
            spec = running.pop(future)
            try:
                library.add(future.result())
                progress(spec.primitive_id, "solved")
            except PrimitiveSolveError as err:
                failed.append(spec.primitive_id)
                progress(spec.primitive_id, f"failed: {err}")
    return failed
