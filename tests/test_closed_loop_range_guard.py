"""The range guard in the realistic plant (one process, no DDS): the paper's constrained maneuver at lambda 1.67
in the wake's water (the vortex wake and the separation drag, the physical disturbances, the rig's stops from the
bridge file), tracked by the circulatory tracker without sliding mode.

The guard must leave the plans alone: followed exactly, no shipped plan meets its bound at the time scales the
experiments run (0.8-1.67).

At lambda 1.67 the plan's torques are 1.67^2 times those it was planned with, nearly the motors' whole torque.
In seed 43 the wake pushes the hub ahead of its plan in the last decelerate; the LQ stage then asks the heave for
more than its motor gives and drives it onto its stop, where the foil makes no stroke, and the run ends 0.16 rad
ahead. With swim_controller.tracker.FoilRangeGuard bounding the law's foil acceleration near the stops the foil
keeps stroking and the run ends on its plan (measured: -0.2 mrad and one period at the heave's stop, against
+156 mrad and 34 periods; over many seeds at the four time scales, with and without sliding mode:
docs/experiments.md).
"""
import numpy as np
import pytest
from conftest import track_plan

from swim_bringup.experiments import PAPER_CONSTRAINED
from swim_controller.tracker import FoilRangeGuard
from swim_model import load_rig
from swim_model.disturbances import Disturbances
from swim_model.plant import Plant, vehicle_model
from swim_planner.library import PrimitiveLibrary
from swim_planner.paths import default_library_path
from swim_sim.wake_coupling import WakeCoupling

SEED = 43
TIME_SCALE = 1.67
#: the experiments' time scales (swim_bringup.experiments: the paper's 1, 1.2 and 1.67, and 0.8)
TIME_SCALES = (0.8, 1.0, 1.2, 1.67)
#: the issue's goal for a constrained run: its end within 0.05 rad of its plan
HUB_END_ERROR_RAD = 0.05


def constrained_run(range_guard):
    rig = load_rig()
    stops = rig.hard_limits_rad
    water = vehicle_model("wake", rig, True, rig.lane_1_radius_m)
    plant = Plant(water, Disturbances(), seed=SEED, wake=WakeCoupling(water), hard_limits_rad=stops)
    library = PrimitiveLibrary.load(default_library_path("circulatory"), rig, "circulatory")
    run = track_plan(library, PAPER_CONSTRAINED, TIME_SCALE, plant, constrained=True, range_guard=range_guard)
    (heave_lower, heave_upper), (pitch_lower, pitch_upper) = stops
    heave, pitch = run.q[:, -2], run.q[:, -1]
    at_a_stop = ((heave <= heave_lower) | (heave >= heave_upper) | (pitch <= pitch_lower) | (pitch >= pitch_upper))
    return float(run.error[-1, 0]), int(np.count_nonzero(at_a_stop))


@pytest.fixture(scope="module")
def stops():
    return load_rig().hard_limits_rad


@pytest.fixture(scope="module")
def runs(stops):
    """(end error rad, periods at a stop) with the guard and without it."""
    return constrained_run(FoilRangeGuard(stops)), constrained_run(None)


def test_without_the_guard_the_heave_stays_on_its_stop_and_the_hub_runs_ahead(runs):
    """Where the wake pushes the hub ahead at all. The wake is chaotic, and its path follows the CPU's floating-point
    kernels: on an Intel Xeon host seeds 40-51 at lambda 1.67 all end within 0.3 mrad of their plans, none at a
    stop, with the guard or without it (the run's heave torque saturates, but the hub is not pushed ahead). The
    guard's own law is tested on every host in swim_controller's test_range_guard.py."""
    _, (end_rad, periods_at_a_stop) = runs
    if periods_at_a_stop == 0 and abs(end_rad) < HUB_END_ERROR_RAD:
        pytest.skip(f"seed {SEED}'s wake did not push the hub ahead on this CPU (end {end_rad * 1e3:+.2f} mrad, "
                    f"never at a stop): no stop to stay on")
    assert periods_at_a_stop > 10
    assert end_rad > HUB_END_ERROR_RAD


def test_with_it_the_foil_keeps_off_its_stops_and_the_run_ends_on_its_plan(runs):
    """The guard brakes the heave at 80 rad/s^2, faster than its motor surely can (21): under a saturated motor
    the heave may still touch its stop, but it does not stay there."""
    (end_rad, periods_at_a_stop), (_, periods_without) = runs
    assert abs(end_rad) <= HUB_END_ERROR_RAD
    assert periods_at_a_stop <= periods_without / 10


@pytest.mark.parametrize("flow", ["circulatory", "ideal"])
def test_no_plan_followed_exactly_meets_the_bound(flow, stops):
    """Every sample of every primitive of the shipped library, re-timed by Theorem 1 (rates times lambda,
    accelerations times lambda^2): the guard passes the plan's own foil acceleration through unchanged."""
    rig = load_rig()
    library = PrimitiveLibrary.load(default_library_path(flow), rig, flow)
    guard = FoilRangeGuard(stops)
    bound_samples = []
    for primitive_id in library.ids():
        primitive = library.get(primitive_id)
        psi, rate, u = primitive.q[:, -2:], primitive.qdot[:, -2:], primitive.foil_acceleration
        for time_scale in TIME_SCALES:
            for i in range(len(primitive.time_s)):
                planned = (u[i] * time_scale ** 2).tolist()
                bounded, _ = guard.bound(planned, psi[i].tolist(), (rate[i] * time_scale).tolist(),
                                         rig.sample_period_s)
                if bounded != planned:
                    bound_samples.append((primitive_id, time_scale, round(float(primitive.time_s[i]), 3)))
    assert not bound_samples, bound_samples[:10]
