"""The tracker against the vortex wake (issue 7): the paper's constrained accelerate primitive (4 s from rest) in
closed loop on swim_sim's plant without other disturbances, the wake off and on, the sliding-mode term on and off.

The plans and gains come from the ideal-flow model, whose only thrust is the added-mass reaction; the wake adds the
circulatory force that model leaves out, on the hub (unactuated) as well as on the motors. Measured (two-norms
sqrt(int e^2 dt) of alpha, phi, theta in rad s^0.5):

    first 2 s            wake off (SM on / off)            wake on, SM on         wake on, SM off
    two-norms            0.0004 0.0026 0.0040 (+-1e-4)     0.047 0.688 0.057      0.207 1.495 0.676
    mean vortical        -                                 +0.093 N m, +0.20 N    +0.54 N m, +1.10 N
    hub torque, thrust
    whole primitive
    two-norms            0.0006 0.0059 0.0061 (both)       3.2 3.8 3.8            2.7 2.5 2.5
    hub travel           0.235 rad (the plan's)            2.9 rad                2.4 rad
    periods saturated    none                              48 %                   54 %

The wake's thrust drives the vehicle ahead of its plan and the tracker, built on the ideal-flow model, loses the
plan from about 2 s on (first saturation at 1.87 s with the sliding-mode term, 1.65 s without); from then on the
runs are chaotic (a change of summation order in the wake changed the 4 s numbers by tens of percent, never the
first 2 s), so only coarse bounds are asserted there. The sliding-mode term delays the loss (errors 2 to 10 times
smaller over the first 2 s) but does not prevent it: the wake's hub torque is unmatched (no motor drives alpha),
while the term rejects bounded torques on the motors (sliding_mode.py).
"""
import numpy as np
import pytest

from swim_controller.testing.closed_loop import simulate
from swim_controller.sliding_mode import SlidingMode
from swim_controller.tracker import CascadeTracker, model_io_linearization


ACCELERATE = "constrained/accelerate/E0.05"
EARLY_S = 2.0                    # s: before the plan is lost (runs repeatable to round-off; see the docstring)
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
def runs():
    """{(wake on, sliding mode on): (run, recorder)} and the planned hub travel."""
    from swim_model import VehicleModel, load_rig
    from swim_planner.library import PrimitiveLibrary
    from swim_planner.maneuver import concatenate, expand_sequence
    from swim_planner.paths import default_library_path
    from swim_sim.disturbances import Disturbances
    from swim_sim.plant import Plant
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
def test_the_wake_pushes_the_vehicle_forward_and_off_its_plan(runs, sliding):
    """First 2 s: positive mean vortical thrust and hub torque, heave error two-norm over a hundred times the
    wake-free run's. Whole primitive: at least three times the planned hub travel, the plan lost (alpha two-norm),
    the motors saturated for a fifth of the periods or more."""
    (run, recorder), planned_rad = runs[0][(True, sliding)], runs[1]
    without, _ = runs[0][(False, sliding)]
    assert np.mean(early(run, recorder.hub_torque_n_m)) > 0.0 and np.mean(early(run, recorder.thrust_n)) > 0.0
    assert run.two_norm(1, EARLY_S) > 100.0 * without.two_norm(1, EARLY_S)
    assert run.q[-1, 0] - run.q[0, 0] > 3.0 * planned_rad
    assert run.two_norm(0) > max(LOST_ALPHA_TWO_NORM, 100.0 * without.two_norm(0))
    assert run.saturated.any(axis=1).mean() > 0.2


def test_sliding_mode_delays_but_does_not_prevent_the_loss_under_the_wake(runs):
    """Over the first 2 s the sliding-mode term lowers every error two-norm by a third or more (measured: alpha
    -77 %, heave -54 %, pitch -92 %); over the primitive the plan is lost with it as without it."""
    with_sliding, without_sliding = runs[0][(True, True)][0], runs[0][(True, False)][0]
    for column in range(3):
        assert with_sliding.two_norm(column, EARLY_S) < 2.0 / 3.0 * without_sliding.two_norm(column, EARLY_S)
    assert min(with_sliding.two_norm(0), without_sliding.two_norm(0)) > LOST_ALPHA_TWO_NORM
