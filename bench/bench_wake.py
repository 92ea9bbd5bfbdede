"""Benchmark: the free-vortex wake (issue 7) at the 8 ms control period over the paper's 30 s maneuver.

Prints one JSON line: simulated seconds per wall second (target >= 1x real time) and the vortex count reached.
Prescribed motion of the paper's size (assumed, no plant in the loop): the foil circles the hub on lane 1
(R = 0.43 m) at 0.25 rad/s, heaves radially with the 15 cm link swinging +-0.3 rad at 0.8 Hz, and pitches to
follow its path with a feathering of 0.2 (angle of attack 20 % of the path angle), so it sheds a reverse von
Karman street and meets its own wake on later laps (one lap takes 25 s). The wake's compiled kernels are loaded
(or compiled) before the clock starts (swim_model.wake.compile_kernels).
"""
import json
import math
import time

import numpy as np

from swim_model import JoukowskiFoil, load_rig
from swim_model.wake import Wake, WakeParameters, compile_kernels

STEP_S = 0.008
DURATION_S = 30.0
TARGET_REALTIME_FACTOR = 1.0
HUB_RATE_RAD_S = 0.25       # assumed: about 0.1 m/s along lane 1
GAIT_FREQUENCY_HZ = 0.8     # assumed: of the order of the paper's gaits
HEAVE_ANGLE_RAD = 0.3       # assumed: heave link swing amplitude
FEATHERING = 0.2            # assumed: angle of attack / path angle (0: chord along the path)


def foil_pose(time_s: float, lane_radius_m: float, heave_link_m: float) -> tuple[float, float, float]:
    """(x, y, theta) of the foil frame in the tank frame at time_s."""
    phase = 2.0 * math.pi * GAIT_FREQUENCY_HZ * time_s
    hub_angle = HUB_RATE_RAD_S * time_s
    omega = 2.0 * math.pi * GAIT_FREQUENCY_HZ
    link = HEAVE_ANGLE_RAD * math.sin(phase)
    radius = lane_radius_m + heave_link_m * math.sin(link)
    radial_speed = heave_link_m * math.cos(link) * HEAVE_ANGLE_RAD * omega * math.cos(phase)
    path_angle = -math.atan2(radial_speed, radius * HUB_RATE_RAD_S)  # outward motion turns the path clockwise
    theta = hub_angle + math.pi / 2.0 + (1.0 - FEATHERING) * path_angle
    return radius * math.cos(hub_angle), radius * math.sin(hub_angle), theta


def foil_velocity(time_s: float, lane_radius_m: float, heave_link_m: float) -> tuple[float, float, float]:
    """(U, V, Omega) in foil axes by a central difference of the pose (step 1e-6 s)."""
    eps = 1e-6
    before, after = foil_pose(time_s - eps, lane_radius_m, heave_link_m), foil_pose(time_s + eps, lane_radius_m,
                                                                                   heave_link_m)
    vx, vy = (after[0] - before[0]) / (2 * eps), (after[1] - before[1]) / (2 * eps)
    theta = foil_pose(time_s, lane_radius_m, heave_link_m)[2]
    u = vx * math.cos(theta) + vy * math.sin(theta)
    v = -vx * math.sin(theta) + vy * math.cos(theta)
    return u, v, (after[2] - before[2]) / (2 * eps)


def main() -> None:
    compile_kernels()
    rig = load_rig()
    foil = JoukowskiFoil(rig.foil_chord_m, rig.foil_max_thickness_m, rig.foil_span_m)
    params = WakeParameters(rho_kg_m3=rig.water_density_kg_m3)
    wake = Wake(foil, params)
    steps = round(DURATION_S / STEP_S)
    fx_n = []
    start = time.perf_counter()
    for n in range(1, steps + 1):
        t = n * STEP_S
        force = wake.step(STEP_S, foil_pose(t, rig.lane_1_radius_m, rig.heave_link_length_m),
                          foil_velocity(t, rig.lane_1_radius_m, rig.heave_link_length_m))
        fx_n.append(force.fx_n)
    wall_s = time.perf_counter() - start
    factor = DURATION_S / wall_s
    print(json.dumps({"benchmark": "wake_realtime_factor", "step_s": STEP_S, "simulated_s": DURATION_S,
                      "realtime_factor": round(factor, 2), "vortex_count": wake.vortex_count(),
                      "max_vortex_count": params.max_vortex_count, "vortices_shed": steps,
                      "merged": wake.merged_count, "reflected_into_foil": wake.reflected_count,
                      "mean_fx_n": round(float(np.mean(fx_n)), 4),
                      "p99_abs_fx_n": round(float(np.percentile(np.abs(fx_n), 99)), 4),
                      "max_abs_fx_n": round(float(np.max(np.abs(fx_n))), 4),
                      "target": TARGET_REALTIME_FACTOR, "meets_target": factor >= TARGET_REALTIME_FACTOR}))


if __name__ == "__main__":
    main()
