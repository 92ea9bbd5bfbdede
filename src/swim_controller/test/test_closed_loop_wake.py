"""The tracker against the vortex wake (issue 7): the paper's constrained accelerate primitive (4 s from rest) in
closed loop on swim_sim's plant without other disturbances, the wake off and on, the sliding-mode term on and off.

The plans and gains come from the ideal-flow model, whose only thrust is the added-mass reaction; the wake adds the
circulatory force that model leaves out, acting on the hub (unactuated) as well as on the motors. Measured (two-norms
sqrt(int e^2 dt) of alpha, phi, theta in rad s^0.5; hub angle reached at 4 s against the plan's 0.235 rad):

    wake off, sliding mode on/off: 0.0006, 0.0059, 0.0061 / 0.0006, 0.0060, 0.0061;  0.235 rad; never saturated
    wake on,  sliding mode on:   2.36, 3.17, 3.39;  1.86 rad; mean vortical thrust +0.067 N, hub torque +0.022 N m;
                                 47 % of periods saturated
    wake on,  sliding mode off:  2.69, 2.54, 2.49;  2.42 rad; mean vortical thrust +0.138 N, hub torque +0.076 N m;
                                 54 % of periods saturated

The wake's thrust drives the vehicle ahead of its plan (8 to 10 times the planned hub travel) and the tracker, built
on the ideal-flow model, loses the plan; the sliding-mode term (matched disturbances: torques on the motors) does not
bring it back.
"""
import numpy as np
import pytest

from swim_controller.closed_loop import reference_of, simulate
from swim_controller.sliding_mode import SlidingMode
from swim_controller.tracker import CascadeTracker, model_io_linearization

ACCELERATE = "constrained/accelerate/E0.05"
TRACKED_ALPHA_TWO_NORM = 0.002   # rad s^0.5: the ideal-flow plant tracks to this (measured 0.0006)
LOST_ALPHA_TWO_NORM = 1.0        # rad s^0.5: a plan lost (the hub tens of centimetres off it for seconds)


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
def runs(library, model_for, rig):
    """{(wake on, sliding mode on): (run, recorder)} and the planned hub travel."""
    from swim_planner.maneuver import concatenate, expand_sequence
    from swim_sim.disturbances import Disturbances
    from swim_sim.plant import Plant
    from swim_sim.wake_coupling import WakeCoupling
    reference = reference_of(concatenate(library, rig, expand_sequence([ACCELERATE], []), 1.0))
    model = model_for(library.spec(ACCELERATE))
    results = {}
    for wake_on in (False, True):
        for sliding in (True, False):
            tracker = CascadeTracker(model_io_linearization(model), model.torque_limits(), SlidingMode(),
                                     sliding_mode_enabled=sliding, sample_period_s=rig.sample_period_s)
            recorder = WakeRecorder(Plant(model, Disturbances.none(), wake=WakeCoupling(model) if wake_on else None))
            results[(wake_on, sliding)] = (simulate(model, tracker, reference, rig.sample_period_s, plant=recorder),
                                           recorder)
    return results, reference.q[-1, 0] - reference.q[0, 0]


@pytest.mark.parametrize("sliding", [True, False], ids=["sliding", "no_sliding"])
def test_without_the_wake_the_plant_tracks_the_plan(runs, sliding):
    (run, _), planned_rad = runs[0][(False, sliding)], runs[1]
    assert run.two_norm(0) < TRACKED_ALPHA_TWO_NORM
    assert abs(run.q[-1, 0] - run.q[0, 0] - planned_rad) < 0.005 * planned_rad
    assert not run.saturated.any()


@pytest.mark.parametrize("sliding", [True, False], ids=["sliding", "no_sliding"])
def test_the_wake_pushes_the_vehicle_ahead_of_its_plan(runs, sliding):
    """Positive mean vortical thrust and hub torque; at least three times the planned hub travel; the plan lost
    (alpha two-norm over a hundred times the wake-free run's) with the motors saturated for a fifth of the periods
    or more."""
    (run, recorder), planned_rad = runs[0][(True, sliding)], runs[1]
    without, _ = runs[0][(False, sliding)]
    assert np.mean(recorder.hub_torque_n_m) > 0.0 and np.mean(recorder.thrust_n) > 0.0
    assert run.q[-1, 0] - run.q[0, 0] > 3.0 * planned_rad
    assert run.two_norm(0) > max(LOST_ALPHA_TWO_NORM, 100.0 * without.two_norm(0))
    assert run.saturated.any(axis=1).mean() > 0.2


def test_sliding_mode_does_not_recover_the_plan_under_the_wake(runs):
    """The wake's hub torque is unmatched (it acts on alpha, which no motor drives), so the sliding-mode term, which
    rejects bounded torques on the motors (sliding_mode.py), cannot cancel it: with it the plan is lost as well, the
    alpha two-norm within a factor 2 of the run without it."""
    with_sliding, without_sliding = runs[0][(True, True)][0], runs[0][(True, False)][0]
    assert with_sliding.two_norm(0) > LOST_ALPHA_TWO_NORM
    assert 0.5 < with_sliding.two_norm(0) / without_sliding.two_norm(0) < 2.0
