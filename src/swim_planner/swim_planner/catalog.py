"""The primitive sets: the constrained graph of Fig. 9 and the free two-lane graph of Fig. 12 (``default_specs``,
the paper's library, ideal flow), and the same graph with a third, faster energy level for the circulatory flow
(``circulatory_specs``).

Ids name what a primitive joins, e.g. ``constrained/cruise/E0.05``, ``constrained/accelerate/E0.05``,
``free/lane_change/R0.43-R0.48/E0.05``. Durations are the paper's (Sec. 7; docs/model_and_method.md section 3):
constrained accelerate 4 s, cruise 5 s (5 cycles of 1 s), cruise-to-cruise 2 s, decelerate 4 s;
free accelerate 3 s, cruise 1 s, lane change 2 s outward (3 s inward, assumed), decelerate 3 s
(cruise-to-cruise 2 s, as constrained).
"""
from __future__ import annotations

import dataclasses
import itertools

from swim_model import RigParameters
from swim_planner.primitives import PrimitiveSpec, PrimitiveType

ENERGY_LEVELS_J = (0.05, 0.1)          # Sec. 7: E = 0.05 and 0.1
CIRCULATORY_ENERGY_LEVELS_J = ENERGY_LEVELS_J + (0.2,)
# the paper's two levels and a third, faster one (assumed): twice the mean kinetic energy of E = 0.1, as E = 0.1 is
# of E = 0.05, so the levels are evenly spaced in speed ratio (speed ~ sqrt(E): about 1.4x a step). It solves
# with every one of its edges within the planning limits (docs/circulatory_primitives.md); a level far above
# it would need the heave torque past its planning limit to get there from rest in the accelerate's 4 s
INTERVALS_PER_S = 20                   # collocation intervals per second of a transition primitive
CRUISE_INTERVALS = 80                  # per 1 s cruise cycle: with 40 the optimizer exploited the
                                       # discretization (J 29 % above the converged value, open-loop
                                       # replay 0.13 rad off); 80 agree with 60 to 1e-4 in J
INWARD_LANE_CHANGE_S = 3.0
CIRCULATORY_FREE_ACCELERATE_S = 4.0
# circulatory flow (assumed, as the constrained accelerate's 4 s): within its angle-of-attack bound the free
# accelerate gets from rest to a cruise in 4 s and not in the paper's 3 s (IPOPT: the R = 0.43 m, E = 0.05 and
# 0.10 ones infeasible in 3 s from both guesses, solved in 4 s)
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


def _neighbour_pairs(energy_levels_j: tuple[float, ...]) -> list[tuple[float, float]]:
    """(from, to) energy levels of the cruise-to-cruise edges: each level to its neighbours, both ways."""
    pairs = []
    for low, high in zip(energy_levels_j[:-1], energy_levels_j[1:]):
        pairs += [(low, high), (high, low)]
    return pairs


def constrained_specs(rig: RigParameters,
                      energy_levels_j: tuple[float, ...] = ENERGY_LEVELS_J) -> list[PrimitiveSpec]:
    """The constrained graph: a cruise, its accelerate and its decelerate at each level (ascending), and the
    cruise-to-cruise edges between neighbouring levels."""
    lane = rig.constrained_lane_radius_m
    specs = []
    for energy in energy_levels_j:
        cruise = cruise_id(True, energy)
        specs.append(PrimitiveSpec(cruise, PrimitiveType.CRUISE, True, 5.0, lane, lane, energy_j=energy,
                                   intervals=CRUISE_INTERVALS, cycles=int(round(5.0 / CRUISE_CYCLE_S))))
        specs.append(PrimitiveSpec(f"constrained/accelerate/{energy_tag(energy)}", PrimitiveType.ACCELERATE, True,
                                   4.0, lane, lane, end_at=cruise, intervals=_intervals(4.0)))
        specs.append(PrimitiveSpec(f"constrained/decelerate/{energy_tag(energy)}", PrimitiveType.DECELERATE, True,
                                   4.0, lane, lane, start_from=cruise, intervals=_intervals(4.0)))
    for low, high in _neighbour_pairs(energy_levels_j):
        specs.append(PrimitiveSpec(f"constrained/cruise_to_cruise/{energy_tag(low)}-{energy_tag(high)}",
                                   PrimitiveType.CRUISE_TO_CRUISE, True, 2.0, lane, lane,
                                   start_from=cruise_id(True, low), end_at=cruise_id(True, high),
                                   speeding_up=high > low, intervals=_intervals(2.0)))
    return specs


def free_specs(rig: RigParameters, energy_levels_j: tuple[float, ...] = ENERGY_LEVELS_J) -> list[PrimitiveSpec]:
    """The free two-lane graph: in each lane the constrained graph's primitives, and a lane change each way at
    every level."""
    lanes = (rig.lane_1_radius_m, rig.lane_2_radius_m)
    specs = []
    for lane, energy in itertools.product(lanes, energy_levels_j):
        tags = f"{lane_tag(lane)}/{energy_tag(energy)}"
        cruise = cruise_id(False, energy, lane)
        specs.append(PrimitiveSpec(cruise, PrimitiveType.CRUISE, False, 1.0, lane, lane, energy_j=energy,
                                   intervals=CRUISE_INTERVALS, cycles=1))
        specs.append(PrimitiveSpec(f"free/accelerate/{tags}", PrimitiveType.ACCELERATE, False, 3.0, lane, lane,
                                   end_at=cruise, intervals=_intervals(3.0)))
        specs.append(PrimitiveSpec(f"free/decelerate/{tags}", PrimitiveType.DECELERATE, False, 3.0, lane, lane,
                                   start_from=cruise, intervals=_intervals(3.0)))
    for lane in lanes:
        for low, high in _neighbour_pairs(energy_levels_j):
            specs.append(PrimitiveSpec(
                f"free/cruise_to_cruise/{lane_tag(lane)}/{energy_tag(low)}-{energy_tag(high)}",
                PrimitiveType.CRUISE_TO_CRUISE, False, 2.0, lane, lane, start_from=cruise_id(False, low, lane),
                end_at=cruise_id(False, high, lane), speeding_up=high > low, intervals=_intervals(2.0)))
    for (start_lane, end_lane), energy in itertools.product(itertools.permutations(lanes, 2), energy_levels_j):
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
    """The paper's library (ideal flow): Figs. 9 and 12 at E = 0.05 and 0.1."""
    return constrained_specs(rig) + free_specs(rig)


def circulatory_specs(rig: RigParameters) -> list[PrimitiveSpec]:
    """The circulatory flow's library: the paper's graph at CIRCULATORY_ENERGY_LEVELS_J, ids and durations as in
    ``default_specs`` except the free accelerate's (CIRCULATORY_FREE_ACCELERATE_S)."""
    specs = constrained_specs(rig, CIRCULATORY_ENERGY_LEVELS_J) + free_specs(rig, CIRCULATORY_ENERGY_LEVELS_J)
    return [dataclasses.replace(s, duration_s=CIRCULATORY_FREE_ACCELERATE_S,
                                intervals=_intervals(CIRCULATORY_FREE_ACCELERATE_S))
            if not s.constrained and s.primitive_type is PrimitiveType.ACCELERATE else s for s in specs]
