"""Benchmark: swim_model.flow.oscillating_foil with the reduced model, 20 cycles (target under 0.5 s).

Prints one JSON line: the wall time of one call (best and median of 5, after one call that builds the model's
functions) on the rig's foil towed at 0.2 m/s, heaving 0.75 chord and pitching with the nominal angle of attack
15 deg at St = 0.3, pitch leading by 90 deg (about the middle of Anderson et al.'s series), and its results.
"""
import json
import math
import statistics
import time

from swim_model import JoukowskiFoil, load_rig
from swim_model.flow import oscillating_foil

CYCLES = 20
TARGET_S = 0.5
SPEED_M_S = 0.2
STROUHAL = 0.3


def main() -> None:
    rig = load_rig()
    foil = JoukowskiFoil(rig.foil_chord_m, rig.foil_max_thickness_m, rig.foil_span_m)
    heave = 0.75 * rig.foil_chord_m
    settings = dict(speed_m_s=SPEED_M_S, heave_amplitude_m=heave,
                    pitch_amplitude_rad=math.atan(math.pi * STROUHAL) - math.radians(15.0),
                    frequency_hz=STROUHAL * SPEED_M_S / (2.0 * heave), phase_rad=math.pi / 2,
                    pivot_from_leading_edge_m=rig.foil_chord_m / 3, model="circulatory", cycles=CYCLES,
                    water_density_kg_m3=rig.water_density_kg_m3)
    oscillating_foil(foil, **settings)
    times = []
    for _ in range(5):
        start = time.perf_counter()
        result = oscillating_foil(foil, **settings)
        times.append(time.perf_counter() - start)
    print(json.dumps({"benchmark": "flow_oscillating_foil", "model": "circulatory", "cycles": CYCLES,
                      "steps_per_cycle": result.steps_per_cycle, "best_s": round(min(times), 4),
                      "median_s": round(statistics.median(times), 4),
                      "thrust_coefficient": round(result.thrust_coefficient, 4),
                      "efficiency": round(result.efficiency, 4), "target_s": TARGET_S,
                      "meets_target": statistics.median(times) < TARGET_S}))


if __name__ == "__main__":
    main()
