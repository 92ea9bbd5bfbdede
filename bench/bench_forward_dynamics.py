"""Benchmark: forward-dynamics evaluations per second through swim_model's numeric path.

Prints one JSON line: single calls through the numpy API (what a Python loop gets) and evaluations
inside one compiled call (what the simulator's integrator gets), for the free (4-DOF) model.
"""
import json
import time

import numpy as np

from swim_model import VehicleModel


def rate(function, repeats: int) -> float:
    start = time.perf_counter()
    for _ in range(repeats):
        function()
    return repeats / (time.perf_counter() - start)


def main() -> None:
    model = VehicleModel(constrained=False)
    q, qdot, tau = np.array([0.1, 0.43, 0.2, -0.3]), np.array([0.2, 0.01, 1.0, -2.0]), np.array([0.3, 0.05])
    model.forward_dynamics(q, qdot, tau)  # compile / load once
    api_rate = rate(lambda: model.forward_dynamics(q, qdot, tau), 20000)
    batch = 10000
    mapped = model.numeric["forward_dynamics"].map(batch)
    qs, qdots, taus = np.tile(q[:, None], batch), np.tile(qdot[:, None], batch), np.tile(tau[:, None], batch)
    batched_rate = batch * rate(lambda: mapped(qs, qdots, taus), 20)
    print(json.dumps({"benchmark": "forward_dynamics", "model": "free_4dof",
                      "api_calls_per_s": round(api_rate), "compiled_evaluations_per_s": round(batched_rate)}))


if __name__ == "__main__":
    main()
