"""Benchmark: the simulator with the vortex wake on (issue 7), at the 8 ms control period, over the paper's 30 s
constrained maneuver in closed loop (target >= 1x real time, so the wake can run in a live closed loop).

The tracker (swim_controller.testing.closed_loop, in one process) drives swim_sim's Plant with the default disturbances
(seed 1, as the demo) and the wake on; measured: simulated seconds per wall second of the simulator's part (the
plant's period with the wake's step, plus the statistics sim_node publishes each period) and of the whole loop,
and the vortex count reached. The same maneuver with the wake off, and with the sliding-mode term off, gives the
tracking numbers beside it (two-norms of alpha, phi, theta in rad s^0.5; hub angle at the end against the plan's).
Prints one JSON line.
"""
import json
import time

import numpy as np

from swim_bringup.experiments import PAPER_CONSTRAINED
from swim_controller.sliding_mode import SlidingMode
from swim_controller.testing.closed_loop import simulate
from swim_controller.tracker import CascadeTracker, model_io_linearization
from swim_model import VehicleModel, load_rig
from swim_model.disturbances import Disturbances
from swim_model.plant import Plant
from swim_model.wake import compile_kernels
from swim_planner.library import PrimitiveLibrary
from swim_planner.maneuver import concatenate, expand_sequence
from swim_planner.paths import default_library_path
from swim_sim.wake_coupling import WakeCoupling

TARGET_REALTIME_FACTOR = 1.0
SEED = 1   # the demo's (swim_bringup/config/sim.yaml)


class TimedPlant:
    """The plant, timed per period together with the wake statistics sim_node computes for each period."""

    def __init__(self, plant: Plant) -> None:
        self.plant, self.wall_s, self.thrust_n, self.hub_torque_n_m = plant, 0.0, [], []

    def reset(self, q, qdot) -> None:
        self.plant.reset(q, qdot)

    def step(self, torque):
        started = time.perf_counter()
        state = self.plant.step(torque)
        if self.plant.wake is not None:
            statistics = self.plant.wake.statistics()
            self.thrust_n.append(statistics.thrust_n)
            self.hub_torque_n_m.append(statistics.generalized_force[0])
        self.wall_s += time.perf_counter() - started
        return state


def closed_loop(model, reference, wake_on: bool, sliding: bool) -> tuple[dict, TimedPlant, float]:
    """One run of the maneuver: (tracking numbers, the timed plant, wall seconds of the whole loop)."""
    tracker = CascadeTracker(model_io_linearization(model), model.torque_limits(), SlidingMode(),
                             sliding_mode_enabled=sliding, sample_period_s=model.rig.sample_period_s)
    plant = TimedPlant(Plant(model, Disturbances(), seed=SEED, wake=WakeCoupling(model) if wake_on else None))
    started = time.perf_counter()
    run = simulate(model, tracker, reference, model.rig.sample_period_s, plant=plant)
    loop_wall_s = time.perf_counter() - started
    numbers = {"two_norms": [round(run.two_norm(i), 4) for i in range(3)],
               "alpha_end_rad": round(float(run.q[-1, 0]), 3),
               "saturated_fraction": round(float(run.saturated.any(axis=1).mean()), 3)}
    if wake_on:
        numbers.update(mean_thrust_n=round(float(np.mean(plant.thrust_n)), 4),
                       mean_hub_torque_n_m=round(float(np.mean(plant.hub_torque_n_m)), 4))
    return numbers, plant, loop_wall_s


def main() -> None:
    rig = load_rig()
    library = PrimitiveLibrary.load(default_library_path(), rig)
    reference = concatenate(library, rig, expand_sequence(*PAPER_CONSTRAINED), 1.0)
    model = VehicleModel(rig, constrained=True, lane_radius_m=library.spec(PAPER_CONSTRAINED[0][0]).lane_radius_m)
    closed_loop(model, reference, False, True)   # compile and warm up
    compile_kernels()                            # the wake's kernels: compiled, or loaded from their cache
    wake_on, timed, loop_wall_s = closed_loop(model, reference, True, True)
    wake = timed.plant.wake
    simulated_s = timed.plant.time_s
    factor = simulated_s / timed.wall_s
    print(json.dumps({
        "benchmark": "wake_simulator_realtime_factor", "period_s": rig.sample_period_s,
        "simulated_s": round(simulated_s, 3), "realtime_factor": round(factor, 2),
        "closed_loop_realtime_factor": round(simulated_s / loop_wall_s, 2),
        "vortex_count": wake.wake.vortex_count(), "max_vortex_count": wake.params.wake.max_vortex_count,
        "merged": wake.wake.merged_count, "reflected_into_foil": wake.wake.reflected_count,
        "clipped_periods": wake.clipped_count,
        "wake_off": closed_loop(model, reference, False, True)[0], "wake_on": wake_on,
        "wake_on_no_sliding_mode": closed_loop(model, reference, True, False)[0],
        "wake_off_no_sliding_mode": closed_loop(model, reference, False, False)[0],
        "alpha_planned_end_rad": round(float(reference.q[-1, 0]), 3),
        "target": TARGET_REALTIME_FACTOR, "meets_target": factor >= TARGET_REALTIME_FACTOR}))


if __name__ == "__main__":
    main()
