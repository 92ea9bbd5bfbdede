"""Building a primitive library: dependency order, parallel solves, resumable.

Cruises depend on nothing; every other primitive needs the states of the cruises it joins. Jobs go to any
``concurrent.futures.Executor`` (a process pool by default, ``local_executor``, or a Dask ``distributed.Client``'s
executor), each once the primitives it depends on are in the library, the longest chains of work first.
Primitives already in the library are not solved again, so an interrupted build resumes where it stopped; a stored
primitive whose spec has changed is solved again, with every primitive that joins it.

A circulatory-flow library also stores each primitive's sliding-mode bound D(t) (swim_planner.disturbance),
measured once the primitives whose motion gives the wake its history are in: a build run on a library that lacks
some (one built before D(t) was stored, a format-3 one) measures only those, and a primitive solved again loses
its D(t) and has it measured again.
"""
from __future__ import annotations

import concurrent.futures
import multiprocessing
import os
from typing import Callable, Optional, Sequence, cast

from swim_control.riccati import LqrWeights
from swim_model import RigParameters, VehicleModel
from swim_planner.disturbance import disturbance_job, lead_in_ids
from swim_planner.errors import ManeuverError, PrimitiveSolveError
from swim_planner.gains import gains_job
from swim_planner.library import PrimitiveLibrary
from swim_planner.primitive_solver import solve_primitive
from swim_planner.primitives import PlanningLimits, Primitive, PrimitiveSpec, SolverSettings
from swim_ros.processes import end_with_starter

Progress = Callable[[str, str], None]


def local_executor(workers: int) -> concurrent.futures.ProcessPoolExecutor:
    """``workers`` local worker processes for a build, each with IPOPT's BLAS on one thread.

    Left to itself the BLAS that CasADi's IPOPT (MUMPS) loads runs as many threads as cores, and on the larger
    factorizations they spin: the free R = 0.43 m, E = 0.05 decelerate took 66 s of CPU for 43 s of wall time with them,
    43 s for the same wall time on one thread, so workers that share the cores slow each other down. The workers are
    spawned, not forked, so none inherits a BLAS this process may have started already. They die with this process
    (swim_ros.processes), which a worker waiting for its next job would otherwise outlive for good.
    """
    return concurrent.futures.ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                                                  initializer=_start_worker, initargs=(os.getpid(),))


def _start_worker(starter_pid: int) -> None:
    end_with_starter(starter_pid)
    # read by OpenBLAS when IPOPT's plugin first loads it, in the worker's first solve
    os.environ["OPENBLAS_NUM_THREADS"] = "1"


def solve_job(rig: RigParameters, spec: PrimitiveSpec, limits: PlanningLimits, settings: SolverSettings,
              start, end, guess: Optional[Primitive] = None, lqr_weights: LqrWeights = LqrWeights(),
              flow_model: str = "ideal") -> Primitive:
    """One primitive and its tracking gains, in a worker process: picklable arguments in, a Primitive out.

    start, end: the boundary states it joins (Primitive.end_boundary_state / start_boundary_state: (q, qdot),
    and the lag states with the circulatory flow), or None.
    guess: a primitive on the same grid to start from, or the cruise this primitive joins (its stroke
    seeds the initial guess of an accelerate or decelerate).
    flow_model: swim_model's flow model the primitive is solved with ("ideal" or "circulatory").
    """
    model = VehicleModel(rig, constrained=spec.constrained, lane_radius_m=spec.lane_radius_m, flow=flow_model)
    primitive = solve_from_guess_or_blend(model, spec, limits, start, end, guess, settings)
    return gains_job(rig, primitive, lqr_weights)


def solve_from_guess_or_blend(model: VehicleModel, spec: PrimitiveSpec, limits: PlanningLimits, start, end,
                              guess: Optional[Primitive] = None,
                              settings: SolverSettings = SolverSettings()) -> Primitive:
    """The solve a library build runs for each primitive: solve_primitive from guess, with one retry.

    If IPOPT gives up from guess, it solves once more from the plain blend of the boundary states (guess None) before
    the PrimitiveSolveError: IPOPT's infeasibility verdicts depend on where it starts, and where a start leads it
    depends on the round-off of the machine's linear algebra.
    """
    try:
        return solve_primitive(model, spec, limits, start=start, end=end, guess=guess, settings=settings)
    except PrimitiveSolveError:
        if guess is None:
            raise
        return solve_primitive(model, spec, limits, start=start, end=end, guess=None, settings=settings)


def dependencies(spec: PrimitiveSpec) -> list[str]:
    """The ids of the primitives spec joins at its start and end, which are solved before it."""
    return [d for d in (spec.start_from, spec.end_at) if d is not None]


def expected_work(spec: PrimitiveSpec) -> int:
    """A spec's solve cost in collocation intervals times NLP solves.

    Its continuation's steps (a first one without the bound, each looser bound, the last) on its coarser grid if it has
    one, then one solve on its own grid.
    """
    continuation = spec.angle_of_attack_continuation_rad
    steps = len(continuation) + 2 if continuation else 1
    if spec.coarse_intervals is None:
        return steps * spec.intervals
    return steps * spec.coarse_intervals + spec.intervals


def critical_work(specs: Sequence[PrimitiveSpec]) -> dict[str, int]:
    """Each spec's bottom level: {id: its expected_work plus the most expected_work of any chain that joins it}.

    A build starts the ready spec of most critical work first, so a cruise whose decelerate is long goes before a short
    transition, and the long solves before the short ones, which fill in at the end (list scheduling, longest path
    first).
    """
    joined_by: dict[str, list[PrimitiveSpec]] = {}
    for spec in specs:
        for dependency in dependencies(spec):
            joined_by.setdefault(dependency, []).append(spec)
    work: dict[str, int] = {}

    def of(spec: PrimitiveSpec) -> int:
        if spec.primitive_id not in work:
            work[spec.primitive_id] = expected_work(spec) + max(
                (of(after) for after in joined_by.get(spec.primitive_id, [])), default=0)
        return work[spec.primitive_id]

    for spec in specs:
        of(spec)
    return work


def _stale(library: PrimitiveLibrary, specs: Sequence[PrimitiveSpec]) -> set[str]:
    """Stored primitives whose spec changed, and everything that joins them (their states may move)."""
    stale = {s.primitive_id for s in specs if s.primitive_id in library and library.spec(s.primitive_id) != s}
    grew = True
    while grew:
        grew = False
        for spec in specs:
            if spec.primitive_id not in stale and any(d in stale for d in dependencies(spec)):
                stale.add(spec.primitive_id)
                grew = True
    return stale


def build_library(  # noqa: C901 - the build's stages in dependency order (solve, gains, D(t)), each resumable
        library: PrimitiveLibrary, specs: Sequence[PrimitiveSpec], executor: concurrent.futures.Executor,
        limits: Optional[PlanningLimits] = None, progress: Progress = lambda i, s: None,
        workers: Optional[int] = None) -> list[str]:
    """Solve every spec not yet in the library within limits (None: PlanningLimits.of(library.rig)).

    Returns the ids that failed (with their reasons reported).

    workers: the executor's worker count, if known. The build then keeps that many solves running and, each time
    one ends, submits the ready spec of most ``critical_work``. None (a cluster whose size may change): every spec
    is submitted as soon as what it joins is solved, those ready together in that order.

    Raises
    ------
        ValueError: workers below 1, or a spec that joins a primitive neither in specs nor in the library; nothing
            is solved or stored then.
    """
    if workers is not None and workers < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    limits = PlanningLimits.of(library.rig) if limits is None else limits
    known = {s.primitive_id for s in specs} | set(library.ids())
    for spec in specs:
        missing = [d for d in dependencies(spec) if d not in known]
        if missing:
            raise ValueError(f"{spec.primitive_id} depends on unknown primitives: {', '.join(missing)}")
    stale = _stale(library, specs)
    pending = [s for s in specs if s.primitive_id not in library or s.primitive_id in stale]
    gain_jobs = {}
    for spec in specs:
        if spec.primitive_id in library and spec.primitive_id not in stale:
            if library.needs_gains(spec.primitive_id):
                # solved before, gains missing or for other weights: compute only those
                gain_jobs[executor.submit(gains_job, library.rig, library.get(spec.primitive_id),
                                          library.lqr_weights)] = spec.primitive_id
            else:
                progress(spec.primitive_id, "cached")
    failed: list[str] = []
    for future in concurrent.futures.as_completed(gain_jobs):
        try:
            library.add(future.result())
            progress(gain_jobs[future], "gains computed")
        except PrimitiveSolveError as err:
            failed.append(gain_jobs[future])
            progress(gain_jobs[future], f"failed: {err}")
    priority = critical_work(specs)
    running: dict[concurrent.futures.Future, PrimitiveSpec] = {}
    while pending or running:
        for spec in sorted(pending, key=lambda s: priority[s.primitive_id], reverse=True):
            deps = dependencies(spec)
            if any(d in failed for d in deps):
                pending.remove(spec)
                failed.append(spec.primitive_id)
                progress(spec.primitive_id, "skipped: a primitive it joins failed")
            elif all(d in library and d not in stale for d in deps) and (workers is None or len(running) < workers):
                pending.remove(spec)
                start = library.get(spec.start_from).end_boundary_state if spec.start_from else None
                end = library.get(spec.end_at).start_boundary_state if spec.end_at else None
                cruise = library.get(cast(str, spec.start_from or spec.end_at)) if deps else None
                running[executor.submit(solve_job, library.rig, spec, limits, library.solver, start, end,
                                        cruise, library.lqr_weights, library.flow_model)] = spec
        if not running:
            break
        done, _ = concurrent.futures.wait(running, return_when=concurrent.futures.FIRST_COMPLETED)
        for future in done:
            spec = running.pop(future)
            try:
                library.add(future.result())
                stale.discard(spec.primitive_id)
                progress(spec.primitive_id, "solved")
            except PrimitiveSolveError as err:
                failed.append(spec.primitive_id)
                progress(spec.primitive_id, f"failed: {err}")
    if library.flow_model == "circulatory":
        failed += measure_disturbance_bounds(library, [s for s in specs if s.primitive_id not in failed], executor,
                                             progress)
    return failed


def measure_disturbance_bounds(library: PrimitiveLibrary, specs: Sequence[PrimitiveSpec],
                               executor: concurrent.futures.Executor,
                               progress: Progress = lambda i, s: None) -> list[str]:
    """Measure and store D(t) of every spec's primitive in the library that has none (disturbance_job, on the executor).

    Returns the ids whose measurement failed (their reasons reported) or whose wake history is missing.
    """
    jobs: dict[concurrent.futures.Future, str] = {}
    failed: list[str] = []
    for spec in specs:
        if spec.primitive_id not in library or not library.needs_disturbance_bound(spec.primitive_id):
            continue
        missing = [i for i in lead_in_ids(spec) if i not in library]
        if missing:
            failed.append(spec.primitive_id)
            progress(spec.primitive_id, f"no disturbance bound: the primitives before it, {', '.join(missing)}, "
                                        "are not in the library")
            continue
        lead_in = [library.get(i) for i in lead_in_ids(spec)]
        jobs[executor.submit(disturbance_job, library.rig, library.get(spec.primitive_id), lead_in)] = \
            spec.primitive_id
    for future in concurrent.futures.as_completed(jobs):
        try:
            primitive_id, bound, record = future.result()
            library.add_disturbance_bound(primitive_id, bound, record)
            progress(primitive_id, f"disturbance bound measured (largest {bound.max():.3g} N m)")
        except (ManeuverError, ValueError) as err:
            failed.append(jobs[future])
            progress(jobs[future], f"disturbance bound failed: {err}")
    return failed
