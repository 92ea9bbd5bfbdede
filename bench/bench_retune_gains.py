"""Benchmark: tracking gains of every shipped primitive for new LQ weights (target <= 1 s each).

What planner_node does when ``lqr_weights_path`` is set: ``RetunedLibrary.get`` computes a primitive's P(t),
G'P for the new weights on its first use (swim_control.riccati; a cruise with its 30 s lookahead). The
weights here are the library's with a 4x heave input weight. Prints one JSON line: the slowest primitive's
time (best of 3, each with a fresh RetunedLibrary), the median over the library, and the load average.
"""
import dataclasses
import json
import os
import statistics
import time

from swim_model import load_rig
from swim_planner.gains import RetunedLibrary
from swim_planner.library import PrimitiveLibrary
from swim_planner.paths import default_library_path

TARGET_S = 1.0
REPEATS = 3


def main() -> None:
    library = PrimitiveLibrary.load(default_library_path(), load_rig())
    weights = dataclasses.replace(library.lqr_weights, heave_input_weight=4 * library.lqr_weights.heave_input_weight)
    for primitive_id in library.ids():
        library.get(primitive_id)          # read the arrays outside the timing
    best: dict[str, float] = {}
    for _ in range(REPEATS):
        retuned = RetunedLibrary(library, weights)
        for primitive_id in library.ids():
            start = time.perf_counter()
            retuned.get(primitive_id)
            elapsed = time.perf_counter() - start
            best[primitive_id] = min(best.get(primitive_id, elapsed), elapsed)
    slowest = max(best, key=best.get)
    print(json.dumps({"benchmark": "retune_gains", "primitives": len(best), "slowest": slowest,
                      "slowest_s": round(best[slowest], 3), "median_s": round(statistics.median(best.values()), 3),
                      "load_average_1min": round(os.getloadavg()[0], 2), "target_s": TARGET_S,
                      "meets_target": best[slowest] <= TARGET_S}))


if __name__ == "__main__":
    main()
