"""Benchmark: simulated seconds per wall second of swim_sim, alone and in the closed loop over DDS.

1. The plant alone (swim_sim.plant, default disturbances, 8 ms periods of 8 RK4 substeps, sinusoidal torques):
   target >= 100x real time.
2. The closed loop in lock-step: sim_node, planner_node and tracker_node as processes over DDS running the
   paper's constrained maneuver (swim-demo); sim time over wall time between the first and last tracked state,
   from the bag's stamps (simulated) and log times (wall): target >= 10x real time.
Prints one JSON line.
"""
import json
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from swim_model import VehicleModel
from swim_sim.disturbances import Disturbances
from swim_sim.plant import Plant

PLANT_TARGET, LOOP_TARGET = 100.0, 10.0


def plant_realtime_factor(constrained: bool, periods: int = 3750) -> float:
    plant = Plant(VehicleModel(constrained=constrained), Disturbances())
    time_s = np.arange(periods) * plant.sample_period_s
    torques = np.column_stack([0.3 * np.sin(2 * np.pi * time_s), 0.05 * np.cos(2 * np.pi * time_s)])
    plant.step(torques[0])
    start = time.perf_counter()
    for torque in torques:
        plant.step(torque)
    return periods * plant.sample_period_s / (time.perf_counter() - start)


def loop_realtime_factor() -> float:
    from swim_bringup.bag import read_messages
    with tempfile.TemporaryDirectory() as work:
        run_dir = Path(work) / "run"
        subprocess.run(["ros2", "run", "swim_bringup", "swim-demo", "--run-dir", str(run_dir)], check=True,
                       capture_output=True)
        stamps = [(log_ns, message.header.stamp) for _, log_ns, message in
                  read_messages(run_dir / "bag", ("tracking_state",))]
    (wall_0, first), (wall_1, last) = stamps[0], stamps[-1]
    simulated_s = (last.sec - first.sec) + 1e-9 * (last.nanosec - first.nanosec)
    return simulated_s / ((wall_1 - wall_0) * 1e-9)


def main() -> None:
    free, constrained = plant_realtime_factor(False), plant_realtime_factor(True)
    loop = loop_realtime_factor()
    print(json.dumps({"benchmark": "simulator_realtime_factor", "plant_free_4dof": round(free, 1),
                      "plant_constrained_3dof": round(constrained, 1), "plant_target": PLANT_TARGET,
                      "closed_loop_over_dds": round(loop, 1), "closed_loop_target": LOOP_TARGET,
                      "meets_target": min(free, constrained) >= PLANT_TARGET and loop >= LOOP_TARGET}))


if __name__ == "__main__":
    main()
