"""Benchmark: one control step of the tracker with the circulatory flow model (target median <= 100 us, 99th
percentile <= 500 us, as bench_control_step).

The step of bench_control_step plus the lag-state estimate (LagEstimator: two calls of the compiled lag rate and
its exponential update) and the lag block of the error state, the I/O linearization taking the estimate. The plan
is the circulatory constrained vehicle following a 1 Hz gait for 10 s (swim_controller.testing.circulatory: made
without a planner; its gains of the plan's shape, arbitrary values: a step costs the same for any), stepped over
20 000 steps at 1 kHz plan time, states from the plan plus a perturbation. Prints one JSON line.
"""
import json
import time

import numpy as np

from swim_controller.testing.circulatory import gait_run, plan_from_run
from swim_controller.tracker import CascadeTracker, model_io_linearization, model_lag_rate
from swim_model import VehicleModel, load_rig

TARGET_MEDIAN_US, TARGET_P99_US = 100.0, 500.0
PLAN_S = 10.0


def main() -> None:
    model = VehicleModel(load_rig(), constrained=True, flow="circulatory")
    trajectory = plan_from_run(gait_run(model, PLAN_S), PLAN_S)
    tracker = CascadeTracker(model_io_linearization(model), model.torque_limits(), sample_period_s=0.001,
                             lag_rate=model_lag_rate(model))
    tracker.start(trajectory)
    rng = np.random.default_rng(0)
    durations = []
    for k in range(20000):
        t = (k * 0.001) % trajectory.duration_s
        point = trajectory.sample(t)
        q = point.q + rng.normal(scale=0.01, size=3)
        qdot = point.qdot + rng.normal(scale=0.05, size=3)
        started = time.perf_counter()
        tracker.step(t, q, qdot)
        durations.append(time.perf_counter() - started)
    micros = np.array(durations[1000:]) * 1e6   # after warm-up
    median, p99 = float(np.median(micros)), float(np.percentile(micros, 99))
    print(json.dumps({"benchmark": "control_step_circulatory", "median_us": round(median, 1),
                      "p99_us": round(p99, 1), "target_median_us": TARGET_MEDIAN_US, "target_p99_us": TARGET_P99_US,
                      "met": median <= TARGET_MEDIAN_US and p99 <= TARGET_P99_US}))


if __name__ == "__main__":
    main()
