"""Benchmark: simulated seconds per wall second with the circulatory flow, RK4 at 1 ms steps (target >= 200x).

Prints one JSON line for the free (4-DOF) and the constrained (3-DOF) vehicle with flow="circulatory" (state q,
qdot and the flow's 2 lag states): 1 s chunks of simulated swimming (sinusoidal torques), integrated the way a
simulator node would call it, as bench_rk4_realtime.py. Each circulatory chunk alternates with a chunk of the ideal
model, so both meet the same load on a shared host: the ratio of their speeds is robust where the speeds are not.
The factors are medians over the chunks; ``best`` is the fastest chunk (the least disturbed).
"""
import json
import statistics
import time

import numpy as np

from swim_model import VehicleModel

STEP_S = 0.001
CHUNK_STEPS = 1000
CHUNKS = 10
TARGET_REALTIME_FACTOR = 200.0


class Runner:
    """Integrates one model chunk by chunk from a swimming start, timing each chunk."""

    def __init__(self, model: VehicleModel) -> None:
        self.model = model
        time_s = np.arange(CHUNK_STEPS) * STEP_S
        self.torques = np.column_stack([0.4 * np.sin(2 * np.pi * time_s), 0.02 * np.cos(2 * np.pi * time_s)])
        q = np.zeros(model.nq)
        if not model.constrained:
            q[1] = model.rig.lane_1_radius_m
        self.state = (q, np.zeros(model.nq)) + ((np.zeros(model.n_lag),) if model.n_lag else ())
        self.factors: list[float] = []
        self.chunk(timed=False)  # compile / load once

    def chunk(self, timed: bool = True) -> None:
        q, qdot, *lag = self.state
        start = time.perf_counter()
        if lag:
            trajectory = self.model.integrate_rk4(q, qdot, self.torques, STEP_S, lag=lag[0])
        else:
            trajectory = self.model.integrate_rk4(q, qdot, self.torques, STEP_S)
        elapsed = time.perf_counter() - start
        self.state = tuple(x[-1] for x in trajectory)
        if timed:
            self.factors.append(CHUNK_STEPS * STEP_S / elapsed)


def main() -> None:
    result = {"benchmark": "flow_rk4_realtime_factor", "step_s": STEP_S, "flow": "circulatory"}
    for label, constrained in (("free_4dof", False), ("constrained_3dof", True)):
        circulatory = Runner(VehicleModel(constrained=constrained, flow="circulatory"))
        ideal = Runner(VehicleModel(constrained=constrained))
        for _ in range(CHUNKS):
            circulatory.chunk()
            ideal.chunk()
        result[label] = round(statistics.median(circulatory.factors), 1)
        result[f"{label}_best"] = round(max(circulatory.factors), 1)
        result[f"ideal_{label}_same_run"] = round(statistics.median(ideal.factors), 1)
        result[f"{label}_speed_vs_ideal"] = round(statistics.median(
            c / i for c, i in zip(circulatory.factors, ideal.factors)), 3)
    result.update({"target": TARGET_REALTIME_FACTOR, "meets_target": result["free_4dof"] >= TARGET_REALTIME_FACTOR})
    print(json.dumps(result))


if __name__ == "__main__":
    main()
