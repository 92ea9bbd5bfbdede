"""Benchmark: simulated seconds per wall second of swim_sim, alone and in the closed loop over DDS.

1. The plant alone: swim_model.plant.Plant.step, the call sim_node makes each period, no ROS. The free and the
   constrained vehicle, default disturbances, 8 ms periods of 8 RK4 substeps, sinusoidal torques computed in
   advance but handed over one period at a time, 3750 periods (the paper's 30 s maneuver). Target >= 100x real
   time. Best and median of PLANT_REPEATS runs.
2. The closed loop in lock-step over DDS: sim_node, planner_node and tracker_node as separate processes with the
   demo's parameter files (swim_bringup's System), the paper's constrained maneuver (30 s). Steady state: the
   simulated time over the wall time between the first and the last action feedback the tracker sends (5 Hz;
   each carries the tracking state's stamp, the simulated time). Whole goal: the plan's duration over the wall
   time from acceptance to result. No recorder: swim-demo's bag recorder is a fourth process that takes three
   messages a period (bench_demo_walltime.py times the demo), and no visualization nodes (swim_viz). Target >=
   10x, steady state. Best and median of LOOP_REPEATS goals, the vehicle put back at its start (sim_node's reset
   service) before each.

Both share the host: the JSON line carries the load average before and after.
Prints one JSON line.
"""
from __future__ import annotations

import json
import os
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from swim_model import VehicleModel
from swim_model.disturbances import Disturbances
from swim_model.plant import Plant

PLANT_TARGET, LOOP_TARGET = 100.0, 10.0
PLANT_REPEATS, LOOP_REPEATS = 5, 3
PERIODS_30_S = 3750
#: the paper's constrained maneuver (Sec. 7.1), as swim-demo runs it
MANEUVER = (["constrained/accelerate/E0.05", "constrained/cruise/E0.05", "constrained/cruise_to_cruise/E0.05-E0.10",
             "constrained/cruise/E0.10", "constrained/decelerate/E0.10"], [1, 2, 1, 2, 1])
STARTUP_TIMEOUT_S, GOAL_TIMEOUT_S = 120.0, 300.0


def plant_realtime_factors(constrained: bool) -> list[float]:
    """Simulated over wall seconds of PLANT_REPEATS runs of PERIODS_30_S periods."""
    plant = Plant(VehicleModel(constrained=constrained), Disturbances())
    time_s = np.arange(PERIODS_30_S) * plant.sample_period_s
    torques = np.column_stack([0.3 * np.sin(2 * np.pi * time_s), 0.05 * np.cos(2 * np.pi * time_s)])
    factors = []
    for _ in range(PLANT_REPEATS):
        plant.reset(plant.rest_positions(), np.zeros(plant.model.nq))
        started = time.perf_counter()
        for torque in torques:
            plant.step(torque)
        factors.append(PERIODS_30_S * plant.sample_period_s / (time.perf_counter() - started))
    return factors


class LoopClient:
    """The bench's side of the loop: the planner's service, the tracker's action, the simulator's reset."""

    def __init__(self) -> None:
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from std_srvs.srv import Trigger
        from swim_interfaces.action import ExecutePlan
        from swim_interfaces.srv import RequestManeuver

        from swim_ros.calls import ActionClient, GoalStatusWatch
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node("bench_simulator", context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.planner = self.node.create_client(RequestManeuver, "request_maneuver")
        self.reset = self.node.create_client(Trigger, "reset")
        self.tracker = ActionClient(self.node, ExecutePlan, "execute_plan")
        self.tracker_status = GoalStatusWatch(self.node, "execute_plan")

    def close(self) -> None:
        import rclpy
        rclpy.try_shutdown(context=self.context)

    def plan(self):
        from swim_interfaces.srv import RequestManeuver

        from swim_ros.calls import RetryPolicy, call_service, new_request_id
        reply = call_service(self.executor, self.planner, RequestManeuver.Request(
            primitive_ids=MANEUVER[0], repeat_counts=MANEUVER[1], time_scale=1.0, request_id=new_request_id()),
            RetryPolicy(discovery_timeout_s=STARTUP_TIMEOUT_S))
        if not reply.success:
            raise RuntimeError(f"the planner refused the maneuver: {reply.message}")
        return reply.plan

    def run(self, plan) -> tuple[float, float]:
        """(steady-state, whole-goal) simulated over wall seconds of one execution of plan from the start."""
        from std_srvs.srv import Trigger
        from swim_interfaces.action import ExecutePlan

        from swim_ros.calls import RetryPolicy, call_service, goal_result, send_goal
        if not call_service(self.executor, self.reset, Trigger.Request()).success:
            raise RuntimeError("sim_node refused the reset")
        feedback: list[tuple[float, float]] = []   # (wall s, simulated s)

        def on_feedback(message) -> None:
            stamp = message.feedback.state.header.stamp
            feedback.append((time.monotonic(), stamp.sec + 1e-9 * stamp.nanosec))
        started = time.monotonic()
        handle = send_goal(self.executor, self.tracker, ExecutePlan.Goal(plan=plan), self.tracker_status,
                           on_feedback, RetryPolicy(discovery_timeout_s=STARTUP_TIMEOUT_S))
        if not handle.accepted:
            raise RuntimeError("the tracker refused the goal")
        result = goal_result(self.executor, handle, GOAL_TIMEOUT_S).result
        whole = result.duration_s / (time.monotonic() - started)
        if result.error_code != ExecutePlan.Result.SUCCESSFUL or len(feedback) < 2:
            raise RuntimeError(f"the maneuver failed: {result.error_string} ({len(feedback)} feedback messages)")
        (wall_0, simulated_0), (wall_1, simulated_1) = feedback[0], feedback[-1]
        return (simulated_1 - simulated_0) / (wall_1 - wall_0), whole


def loop_realtime_factors() -> tuple[list[float], list[float]]:
    """Steady-state and whole-goal factors of LOOP_REPEATS executions in one bring-up."""
    from swim_bringup.system import System, closed_loop_specs, config_dir
    from swim_ros.domains import run_domain
    run_domain()   # a domain of our own unless the user chose one: never another session's nodes
    steady, whole = [], []
    specs = closed_loop_specs(config_dir(), visualization=False)
    with tempfile.TemporaryDirectory() as logs, System(specs, Path(logs)):
        client = LoopClient()
        try:
            plan = client.plan()
            for _ in range(LOOP_REPEATS):
                factors = client.run(plan)
                steady.append(factors[0])
                whole.append(factors[1])
        finally:
            client.close()
    return steady, whole


def summary(factors: list[float]) -> dict[str, float]:
    return {"best": round(max(factors), 1), "median": round(statistics.median(factors), 1)}


def main() -> None:
    from swim_ros.processes import interrupt_on_sigterm
    interrupt_on_sigterm()   # SIGTERM stops the nodes as Ctrl-C does
    load_before = os.getloadavg()[0]
    free, constrained = plant_realtime_factors(False), plant_realtime_factors(True)
    steady, whole = loop_realtime_factors()
    print(json.dumps({
        "benchmark": "simulator_realtime_factor",
        "plant_free_4dof": summary(free), "plant_constrained_3dof": summary(constrained), "plant_target": PLANT_TARGET,
        "closed_loop_over_dds": summary(steady), "closed_loop_whole_goal": summary(whole),
        "closed_loop_target": LOOP_TARGET,
        "meets_target": min(max(free), max(constrained)) >= PLANT_TARGET and max(steady) >= LOOP_TARGET,
        "load_average_1min": [round(load_before, 2), round(os.getloadavg()[0], 2)]}))


if __name__ == "__main__":
    main()
