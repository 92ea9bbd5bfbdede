"""Benchmark: wall time to build the whole circulatory library (target <= 5 min on this 2-core machine).

Builds catalog.circulatory_specs into a temporary directory with two local worker processes, as
`swim-primitives build --flow circulatory` does (bench_library_build.timed_build), and prints one JSON line with
the ids that failed (docs/circulatory_primitives.md says which do and why).
"""
import json

from bench_library_build import timed_build

from swim_model import load_rig
from swim_planner.catalog import circulatory_specs

TARGET_S = 300.0


def main() -> None:
    specs = circulatory_specs(load_rig())
    wall, failed = timed_build(specs, "circulatory")
    print(json.dumps({"benchmark": "circulatory_library_build", "primitives": len(specs), "failed": sorted(failed),
                      "wall_s": round(wall, 1), "target_s": TARGET_S, "meets_target": wall <= TARGET_S}))


if __name__ == "__main__":
    main()
