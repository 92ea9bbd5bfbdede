"""The default primitive sets: the constrained graph of Fig. 9 and the free two-lane graph of Fig. 12.

Ids name what a primitive joins, e.g. ``constrained/cruise/E0.05``, ``constrained/accelerate/E0.05``,
``free/lane_change/R0.43-R0.48/E0.05``. Durations are the paper's (Sec. 7; docs/model_and_method.md section 3):
constrained accelerate 4 s, cruise 5 s (5 cycles of 1 s), cruise-to-cruise 2 s, decelerate 4 s;
free accelerate 3 s, cruise 1 s, lane change 2 s outward (3 s inward, assumed), decelerate 3 s
(cruise-to-cruise 2 s, as constrained).
"""
from __future__ import annotations

import itertools

from swim_model import RigParameters
from swim_planner.primitives import PrimitiveSpec, PrimitiveType

ENERGY_LEVELS_J = (0.05, 0.1)          # Sec. 7: E = 0.05 and 0.1
INTERVALS_PER_S = 20                   # collocation intervals per second of a transition primitive
CRUISE_INTERVALS = 80                  # per 1 s cruise cycle: with 40 the optimizer exploited the
                                       # discretization (J 29 % above the converged value, open-loop
                                       # replay 0.13 rad off); 80 agree with 60 to 1e-4 in J
INWARD_LANE_CHANGE_S = 3.0
CRUISE_CYCLE_S = 1.0                   # assumed: one stroke per second, as the paper's cruise figures


def energy_tag(energy_j: float) -> str:
    return f"E{energy_j:.2f}"


def lane_tag(radius_m: float) -> str:
    return f"R{radius_m:.2f}"


def cruise_id(constrained: bool, energy_j: float, lane_m: float | None = None) -> str:
    if constrained:
        return f"constrained/cruise/{energy_tag(energy_j)}"
    assert lane_m is not None, "a free cruise's id names its lane"
    return f"free/cruise/{lane_tag(lane_m)}/{energy_tag(energy_j)}"


def _intervals(duration_s: float) -> int:
    return max(20, int(round(INTERVALS_PER_S * duration_s)))


def constrained_specs(rig: RigParameters) -> list[PrimitiveSpec]:
    lane = rig.constrained_lane_radius_m
    specs = []
    for energy in ENERGY_LEVELS_J:
        cruise = cruise_id(True, energy)
        specs.append(PrimitiveSpec(cruise, PrimitiveType.CRUISE, True, 5.0, lane, lane, energy_j=energy,
                                   intervals=CRUISE_INTERVALS, cycles=int(round(5.0 / CRUISE_CYCLE_S))))
        specs.append(PrimitiveSpec(f"constrained/accelerate/{energy_tag(energy)}", PrimitiveType.ACCELERATE, True,
                                   4.0, lane, lane, end_at=cruise, intervals=_intervals(4.0)))
        specs.append(PrimitiveSpec(f"constrained/decelerate/{energy_tag(energy)}", PrimitiveType.DECELERATE, True,
                                   4.0, lane, lane, start_from=cruise, intervals=_intervals(4.0)))
    for low, high in itertools.permutations(ENERGY_LEVELS_J, 2):
        specs.append(PrimitiveSpec(f"constrained/cruise_to_cruise/{energy_tag(low)}-{energy_tag(high)}",
                                   PrimitiveType.CRUISE_TO_CRUISE, True, 2.0, lane, lane,
                                   start_from=cruise_id(True, low), end_at=cruise_id(True, high),
                                   speeding_up=high > low, intervals=_intervals(2.0)))
    return specs


def free_specs(rig: RigParameters) -> list[PrimitiveSpec]:
    lanes = (rig.lane_1_radius_m, rig.lane_2_radius_m)
    specs = []
    for lane, energy in itertools.product(lanes, ENERGY_LEVELS_J):
        tags = f"{lane_tag(lane)}/{energy_tag(energy)}"
        cruise = cruise_id(False, energy, lane)
        specs.append(PrimitiveSpec(cruise, PrimitiveType.CRUISE, False, 1.0, lane, lane, energy_j=energy,
                                   intervals=CRUISE_INTERVALS, cycles=1))
        specs.append(PrimitiveSpec(f"free/accelerate/{tags}", PrimitiveType.ACCELERATE, False, 3.0, lane, lane,
                                   end_at=cruise, intervals=_intervals(3.0)))
        specs.append(PrimitiveSpec(f"free/decelerate/{tags}", PrimitiveType.DECELERATE, False, 3.0, lane, lane,
                                   start_from=cruise, intervals=_intervals(3.0)))
    for lane in lanes:
        for low, high in itertools.permutations(ENERGY_LEVELS_J, 2):
            specs.append(PrimitiveSpec(
                f"free/cruise_to_cruise/{lane_tag(lane)}/{energy_tag(low)}-{energy_tag(high)}",
                PrimitiveType.CRUISE_TO_CRUISE, False, 2.0, lane, lane, start_from=cruise_id(False, low, lane),
                end_at=cruise_id(False, high, lane), speeding_up=high > low, intervals=_intervals(2.0)))
    for (start_lane, end_lane), energy in itertools.product(itertools.permutations(lanes, 2), ENERGY_LEVELS_J):
        # the paper's lane change (outward, Sec. 7.3) takes 2 s; inward we allow 3 s (assumed: in 2 s the
        # E = 0.05 inward change is infeasible within the planning torque limits)
        duration = 2.0 if end_lane > start_lane else INWARD_LANE_CHANGE_S
        specs.append(PrimitiveSpec(
            f"free/lane_change/{lane_tag(start_lane)}-{lane_tag(end_lane)}/{energy_tag(energy)}",
            PrimitiveType.LANE_CHANGE, False, duration, start_lane, end_lane,
            start_from=cruise_id(False, energy, start_lane), end_at=cruise_id(False, energy, end_lane),
            intervals=_intervals(duration)))
    return specs


def default_specs(rig: RigParameters) -> list[PrimitiveSpec]:
    return constrained_specs(rig) + free_specs(rig)
