"""Benchmark: simulated seconds per wall second, rigid model, RK4 at 1 ms steps (target >= 200x).

Prints one JSON line for the free (4-DOF) and the constrained (3-DOF) model: 10 s of simulated
swimming (sinusoidal torques), integrated in 1 s chunks the way a simulator node would call it.
"""
import json
import time

import numpy as np

from swim_model import VehicleModel

STEP_S = 0.001
CHUNK_STEPS = 1000
TARGET_REALTIME_FACTOR = 200.0


def realtime_factor(model: VehicleModel, seconds: int = 10) -> float:
    time_s = np.arange(CHUNK_STEPS) * STEP_S
    torques = np.column_stack([0.4 * np.sin(2 * np.pi * time_s), 0.02 * np.cos(2 * np.pi * time_s)])
    q = np.zeros(model.nq)
    if not model.constrained:
        q[1] = model.rig.lane_1_radius_m
    qdot = np.zeros(model.nq)
    model.integrate_rk4(q, qdot, torques, STEP_S)  # compile / load once
    start = time.perf_counter()
    for _ in range(seconds):
        qs, qdots = model.integrate_rk4(q, qdot, torques, STEP_S)
        q, qdot = qs[-1], qdots[-1]
    return seconds / (time.perf_counter() - start)


def main() -> None:
    free = realtime_factor(VehicleModel(constrained=False))
    constrained = realtime_factor(VehicleModel(constrained=True))
    print(json.dumps({"benchmark": "rk4_realtime_factor", "step_s": STEP_S,
                      "free_4dof": round(free, 1), "constrained_3dof": round(constrained, 1),
                      "target": TARGET_REALTIME_FACTOR, "meets_target": free >= TARGET_REALTIME_FACTOR}))


if __name__ == "__main__":
    main()
