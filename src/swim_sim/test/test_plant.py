"""The simulator core against invariants and closed forms: energy, momentum, stiction, repeatability, sensors."""
import dataclasses
import math

import numpy as np
import pytest

from swim_model import VehicleModel
from swim_model.disturbances import GRAVITY_M_S2, Disturbances
from swim_model.plant import Plant, SimulationError
from swim_sim.sensors import SensorNoise, Sensors, counts_per_unit

PERIODS_30_S = 3750   # the paper's maneuver length at 8 ms
# RK4 at 1 ms on this model over 30 s, relative: energy drifts ~3e-11, p_alpha ~2.4e-9 (measured)
ENERGY_TOLERANCE = 1e-9
MOMENTUM_TOLERANCE = 1e-8


def swinging_start(plant):
    qdot = np.zeros(plant.model.nq)
    qdot[0], qdot[-2], qdot[-1] = 0.3, 2.0, -3.0
    return plant.q.copy(), qdot


def test_ideal_plant_conserves_energy_and_p_alpha_over_30_s(model):
    plant = Plant(model, Disturbances.none())
    plant.reset(*swinging_start(plant))
    energy, p_alpha = plant.energy(), model.momentum(plant.q, plant.qdot)[0]
    for _ in range(PERIODS_30_S):
        plant.step([0.0, 0.0])
    assert abs(plant.energy() - energy) < ENERGY_TOLERANCE * energy
    assert abs(model.momentum(plant.q, plant.qdot)[0] - p_alpha) < MOMENTUM_TOLERANCE * max(abs(p_alpha), energy)


def test_with_friction_and_drag_energy_only_decreases(model):
    plant = Plant(model, Disturbances(tilt_rad=0.0, wave_force_per_speed2_n_s2_m2=0.0))
    plant.reset(*swinging_start(plant))
    energies = [plant.energy()]
    for _ in range(PERIODS_30_S):
        plant.step([0.0, 0.0])
        energies.append(plant.energy())
    assert np.all(np.diff(energies) <= 1e-12)
    assert energies[-1] < 0.5 * energies[0]   # drag and friction took most of it (measured: 12 % and 18 % left)


def tilted_hub(rig, tilt_rad, static_n_m):
    """The constrained vehicle at rest with alpha 90 degrees from the tilt: gravity torque m g sin(tilt) R."""
    model = VehicleModel(rig, constrained=True)
    disturbances = dataclasses.replace(Disturbances.none(), hub_coulomb_n_m=0.5 * static_n_m,
                                       hub_static_n_m=static_n_m, tilt_rad=tilt_rad)
    plant = Plant(model, disturbances)
    plant.reset([math.pi / 2, 0.0, 0.0], np.zeros(3))
    mass = rig.platform_mass_kg + rig.heave_link_mass_kg + rig.foil_assembly_mass_kg
    return plant, mass * GRAVITY_M_S2 * math.sin(tilt_rad) * model.lane_radius_m


def test_stiction_holds_below_and_breaks_away_above_the_static_limit(rig):
    plant, torque = tilted_hub(rig, 0.002, 0.02)
    assert torque < 0.02 * 0.9   # ~0.015 N m of gravity torque against a 0.02 N m static limit
    for _ in range(250):
        plant.step([0.0, 0.0])
    assert plant.q[0] == math.pi / 2 and plant.qdot[0] == 0.0   # held exactly
    plant, torque = tilted_hub(rig, 0.004, 0.02)
    assert torque > 0.02 * 1.1
    for _ in range(250):
        plant.step([0.0, 0.0])
    assert plant.qdot[0] > 0.0   # tilted downhill: Q_alpha = m g sin(tilt) R sin(alpha - 0) > 0


def test_a_moving_coordinate_stops_at_zero_and_stays(rig):
    """The lateral velocity sticks at 0 (paper Sec. 7.3): a small drift is stopped by rail friction."""
    model = VehicleModel(rig, constrained=False)
    plant = Plant(model, dataclasses.replace(Disturbances.none(), rail_coulomb_n=0.3, rail_static_n=0.5))
    q = plant.q.copy()
    plant.reset(q, np.array([0.0, 0.01, 0.0, 0.0]))
    for _ in range(100):
        plant.step([0.0, 0.0])
    assert plant.stuck[1] and plant.qdot[1] == 0.0
    # Coulomb deceleration F/m_eff stops 0.01 m/s within 0.01 m / (0.3 N / 2 kg) = 67 ms; then R stays put
    r_stopped = plant.q[1]
    assert 0.0 < r_stopped - q[1] < 0.01 * 0.067
    for _ in range(100):
        plant.step([0.0, 0.0])
    assert plant.q[1] == r_stopped


def test_runs_repeat_bit_for_bit_for_a_seed(rig):
    model = VehicleModel(rig, constrained=False)
    torques = 0.3 * np.sin(np.arange(500)[:, None] * np.array([0.05, 0.07]))

    def run(seed):
        plant = Plant(model, Disturbances(), seed=seed)
        plant.reset(*swinging_start(plant))
        sensors = Sensors(model)
        return np.array([np.concatenate(sensors.measure(plant.step(t).q, plant.qdot, plant.rng)) for t in torques])

    first, second, other = run(7), run(7), run(8)
    assert np.array_equal(first, second)
    assert not np.array_equal(first, other)


def test_a_period_of_its_own_length_is_a_plant_of_that_period_bit_for_bit(rig):
    """step(torque, period_s), as the emulated rig steps its reads, integrates as a plant whose sample period is
    period_s, disturbances and noise included; the clock adds the periods; a period that is not > 0 is refused."""
    model = VehicleModel(rig, constrained=False)
    torques = 0.3 * np.sin(np.arange(50)[:, None] * np.array([0.05, 0.07]))
    reference, varied = Plant(model, Disturbances(), sample_period_s=0.004), Plant(model, Disturbances())
    for plant in (reference, varied):
        plant.reset(*swinging_start(plant))
    for torque in torques:
        reference.step(torque)
        varied.step(torque, 0.004)
        assert np.array_equal(reference.q, varied.q) and np.array_equal(reference.qdot, varied.qdot)
    assert varied.time_s == pytest.approx(50 * 0.004, abs=1e-12)
    before = varied.state
    varied.step(torques[0])   # back to its own 8 ms: a different period than 4 ms
    assert varied.time_s == pytest.approx(before.time_s + 0.008, abs=1e-12)
    for bad in (0.0, -0.008, math.nan):
        with pytest.raises(ValueError, match="period"):
            varied.step(torques[0], bad)


def test_torque_is_held_clipped_and_reported(model):
    plant = Plant(model, Disturbances.none())
    state = plant.step([10.0, -10.0])
    np.testing.assert_array_equal(state.torque, [model.torque_limits()[0], -model.torque_limits()[1]])
    assert state.saturated == (True, True)
    assert np.array_equal(plant.step([math.nan, 0.0]).torque, [0.0, 0.0])


def test_blow_up_stops_with_an_error_and_keeps_the_last_state(rig):
    model = VehicleModel(rig, constrained=True)
    plant = Plant(model, Disturbances.none(), sample_period_s=0.1, substeps=1)
    plant.reset([0.0, 0.0, 0.0], [0.0, 0.0, 900.0])
    before = plant.state
    with pytest.raises(SimulationError, match="blew up"):
        plant.step([0.0, 0.0])
    assert np.array_equal(plant.q, before.q) and plant.time_s == before.time_s


def test_encoder_resolutions_are_the_papers(rig):
    """Sec. 2: 512 x 43 / (2 pi) lines/rad heave, 512 x 25 / (2 pi) pitch, 6144 / (2 pi) hub, 1024 lines/in."""
    free = VehicleModel(rig, constrained=False)
    expected = 4 * np.array([6144 / (2 * math.pi), 1024 / 0.0254, 512 * 43 / (2 * math.pi), 512 * 25 / (2 * math.pi)])
    np.testing.assert_allclose(counts_per_unit(free), expected, rtol=1e-12)


def test_quantization_and_noise_statistics_match_their_parameters(rig):
    model = VehicleModel(rig, constrained=False)
    rng = np.random.default_rng(3)
    samples = 20000
    q = rng.uniform(-1, 1, (samples, 4)) + [0, 0.43, 0, 0]
    qdot = rng.uniform(-1, 1, (samples, 4))
    noisy = Sensors(model, SensorNoise(position_noise_counts=0.5, velocity_noise_fraction=0.2, quantize=False))
    quantized = Sensors(model, SensorNoise(position_noise_counts=0.0))
    measured = np.array([noisy.measure(a, b, rng) for a, b in zip(q, qdot)])
    position_error_counts = (measured[:, 0] - q) * noisy.counts_per_unit
    velocity_error_quanta = (measured[:, 1] - qdot) / noisy.velocity_quantum
    np.testing.assert_allclose(position_error_counts.std(axis=0), 0.5, rtol=0.05)
    np.testing.assert_allclose(velocity_error_quanta.std(axis=0), 0.2, rtol=0.05)
    assert np.all(np.abs(position_error_counts.mean(axis=0)) < 0.02)
    exact = np.array([quantized.measure(a, b, rng)[0] for a, b in zip(q, qdot)])
    counts = exact * quantized.counts_per_unit
    np.testing.assert_allclose(counts, np.round(counts), atol=1e-6)            # whole counts
    error = (q - exact) * quantized.counts_per_unit
    assert np.all((error >= -1e-9) & (error < 1.0 + 1e-9))                       # floor: within one count below
    np.testing.assert_allclose(error.mean(axis=0), 0.5, atol=0.02)               # uniform over the count
