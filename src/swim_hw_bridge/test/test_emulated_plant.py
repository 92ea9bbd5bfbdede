"""One plant: the emulated rig driven with the same torques as the simulator's plant, at reads exactly 8 ms apart,
has the same vehicle state, bit for bit. The simulator's plant is built here as sim_node's is, from Plant's own
arguments (not through the emulated rig's make_plant), at the 8 ms period; each runs in the water the emulated rig
swims in for each flow, and once with the simulator's physical disturbances (friction, tilt, waves). No noise and
no quantization: the vehicles' q (and qdot) are compared, not the encoders' counts or the simulator's sensors."""
import numpy as np
import pytest
from conftest import PERIOD_S

from swim_hw_bridge.backends.emulated import EmulatedDevice
from swim_model import load_rig
from swim_model.disturbances import Disturbances
from swim_model.plant import Plant, PlantSettings, vehicle_model
from swim_model.wake_coupling import WakeCoupling

#: 0.48 s: the heave driven into its upper stop and held there, then pulled back, the pitch swinging throughout
PERIODS = 60
#: the periods of heave current into the upper stop, A (0.8 A: 1.15 N m of the 1.25 N m limit)
INTO_THE_STOP = 40
HEAVE_CURRENTS_A = (0.8, -0.6)
PITCH_CURRENT_A = 0.5


class ExactReadDevice(EmulatedDevice):
    """The emulated rig read exactly PERIOD_S after its last read (a float 8 ms, not a difference of clock
    readings, which rounds), its amplifiers on while enabled."""

    def amplifiers_enabled(self, now_s=None):
        return self.enable_requested

    def read_period(self):
        self._time_s = 0.0
        self._advance(PERIOD_S)


def currents_a(k):
    """The currents of period k: the heave into its stop and back, the pitch swinging."""
    heave = HEAVE_CURRENTS_A[0] if k < INTO_THE_STOP else HEAVE_CURRENTS_A[1]
    return heave, PITCH_CURRENT_A * np.sin(k / 4.0)


@pytest.mark.parametrize("settings", [PlantSettings.flow_only("ideal"), PlantSettings.flow_only("circulatory"),
                                      PlantSettings.flow_only("wake"), PlantSettings("ideal", 8, Disturbances())],
                         ids=["ideal", "circulatory", "wake", "ideal-with-disturbances"])
def test_the_emulated_rig_steps_the_simulators_plant_bit_for_bit(config, settings):
    device = ExactReadDevice({**config.device_config("emulated"), "plant": settings})
    device.open()
    device.enable()
    stops = tuple(device.plant.hard_limits_rad.values())
    model = vehicle_model(settings.flow, load_rig(), constrained=False)
    wake = WakeCoupling(model) if settings.flow == "wake" else None
    simulator = Plant(model, settings.disturbances, PERIOD_S, settings.substeps, 0, wake, stops, flow=settings.flow)
    home = np.array(config.home_positions)
    simulator.reset(home, np.zeros(4))
    assert np.array_equal(device.plant.q, home)   # both at rest at the rig's home pose
    gains = np.array(config.motor_torque_gains_n_m_per_a)
    heave_upper = stops[0][1]
    pitch_swing = 0.0
    for k in range(PERIODS):
        currents = currents_a(k)
        device.write_currents(*currents)
        device.read_period()
        simulator.step(np.array(currents) * gains)
        assert np.array_equal(device.plant.q, simulator.q), k
        assert np.array_equal(device.plant.qdot, simulator.qdot), k
        assert np.array_equal(device.plant.lag, simulator.lag), k
        pitch_swing = max(pitch_swing, abs(simulator.q[3]))
        if k == INTO_THE_STOP - 1:
            assert simulator.q[2] == heave_upper   # the run met the stop: the stop model is compared too
    assert simulator.q[2] < heave_upper and pitch_swing > 0.05   # pulled back from the stop; the pitch swung
