"""Self-propulsion in a perfect fluid: shape change alone moves the vehicle (docs/model_and_method.md P1)."""
import math

import numpy as np
import pytest

from swim_model import SinusoidalGait, VehicleModel, simulate_gait


@pytest.mark.parametrize("constrained", [True, False])
def test_pitch_leading_heave_advances_and_mirror_reverses(constrained):
    model = VehicleModel(constrained=constrained)
    gait = SinusoidalGait(heave_amplitude_rad=0.35, pitch_amplitude_rad=0.6, frequency_hz=1.0,
                          pitch_lead_rad=math.pi / 2)
    forward = simulate_gait(model, gait, duration_s=4.0)
    backward = simulate_gait(model, gait.mirrored(), duration_s=4.0)
    # sampled at whole cycles, so the net advance is what a period adds, not the oscillation
    advance, retreat = forward.q[-1, 0] - forward.q[0, 0], backward.q[-1, 0] - backward.q[0, 0]
    assert advance > 0.05 and retreat < -0.05
    for run in (forward, backward):
        momenta = [model.momentum(q, qd)[0] for q, qd in zip(run.q[::50], run.qdot[::50])]
        assert np.abs(momenta).max() < 1e-9
    if constrained:  # the rig is mirror-symmetric about the rail: the mirrored gait exactly reverses
        assert retreat == pytest.approx(-advance, rel=1e-6)


def test_no_phase_no_net_motion():
    """Heave and pitch in phase trace no loop in shape space: no net displacement per cycle."""
    model = VehicleModel(constrained=True)
    run = simulate_gait(model, SinusoidalGait(pitch_lead_rad=0.0), duration_s=3.0)
    assert abs(run.q[-1, 0] - run.q[0, 0]) < 1e-6
