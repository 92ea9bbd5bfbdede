"""Benchmark: one control step of the tracker with the circulatory flow model (target median <= 100 us, 99th
percentile <= 500 us, as bench_control_step).

The step of bench_control_step plus the lag-state estimate (LagEstimator: two calls of the compiled lag rate and
its exponential update), the lag block of the error state and the I/O linearization taking the estimate, on the
paper's constrained maneuver at lambda = 1.2 planned with the shipped circulatory library. Prints one JSON line.
"""
import json

from bench_control_step import TARGET_MEDIAN_US, TARGET_P99_US, step_times_us


def main() -> None:
    median, p99 = step_times_us("circulatory")
    print(json.dumps({"benchmark": "control_step_circulatory", "median_us": round(median, 1),
                      "p99_us": round(p99, 1), "target_median_us": TARGET_MEDIAN_US, "target_p99_us": TARGET_P99_US,
                      "met": median <= TARGET_MEDIAN_US and p99 <= TARGET_P99_US}))


if __name__ == "__main__":
    main()
