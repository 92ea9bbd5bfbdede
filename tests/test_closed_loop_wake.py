"""The tracker against the vortex wake: the paper's constrained accelerate primitive (4 s from rest) in closed loop
on swim_sim's plant without other disturbances, the wake off and on, the sliding-mode term on and off.

The plans and gains come from the ideal-flow model, whose only thrust is the added-mass reaction; the wake adds the
circulatory force that model leaves out, on the hub (unactuated) as well as on the motors. Measured (two-norms
sqrt(int e^2 dt) of alpha, phi, theta in rad s^0.5):

    first 2 s            wake off (SM on / off)            wake on, SM on         wake on, SM off
    two-norms            0.0004 0.0026 0.0040 (+-1e-4)     0.028 0.499 0.042      0.029 0.477 0.040
    mean vortical        -                                 +0.021 N m, +0.052 N   +0.019 N m, +0.046 N
    hub torque, thrust
    whole primitive
    two-norms            0.0006 0.0059 0.0061 (both)       1.02 3.7 1.4           0.32 2.5 0.87
    hub travel           0.235 rad (the plan's)            1.86 rad               0.13 rad
    largest alpha error  0.0004 rad                        1.63 rad               0.44 rad
    periods saturated    none                              35 %                   15 %

The ideal-flow plans meet the water at angles of attack past 90 degrees, where the wake's leading edge holds
little suction (swim_model.wake), so the wake's mean thrust on them is small; its strokes' forces are not. The
heave's error is a hundred times the wake-free run's within 2 s, the motors saturate, and neither run ends within
the goal tolerance of its plan (0.25 rad). From 2 s on the runs are chaotic (a change of summation order in the
wake changed the 4 s numbers by tens of percent, never the first 2 s), so only coarse bounds are asserted there.
The sliding-mode term does not keep the plan: the wake's hub torque is unmatched (no motor drives alpha), while
the term rejects bounded torques on the motors (sliding_mode.py).
"""
import numpy as np
import pytest

from swim_controller.sliding_mode import SlidingMode
from swim_controller.testing.closed_loop import simulate
from swim_controller.tracker import CascadeTracker, model_io_linearization

ACCELERATE = "constrained/accelerate/E0.05"
EARLY_S = 2.0                    # s: before the plan is lost (runs repeatable to round-off; see the docstring)
TRACKED_ALPHA_TWO_NORM = 0.002   # rad s^0.5: the ideal-flow plant tracks to this (measured 0.0006)
GOAL_ALPHA_RAD = 0.25            # rad: the run tolerances' goal (swim-demo, swim-experiments)


class WakeRecorder:
    """swim_sim's Plant, recording the wake's held hub torque and thrust each period."""

    def __init__(self, plant):
        self.plant, self.hub_torque_n_m, self.thrust_n = plant, [], []

    def reset(self, q, qdot):
        self.plant.reset(q, qdot)

    def step(self, torque):
        state = self.plant.step(torque)
        if self.plant.wake is not None:
            self.hub_torque_n_m.append(self.plant.wake.generalized_force[0])
            self.thrust_n.append(self.plant.wake.thrust_n())
        return state


@pytest.fixture(scope="module")
def runs():
    """{(wake on, sliding mode on): (run, recorder)} and the planned hub travel."""
    from swim_model import VehicleModel, load_rig
    from swim_model.disturbances import Disturbances
    from swim_model.plant import Plant
    from swim_planner.library import PrimitiveLibrary
    from swim_planner.maneuver import concatenate, expand_sequence
    from swim_planner.paths import default_library_path
    from swim_sim.wake_coupling import WakeCoupling
    rig = load_rig()
    library = PrimitiveLibrary.load(default_library_path(), rig)
    reference = concatenate(library, rig, expand_sequence([ACCELERATE], []), 1.0)
    spec = library.spec(ACCELERATE)
    model = VehicleModel(rig, constrained=spec.constrained, lane_radius_m=spec.lane_radius_m)
    results = {}
    for wake_on in (False, True):
        for sliding in (True, False):
            tracker = CascadeTracker(model_io_linearization(model), model.torque_limits(), SlidingMode(),
                                     sliding_mode_enabled=sliding, sample_period_s=rig.sample_period_s)
            recorder = WakeRecorder(Plant(model, Disturbances.none(), wake=WakeCoupling(model) if wake_on else None))
            results[(wake_on, sliding)] = (simulate(model, tracker, reference, rig.sample_period_s, plant=recorder),
                                           recorder)
    return results, reference.q[-1, 0] - reference.q[0, 0]


def early(run, values):
    return np.asarray(values)[run.time_s < EARLY_S]


@pytest.mark.parametrize("sliding", [True, False], ids=["sliding", "no_sliding"])
def test_without_the_wake_the_plant_tracks_the_plan(runs, sliding):
    (run, _), planned_rad = runs[0][(False, sliding)], runs[1]
    assert run.two_norm(0) < TRACKED_ALPHA_TWO_NORM
    assert abs(run.q[-1, 0] - run.q[0, 0] - planned_rad) < 0.005 * planned_rad
    assert not run.saturated.any()


@pytest.mark.parametrize("sliding", [True, False], ids=["sliding", "no_sliding"])
def test_the_wake_takes_the_ideal_flow_plans_off(runs, sliding):
    """First 2 s: positive mean vortical thrust and hub torque, heave error two-norm over a hundred times the
    wake-free run's. Whole primitive: the alpha two-norm a hundred times the wake-free run's, an alpha error past
    the goal tolerance, the motors saturated in a tenth of the periods or more."""
    (run, recorder), _ = runs[0][(True, sliding)], runs[1]
    without, _ = runs[0][(False, sliding)]
    assert np.mean(early(run, recorder.hub_torque_n_m)) > 0.0 and np.mean(early(run, recorder.thrust_n)) > 0.0
    assert run.two_norm(1, EARLY_S) > 100.0 * without.two_norm(1, EARLY_S)
    assert run.two_norm(0) > 100.0 * without.two_norm(0)
    assert np.abs(run.error[:, 0]).max() > GOAL_ALPHA_RAD
    assert run.saturated.any(axis=1).mean() > 0.1
