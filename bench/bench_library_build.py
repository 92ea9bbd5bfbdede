"""Benchmark: wall time to build the whole default library (target <= 10 min on this 2-core machine).

Builds the 28 default primitives (constrained graph of Fig. 9, free two-lane graph of Fig. 12) into a
temporary directory with two local worker processes, exactly as `swim-primitives build` does, and prints
one JSON line.
"""
import json
import tempfile
import time

from swim_model import load_rig
from swim_planner.build import build_library, local_executor
from swim_planner.catalog import default_specs, lqr_weights
from swim_planner.library import PrimitiveLibrary

TARGET_S = 600.0
WORKERS = 2                      # local worker processes, one per core of this machine


def timed_build(specs, flow_model: str = "ideal") -> tuple[float, list[str]]:
    """(wall time s, failed ids) of building specs into an empty library of flow_model on WORKERS local workers."""
    with tempfile.TemporaryDirectory() as directory:
        library = PrimitiveLibrary.create_or_open(directory, load_rig(), lqr_weights=lqr_weights(flow_model),
                                                  flow_model=flow_model)
        start = time.perf_counter()
        with local_executor(WORKERS) as executor:
            failed = build_library(library, specs, executor, workers=WORKERS)
        return time.perf_counter() - start, failed


def main() -> None:
    specs = default_specs(load_rig())
    wall, failed = timed_build(specs)
    print(json.dumps({"benchmark": "library_build", "primitives": len(specs), "failed": failed,
                      "wall_s": round(wall, 1), "target_s": TARGET_S, "meets_target": wall <= TARGET_S}))

if __name__ == "__main__":
    main()
