"""Benchmark: time to compute the circulatory flow's constrained E = 0.05 cruise (target <= 2 s on this 2-core
machine), the spec of the shipped circulatory library (catalog.circulatory_specs), from the built-in guess.

The model's pointwise function is compiled or loaded before the timing (bench_cruise_primitive.timed_solve) and
reported apart as ``compile_s``. Prints one JSON line: wall time, IPOPT's time and iterations, the cruise's mean
speed.
"""
import json

from bench_cruise_primitive import timed_solve

from swim_model import VehicleModel, load_rig
from swim_planner.catalog import circulatory_specs
from swim_planner.primitives import cruise_mean_speed_m_s

TARGET_S = 2.0


def main() -> None:
    rig = load_rig()
    spec = next(s for s in circulatory_specs(rig) if s.primitive_id == "constrained/cruise/E0.05")
    model = VehicleModel(rig, constrained=True, lane_radius_m=spec.lane_radius_m, flow="circulatory")
    primitive, wall, compile_s = timed_solve(model, spec)
    print(json.dumps({"benchmark": "circulatory_cruise_primitive", "primitive": spec.primitive_id,
                      "wall_s": round(wall, 2), "ipopt_s": round(primitive.solve_time_s, 2),
                      "iterations": primitive.iterations, "compile_s": round(compile_s, 2),
                      "mean_speed_m_s": round(cruise_mean_speed_m_s(primitive), 4), "target_s": TARGET_S,
                      "meets_target": wall <= TARGET_S}))


if __name__ == "__main__":
    main()
