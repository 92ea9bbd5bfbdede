"""The free lane change at lambda 1.25 in the vortex wake (one process, no DDS): the circulatory library's plans
and gains, the tracker without sliding mode, on swim_sim's plant in the wake's water ("wake": the vortex wake and
the separation drag) with the physical disturbances (seed 3) and the rig's stops.

The plans' model holds the leading edge's suction at the critical leading-edge suction parameter; in the last
decelerate the wake's attached flow asks the edge for several times that. With the wake's leading edge losing
the suction beyond the same parameter (WakeParameters' default) the lane change ends 1.4 mm off its outer lane;
with the attached flow's whole suction, 11.3 mm.
"""
import pytest
from conftest import track_plan

from swim_model import load_rig
from swim_model.disturbances import Disturbances
from swim_model.plant import Plant, vehicle_model
from swim_model.wake import WakeParameters
from swim_model.wake_coupling import WakeCouplingParameters
from swim_planner.library import PrimitiveLibrary
from swim_planner.paths import default_library_path
from swim_sim.wake_coupling import WakeCoupling

LANE_CHANGE = (["free/accelerate/R0.43/E0.05", "free/cruise/R0.43/E0.05", "free/lane_change/R0.43-R0.48/E0.05",
                "free/cruise/R0.48/E0.05", "free/decelerate/R0.48/E0.05"], [1, 5, 1, 10, 1])
TIME_SCALE = 1.25
PAPERS_LANE_ERROR_M = 5e-3   # the paper's rig ended within 0.5 cm of its lane


def lane_change_end_offset_m(library, wake: WakeParameters) -> float:
    rig = load_rig()
    water = vehicle_model("wake", rig, False, rig.lane_1_radius_m)
    plant = Plant(water, Disturbances(), seed=3, wake=WakeCoupling(water, WakeCouplingParameters(wake=wake)),
                  hard_limits_rad=rig.hard_limits_rad)
    run = track_plan(library, LANE_CHANGE, TIME_SCALE, plant)
    return abs(run.q[-1, 1] - rig.lane_2_radius_m)


@pytest.fixture(scope="module")
def library():
    return PrimitiveLibrary.load(default_library_path("circulatory"), load_rig(), "circulatory")


def test_with_the_edges_suction_held_the_lane_change_ends_within_the_papers_half_centimetre(library):
    assert lane_change_end_offset_m(library, WakeParameters()) <= PAPERS_LANE_ERROR_M


def test_with_the_attached_flows_whole_suction_it_ends_outside(library):
    whole = WakeParameters(critical_leading_edge_suction=None)
    assert lane_change_end_offset_m(library, whole) > 2.0 * PAPERS_LANE_ERROR_M
