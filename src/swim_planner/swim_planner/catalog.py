"""The primitive sets.

The constrained graph of Fig. 9 and the free two-lane graph of Fig. 12 (``default_specs``, the paper's library, ideal
flow), and the same graph with a third, faster energy level for the circulatory flow (``circulatory_specs``).

Ids name what a primitive joins, e.g. ``constrained/cruise/E0.05``, ``constrained/accelerate/E0.05``,
``free/lane_change/R0.43-R0.48/E0.05``. Durations are the paper's (Sec. 7; docs/model_and_method.md section 3):
constrained accelerate 4 s, cruise 5 s (5 cycles of 1 s), cruise-to-cruise 2 s, decelerate 4 s;
free accelerate 3 s, cruise 1 s, lane change 2 s outward (3 s inward, assumed), decelerate 3 s
(cruise-to-cruise 2 s, as constrained).
"""
from __future__ import annotations

import dataclasses
import itertools
import math

from swim_control.riccati import LqrWeights
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
CIRCULATORY_FREE_DECELERATE_S = 5.0
# circulatory flow (assumed, the shortest that solved): within its angle-of-attack bound the free vehicle's hub
# momentum cannot be taken out in the paper's 3 s decelerate (IPOPT: all six infeasible from both guesses; with
# p_alpha = 0 asked only at the window next to rest, 10 % of the R = 0.43 m, E = 0.05 cruise's p_alpha is left) nor
# in 4 s (R = 0.43 m, E = 0.05: infeasible below 28 deg); in 5 s, with the continuation below, it solves
CIRCULATORY_FREE_DECELERATE_CONTINUATION_RAD = (math.radians(30.0),)
# circulatory flow, the free decelerates (PrimitiveSpec.angle_of_attack_continuation_rad, assumed): from the
# still-foil guess IPOPT finds each infeasible with the bound at 20 deg; solved first without the bound, then with
# 30 deg, each step warm-starting the next, it reaches 20 deg. From the stroking cruises the finer steps 40, 30, 25
# and 22 deg took 1.1-2.9 times the iterations, to optima of much the same J or worse (docs/circulatory_primitives.md)
CIRCULATORY_FREE_DECELERATE_INTERVALS_PER_S = 40
# circulatory flow, the free decelerates' collocation intervals per second (assumed: twice INTERVALS_PER_S, the
# least tried that ends the paper's lane keeping within 1 mrad of its plan). A free decelerate ends at rest, where
# the tracker can no longer take a hub-angle error out, so what its plan's discretization leaves in its last
# intervals stays; an accelerate's is taken out by the cruise after it (docs/circulatory_primitives.md). Each is
# solved first on INTERVALS_PER_S, its continuation included, then on this grid from that solution (mesh refinement,
# PrimitiveSpec.coarse_intervals): on the coarser grid the continuation's iterations cost less than half as much
CIRCULATORY_CONSTRAINED_MIN_STROUHAL = 0.35
# circulatory flow, the constrained cruises' least Strouhal number (PrimitiveSpec.min_strouhal; assumed: inside
# 0.2-0.4, where oscillating foils and swimming animals are most efficient: Triantafyllou, Triantafyllou &
# Grosenbaugh, J. Fluids Struct. 7 (1993)). Without it the best cruise at a fixed mean kinetic energy folds the heave
# link to its planning limit and strokes only enough for the foil's profile drag (St about 0.015). The mean thrust
# grows with the square of the stroke, so about a stroke this small the tracker can change it little, and nothing
# else drives the hub: a 0.1 degree tilt of the platform loses the plan. With the stroke the maneuver is tracked,
# in the vortex wake too (docs/circulatory_primitives.md measures both, and the floors tried)
CIRCULATORY_FREE_MIN_STROUHAL = 0.2
# circulatory flow, the free cruises' least Strouhal number (assumed: the low end of the same 0.2-0.4 band). The
# free vehicle's cruises fold as the constrained ones did (St 0.02-0.05), and its lane change was then lost in its
# last decelerate in most runs in the vortex wake; at this floor it is tracked in most (docs/circulatory_primitives.md)
CIRCULATORY_CONSTRAINED_DECELERATE_REST_WINDOW_S = 0.5
CIRCULATORY_CONSTRAINED_DECELERATE_FOIL_RATE_RAD_S = 4.0
# circulatory flow, the constrained decelerates (PrimitiveSpec.rest_window_s, rest_window_foil_rate_limit_rad_s;
# assumed): the foil turns back to rest in their last 0.5 s, its heave and pitch at most 4 rad/s there. With
# PlanningLimits' 0.2 s window and no rate bound that turn is a bang-bang of the planning torque, the pitch through
# 66-70 deg at 9.5-10.6 rad/s with the hub nearly still, and the hub stops on the separated force it makes; in the
# vortex wake 21 of 640 constrained runs then ended 0.1-1.5 rad off their plan, all but one ahead; with this end 2
# (docs/experiments.md). The window's samples are past 30 deg of angle of attack: 9-12 % of these primitives'
# samples, more than the 5 % the other primitives keep to
CIRCULATORY_LONGER_S = {"free/decelerate/R0.43/E0.10": 6.0, "free/decelerate/R0.43/E0.20": 6.0,
                        "free/decelerate/R0.48/E0.20": 6.0, "free/cruise_to_cruise/R0.43/E0.10-E0.05": 3.0,
                        "free/accelerate/R0.43/E0.20": 5.0}
# circulatory flow: transitions given more than the durations above (assumed, each the shortest tried that solves).
# The inner lane's E = 0.10 and 0.20 decelerates and the outer lane's E = 0.20 one: in 5 s the continuation fails at
# its last step, to 20 deg, from both guesses (IPOPT: the hub's rate in the last intervals, the lane band active;
# the outer one with IPOPT's BLAS on one thread, build.local_executor's, and not on two), in 6 s it solves. Slowing
# down from E = 0.10 to 0.05 in the inner lane is infeasible in 2 s within the angle-of-attack bound (from both
# guesses, from the outer lane's solution moved inward, and at the end of the continuation above: solved at 22 deg,
# infeasible at 20), as the free decelerate is in 3 s; in 3 s it solves directly (73 iterations). The inner lane's
# E = 0.20 accelerate, to a cruise at CIRCULATORY_FREE_MIN_STROUHAL: infeasible in 4 s from both guesses, solved in
# 5 s
CIRCULATORY_LQR_WEIGHTS = LqrWeights(rest_lateral_terminal_weight=1.0e5, rest_alpha_terminal_weight=1.0e5)
# circulatory flow, the weights of the stored gains: the package defaults, with the task's error at the
# decelerates' end weighted. The carriage's at the free ones' (1/m^2; assumed: about 40 times e_R's entry of P in
# the middle of the lane keeping's decelerate, 2570 /m^2): without it the lane keeping ends 1-2 cm off its lane, the
# carriage held by the rails' friction and the tilt where the braking strokes left it; in the vortex wake 3e4-3e5 end
# it within 0.5 cm, 3e3 does not. The hub's at the constrained ones' (1/rad^2; assumed: about 240 times e_alpha's
# entry of P in the middle of the E = 0.10 decelerate, 424 /rad^2): without it the constrained runs in the vortex
# wake end 19-39 mrad behind their plan at the median of each time scale (seeds 1-10), with it 0.4-0.6 mrad; 3e4
# and 3e5 do as well, 1e3 (with 300 vortices) halves the lag (docs/experiments.md)
CRUISE_CYCLE_S = 1.0                   # assumed: one stroke per second, as the paper's cruise figures


def energy_tag(energy_j: float) -> str:
    """The energy level as an id part, "E0.05" for 0.05 J."""
    return f"E{energy_j:.2f}"


def lane_tag(radius_m: float) -> str:
    """The lane radius as an id part, "R0.43" for 0.43 m."""
    return f"R{radius_m:.2f}"


def cruise_id(constrained: bool, energy_j: float, lane_m: float | None = None) -> str:
    """The id of the cruise at energy_j (J); a free cruise's also names its lane (m)."""
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
    """The constrained graph.

    A cruise, its accelerate and its decelerate at each level (ascending), and the cruise-to-cruise edges between
    neighbouring levels.
    """
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
    """The free two-lane graph.

    In each lane the constrained graph's primitives, and a lane change each way at every level.
    """
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
    """The circulatory flow's library.

    The paper's graph at CIRCULATORY_ENERGY_LEVELS_J, ids and durations as in ``default_specs`` except the free
    accelerate's (CIRCULATORY_FREE_ACCELERATE_S), the free decelerate's (CIRCULATORY_FREE_DECELERATE_S, solved by
    continuation in the angle-of-attack bound and ending at rest with the lag states its braking leaves:
    PrimitiveSpec.end_lag_free; CIRCULATORY_FREE_DECELERATE_INTERVALS_PER_S, refined from INTERVALS_PER_S:
    PrimitiveSpec.coarse_intervals) and those of CIRCULATORY_LONGER_S (which take precedence); the cruises stroke at a
    Strouhal number of at least CIRCULATORY_CONSTRAINED_MIN_STROUHAL (constrained) or CIRCULATORY_FREE_MIN_STROUHAL
    (free); the constrained decelerates turn the foil back to rest within
    CIRCULATORY_CONSTRAINED_DECELERATE_REST_WINDOW_S at no more than CIRCULATORY_CONSTRAINED_DECELERATE_FOIL_RATE_RAD_S.
    """
    specs = constrained_specs(rig, CIRCULATORY_ENERGY_LEVELS_J) + free_specs(rig, CIRCULATORY_ENERGY_LEVELS_J)
    unknown = set(CIRCULATORY_LONGER_S) - {s.primitive_id for s in specs}
    assert not unknown, f"CIRCULATORY_LONGER_S names no spec of the set: {sorted(unknown)}"

    def circulatory(spec: PrimitiveSpec) -> PrimitiveSpec:
        if not spec.constrained and spec.primitive_type is PrimitiveType.ACCELERATE:
            spec = _lasting(spec, CIRCULATORY_FREE_ACCELERATE_S)
        if not spec.constrained and spec.primitive_type is PrimitiveType.DECELERATE:
            spec = dataclasses.replace(_lasting(spec, CIRCULATORY_FREE_DECELERATE_S), end_lag_free=True,
                                       angle_of_attack_continuation_rad=CIRCULATORY_FREE_DECELERATE_CONTINUATION_RAD)
        if spec.primitive_id in CIRCULATORY_LONGER_S:
            spec = _lasting(spec, CIRCULATORY_LONGER_S[spec.primitive_id])
        if not spec.constrained and spec.primitive_type is PrimitiveType.DECELERATE:
            spec = dataclasses.replace(spec, intervals=int(round(CIRCULATORY_FREE_DECELERATE_INTERVALS_PER_S
                                                                 * spec.duration_s)),
                                       coarse_intervals=_intervals(spec.duration_s))
        if spec.constrained and spec.primitive_type is PrimitiveType.DECELERATE:
            spec = dataclasses.replace(
                spec, rest_window_s=CIRCULATORY_CONSTRAINED_DECELERATE_REST_WINDOW_S,
                rest_window_foil_rate_limit_rad_s=CIRCULATORY_CONSTRAINED_DECELERATE_FOIL_RATE_RAD_S)
        if spec.primitive_type is PrimitiveType.CRUISE:
            spec = dataclasses.replace(spec, min_strouhal=CIRCULATORY_CONSTRAINED_MIN_STROUHAL if spec.constrained
                                       else CIRCULATORY_FREE_MIN_STROUHAL)
        return spec
    return [circulatory(s) for s in specs]


def _lasting(spec: PrimitiveSpec, duration_s: float) -> PrimitiveSpec:
    """The spec with another duration, its collocation intervals at INTERVALS_PER_S."""
    return dataclasses.replace(spec, duration_s=duration_s, intervals=_intervals(duration_s))


def lqr_weights(flow_model: str) -> LqrWeights:
    """The LQ weights a library of this flow model ("ideal" or "circulatory") stores its gains for."""
    return CIRCULATORY_LQR_WEIGHTS if flow_model == "circulatory" else LqrWeights()


# The paper's maneuvers as (primitive ids, repeat counts) over the paper's library (Sec. 7), at lambda = 1.
#: the constrained maneuver (Sec. 7.1): accelerate to E1, cruise x2, cruise-to-cruise, cruise x2, stop
PAPER_CONSTRAINED = (["constrained/accelerate/E0.05", "constrained/cruise/E0.05",
                      "constrained/cruise_to_cruise/E0.05-E0.10", "constrained/cruise/E0.10",
                      "constrained/decelerate/E0.10"], [1, 2, 1, 2, 1])
#: the free lane keeping (Sec. 7.2) at R = 0.43 m: accelerate, 14 cruises, decelerate (20 s)
PAPER_LANE_KEEPING = (["free/accelerate/R0.43/E0.05", "free/cruise/R0.43/E0.05", "free/decelerate/R0.43/E0.05"],
                      [1, 14, 1])
#: the lane change (Sec. 7.3) at E = 0.05: accelerate, 5 cruises in lane 1, the change, 10 in lane 2, stop
PAPER_LANE_CHANGE = (["free/accelerate/R0.43/E0.05", "free/cruise/R0.43/E0.05", "free/lane_change/R0.43-R0.48/E0.05",
                      "free/cruise/R0.48/E0.05", "free/decelerate/R0.48/E0.05"], [1, 5, 1, 10, 1])
