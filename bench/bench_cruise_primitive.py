"""Benchmark: time to compute one cruise primitive (target <= 10 s on this 2-core machine), and its index J.

Solves the default constrained E = 0.05 cruise (one 1 s cycle, 80 Hermite-Simpson intervals) from the
built-in initial guess, and the same cruise by the paper's method (2-harmonic Fourier series, Nelder-Mead,
8000 evaluations). Prints one JSON line with both: wall time, index J per cycle, energy error, and the speed-up
(target >= 10x at equal or better J).

The model's pointwise function and its derivatives are compiled to C once per machine and model and cached on
disk (swim_planner.pointwise), as the model itself is: that is done before the timing and reported apart as
``compile_s`` (about 5 s the first time, a cache lookup after).
"""
import json
import time

from swim_model import VehicleModel, load_rig
from swim_planner.catalog import constrained_specs
from swim_planner.paper_method import solve_fourier_cruise
from swim_planner.primitive_solver import pointwise_function, solve_primitive
from swim_planner.primitives import Primitive, PrimitiveSpec

TARGET_S = 10.0
TARGET_SPEEDUP = 10.0


def timed_solve(model: VehicleModel, spec: PrimitiveSpec) -> tuple[Primitive, float, float]:
    """(the primitive, its solve's wall time s, the pointwise function's compile or cache-load time s), the
    compiled model and pointwise function loaded before the solve's timing."""
    model.numeric  # load the compiled model outside the timing
    start = time.perf_counter()
    pointwise_function(model)
    compile_s = time.perf_counter() - start
    start = time.perf_counter()
    primitive = solve_primitive(model, spec)
    return primitive, time.perf_counter() - start, compile_s


def main() -> None:
    rig = load_rig()
    spec = next(s for s in constrained_specs(rig) if s.primitive_id == "constrained/cruise/E0.05")
    model = VehicleModel(rig, constrained=True, lane_radius_m=spec.lane_radius_m)
    primitive, wall, compile_s = timed_solve(model, spec)
    paper = solve_fourier_cruise(model, spec, max_evaluations=8000)
    print(json.dumps({"benchmark": "cruise_primitive", "primitive": spec.primitive_id,
                      "wall_s": round(wall, 2), "ipopt_s": round(primitive.solve_time_s, 2),
                      "iterations": primitive.iterations, "compile_s": round(compile_s, 2),
                      "index_j_per_cycle": round(primitive.index_j / spec.cycles, 5),
                      "paper_method_wall_s": round(paper.wall_s, 2), "paper_method_index_j_per_cycle":
                      round(paper.index_j, 5), "paper_method_energy_error_j": round(paper.energy_error_j, 5),
                      "speedup": round(paper.wall_s / wall, 2), "target_s": TARGET_S,
                      "target_speedup": TARGET_SPEEDUP,
                      "meets_target": wall <= TARGET_S and paper.wall_s / wall >= TARGET_SPEEDUP
                      and primitive.index_j / spec.cycles >= paper.index_j}))


if __name__ == "__main__":
    main()
