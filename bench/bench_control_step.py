"""Benchmark: one control step of the tracker in Python (target median <= 100 us, 99th percentile <= 500 us).

A step is what tracker_node does per state: sample the plan and its time-scaled gains, form the error
state, the LQ feedback, the range guard (the node's, on the bridge file's stops), the I/O linearization
(eqs. 22-23, compiled CasADi), the sliding-mode term and the saturation. Measured on the paper's constrained
maneuver at lambda = 1.2 over 20 000 steps at 1 kHz plan time, states from the plan plus a perturbation.
Prints one JSON line.
"""
import json
import time

import numpy as np

from swim_controller.tracker import CascadeTracker, FoilRangeGuard, model_io_linearization, model_lag_rate
from swim_model import VehicleModel, load_rig
from swim_planner.library import PrimitiveLibrary
from swim_planner.maneuver import concatenate, expand_sequence
from swim_planner.paths import default_library_path

TARGET_MEDIAN_US, TARGET_P99_US = 100.0, 500.0
PAPER = (["constrained/accelerate/E0.05", "constrained/cruise/E0.05", "constrained/cruise_to_cruise/E0.05-E0.10",
          "constrained/cruise/E0.10", "constrained/decelerate/E0.10"], [1, 2, 1, 2, 1])


def step_times_us(flow_model: str) -> tuple[float, float]:
    """(median, 99th percentile) of the tracker's step in us on the paper's maneuver planned with the shipped
    library of flow_model (swim_planner.paths.default_library_path)."""
    rig = load_rig()
    library = PrimitiveLibrary.load(default_library_path(flow_model), rig, flow_model)
    trajectory = concatenate(library, rig, expand_sequence(*PAPER), 1.2)
    model = VehicleModel(rig, constrained=True, flow=flow_model)
    tracker = CascadeTracker(model_io_linearization(model), model.torque_limits(), sample_period_s=0.001,
                             lag_rate=model_lag_rate(model),
                             range_guard=FoilRangeGuard(load_rig().hard_limits_rad))
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
    return float(np.median(micros)), float(np.percentile(micros, 99))


def main() -> None:
    median, p99 = step_times_us("ideal")
    print(json.dumps({"benchmark": "control_step", "median_us": round(median, 1), "p99_us": round(p99, 1),
                      "target_median_us": TARGET_MEDIAN_US, "target_p99_us": TARGET_P99_US,
                      "met": median <= TARGET_MEDIAN_US and p99 <= TARGET_P99_US}))


if __name__ == "__main__":
    main()
