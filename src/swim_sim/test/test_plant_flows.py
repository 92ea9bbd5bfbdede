"""The plant's flow models against independent computations: the circulatory plant against swim_model's own RK4 of
VehicleModel(flow="circulatory") and the flow's momentum and energy balances; its foil drag is the flow model's
alone; the wake plant's separation drag against 1/2 rho Cd A |v| v; the flow a plant is built for."""
import dataclasses

import numpy as np
import pytest
from scipy.integrate import simpson

from swim_model import StateError, VehicleModel
from swim_model.disturbances import Disturbances
from swim_model.flow import FLOWS
from swim_model.plant import Plant, vehicle_model
from swim_sim.wake_coupling import WakeCoupling, WakeCouplingParameters

#: 2 s of a swinging foil: the flow's lift and lag states change sign several times
PERIODS = 250
#: round-off of two compiled RK4s of the same equations over PERIODS (measured: equal bit for bit on this host)
ROUND_OFF = 1e-10
#: a flat plate broadside (Hoerner, Fluid-Dynamic Drag, Ch. 3) and skin friction, for the drag tests
FLAT_PLATE_NORMAL_DRAG_COEFFICIENT = 1.2
AXIAL_DRAG_COEFFICIENT = 0.01


@pytest.fixture(scope="module", params=[True, False], ids=["constrained", "free"])
def circulatory_model(request, rig):
    return vehicle_model("circulatory", rig, constrained=request.param)


def swinging_state(model):
    """(q, qdot, lag): the vehicle moving along alpha, heaving and pitching, the flow's lag states not at rest."""
    q = np.zeros(model.nq)
    if not model.constrained:
        q[1] = model.lane_radius_m
    qdot = np.zeros(model.nq)
    qdot[0], qdot[-2], qdot[-1] = 0.3, 2.0, -3.0
    return q, qdot, np.array([0.02, -0.05])


def torques(periods):
    """Heave and pitch torques of a few tenths of a newton metre, N m, one row per period."""
    k = np.arange(periods)[:, None]
    return 0.3 * np.sin(k * np.array([0.05, 0.08]))


def test_circulatory_plant_is_the_models_rk4(circulatory_model):
    """No disturbances: the plant's period is substeps of the model's own RK4 step with the torque held, lag states
    included, to round-off."""
    model = circulatory_model
    plant = Plant(model, Disturbances.none(), flow="circulatory")
    q, qdot, lag = swinging_state(model)
    plant.reset(q, qdot, lag=lag)
    commands = torques(PERIODS)
    for torque in commands:
        plant.step(torque)
    held = np.repeat(commands, plant.substeps, axis=0)   # the torque held over each substep
    q_ref, qdot_ref, lag_ref = model.integrate_rk4(q, qdot, held, plant.sample_period_s / plant.substeps, lag=lag)
    np.testing.assert_allclose(plant.q, q_ref[-1], rtol=0.0, atol=ROUND_OFF)
    np.testing.assert_allclose(plant.qdot, qdot_ref[-1], rtol=0.0, atol=ROUND_OFF)
    np.testing.assert_allclose(plant.lag, lag_ref[-1], rtol=0.0, atol=ROUND_OFF)
    np.testing.assert_array_equal(plant.state.lag, plant.lag)
    assert np.abs(lag_ref[-1] - lag).max() > 1e-3   # the lag states moved: the test compares something


def test_circulatory_momentum_and_energy_balance(circulatory_model):
    """No torque, no disturbances: dp_alpha/dt = Q_flow[0] and dT/dt = qdot . Q_flow (swim_model.vehicle), the
    changes over 2 s equal to the integrals of the flow's force along the plant's trajectory."""
    model = circulatory_model
    sample_period_s = 1e-3   # the same compiled period at 1 ms: samples fine enough for Simpson's rule
    plant = Plant(model, Disturbances.none(), sample_period_s=sample_period_s, flow="circulatory")
    plant.reset(*swinging_state(model)[:2])
    momenta, energies, hub_forces, powers = [], [], [], []
    for k in range(2001):
        _, generalized = model.flow_force(plant.q, plant.qdot, plant.lag)
        momenta.append(model.momentum(plant.q, plant.qdot)[0])
        energies.append(plant.energy())
        hub_forces.append(generalized[0])
        powers.append(float(plant.qdot @ generalized))
        if k < 2000:
            plant.step([0.0, 0.0])
    momentum_change = momenta[-1] - momenta[0]
    energy_change = energies[-1] - energies[0]
    assert abs(momentum_change) > 1e-3 * abs(momenta[0])   # the flow did change p_alpha (the ideal model cannot)
    assert momentum_change == pytest.approx(simpson(hub_forces, dx=sample_period_s), rel=1e-6)
    assert energy_change == pytest.approx(simpson(powers, dx=sample_period_s), rel=1e-6)


def test_circulatory_plant_takes_its_drag_from_the_flow_model_and_the_other_disturbances_from_disturbances(rig):
    """Disturbances' foil drag coefficients change nothing on the circulatory plant (the flow model's profile drag
    and separated normal force are the foil's drag); the hub's friction does change it."""
    model = vehicle_model("circulatory", rig, constrained=True)
    drag = dataclasses.replace(Disturbances.none(), foil_normal_drag_coefficient=FLAT_PLATE_NORMAL_DRAG_COEFFICIENT,
                               foil_axial_drag_coefficient=AXIAL_DRAG_COEFFICIENT)
    friction = dataclasses.replace(Disturbances.none(), hub_viscous_n_m_s=0.01)
    runs = {}
    for name, disturbances in (("none", Disturbances.none()), ("foil drag", drag), ("hub friction", friction)):
        plant = Plant(model, disturbances)
        assert plant.flow == "circulatory"
        q, qdot, lag = swinging_state(model)
        plant.reset(q, qdot, lag=lag)
        for torque in torques(100):
            plant.step(torque)
        runs[name] = np.concatenate([plant.q, plant.qdot, plant.lag])
    np.testing.assert_array_equal(runs["foil drag"], runs["none"])
    assert np.abs(runs["hub friction"] - runs["none"]).max() > 1e-4


def test_circulatory_plant_with_stick_slip_and_hard_stops(rig):
    """The larger state through the slow paths: the hub held by stiction under a small torque, pitch driven into
    its stop and held there, the lag states running on from the foil's motion."""
    model = vehicle_model("circulatory", rig, constrained=True)
    disturbances = dataclasses.replace(Disturbances.none(), hub_coulomb_n_m=0.5, hub_static_n_m=1.0)
    plant = Plant(model, disturbances, hard_limits_rad=((-0.5, 0.5), (-0.4, 0.4)))
    for _ in range(200):
        plant.step([0.02, 0.05])
    assert plant.q[0] == 0.0 and plant.qdot[0] == 0.0   # the hub stuck: 1 N m of stiction
    assert plant.q[2] == 0.4 and plant.at_stop[2] == 1   # pitch held at its upper stop
    assert np.isfinite(plant.lag).all() and np.abs(plant.lag).max() > 0.0


def test_wake_plant_separation_drag_is_half_rho_cd_area_v_squared(rig):
    """The wake plant with and without the foil's quadratic drag over a 1 us period from the same state: the
    difference of accelerations, Mm dqddot = Q2' F, gives back F = -1/2 rho Cd A |v| v on the chordwise (U) and
    normal (V) velocities of the foil frame, and no moment (A the foil's planform, chord x span)."""
    model = VehicleModel(rig, constrained=True)
    quiet = WakeCouplingParameters(force_limit_n=1e-12, moment_limit_n_m=1e-12)   # the wake's force off
    drag = dataclasses.replace(Disturbances.none(), foil_normal_drag_coefficient=FLAT_PLATE_NORMAL_DRAG_COEFFICIENT,
                               foil_axial_drag_coefficient=AXIAL_DRAG_COEFFICIENT)
    q, qdot = np.array([0.1, 0.3, -0.4]), np.array([0.3, 1.5, -2.0])
    period_s = 1e-6   # the accelerations' change within it is O(period): 1e-6 of the force (measured at 1e-5: 2e-6)
    accelerations = []
    for disturbances in (Disturbances.none(), drag):
        plant = Plant(model, disturbances, sample_period_s=period_s, substeps=1, flow="wake",
                      wake=WakeCoupling(model, quiet))
        plant.reset(q, qdot)
        plant.step([0.0, 0.0])
        accelerations.append((plant.qdot - qdot) / period_s)
    generalized = model.mass_matrix(q) @ (accelerations[1] - accelerations[0])
    q2 = model.foil_velocity_map(q)
    force = np.linalg.solve(q2.T, generalized)
    u, v, _ = q2 @ qdot
    area_m2 = rig.foil_chord_m * rig.foil_span_m
    half_rho = 0.5 * rig.water_density_kg_m3
    expected = [-half_rho * AXIAL_DRAG_COEFFICIENT * area_m2 * abs(u) * u,
                -half_rho * FLAT_PLATE_NORMAL_DRAG_COEFFICIENT * area_m2 * abs(v) * v, 0.0]
    np.testing.assert_allclose(force, expected, rtol=1e-4, atol=1e-6 * abs(expected[1]))
    assert abs(expected[1]) > 0.1   # a tenth of a newton and more: the normal drag is what the plant applies


def test_a_plant_is_built_for_one_flow(rig):
    ideal = VehicleModel(rig, constrained=True)
    assert Plant(ideal, Disturbances.none()).flow == "ideal"
    assert Plant(ideal, Disturbances.none()).wake is None
    built = Plant(ideal, Disturbances.none(), flow="wake")
    assert built.flow == "wake" and isinstance(built.wake, WakeCoupling)
    assert Plant(ideal, Disturbances.none(), wake=WakeCoupling(ideal)).flow == "wake"
    with pytest.raises(ValueError, match="vehicle_model"):
        Plant(ideal, Disturbances.none(), flow="circulatory")
    with pytest.raises(ValueError, match="one of"):
        Plant(ideal, Disturbances.none(), flow="potential")
    with pytest.raises(ValueError, match="for flow 'wake'"):
        Plant(ideal, Disturbances.none(), wake=WakeCoupling(ideal), flow="ideal")
    assert {f: vehicle_model(f, rig).flow for f in FLOWS} == {"ideal": "ideal", "circulatory": "circulatory",
                                                               "wake": "ideal"}


def test_reset_puts_the_flow_at_rest_unless_given(rig):
    model = vehicle_model("circulatory", rig, constrained=True)
    plant = Plant(model, Disturbances.none())
    q, qdot, lag = swinging_state(model)
    plant.reset(q, qdot, lag=lag)
    for torque in torques(20):
        plant.step(torque)
    plant.reset(np.zeros(3), np.zeros(3))
    np.testing.assert_array_equal(plant.state.lag, np.zeros(2))
    plant.reset(np.zeros(3), np.zeros(3), lag=[0.1, -0.2])
    np.testing.assert_array_equal(plant.lag, [0.1, -0.2])
    with pytest.raises(StateError, match="lag"):
        plant.reset(np.ones(3), np.zeros(3), lag=[0.1])
    np.testing.assert_array_equal(plant.q, np.zeros(3))   # refused: nothing changed
    with pytest.raises(StateError, match="lag"):
        Plant(VehicleModel(rig, constrained=True), Disturbances.none()).reset(np.zeros(3), np.zeros(3), lag=[0.1])


@pytest.mark.parametrize("constrained", [True, False], ids=["constrained", "free"])
def test_a_period_prepared_ahead_of_its_torque_steps_bit_for_bit_as_one_computed_with_it(rig, constrained):
    """Plant.prepare_period (sim_node's, while the controller computes): the wake and the waves of a period from its
    start state, the noise drawn in the same sequence, interleaved with the sensors' draws as sim_node makes them."""
    model = vehicle_model("wake", rig, constrained=constrained)
    runs = []
    for prepared in (False, True):
        plant = Plant(model, Disturbances(), seed=3, wake=WakeCoupling(model))
        q, qdot, _ = swinging_state(model)
        plant.reset(q, qdot)
        states, noise = [], []
        if prepared:
            plant.prepare_period()
        for k, torque in enumerate(torques(PERIODS)):
            if k == 100:   # a reset discards a prepared period
                plant.reset(q, qdot, time_s=plant.time_s)
                if prepared:
                    plant.prepare_period()
            state = plant.step(torque)
            noise.append(plant.rng.standard_normal())   # the sensors' draw after each period, as sim_node's
            if prepared:
                plant.prepare_period()
                plant.prepare_period()   # once per period: a second call does nothing
            states.append(np.concatenate([state.q, state.qdot]))
        runs.append((np.array(states), np.array(noise), plant.wake.vortices().time_s))
    (states, noise, wake_time_s), (prepared_states, prepared_noise, prepared_wake_time_s) = runs
    np.testing.assert_array_equal(prepared_states, states)
    np.testing.assert_array_equal(prepared_noise, noise)
    # the prepared run has stepped its wake once more, into the period after the last (and only once: not twice)
    assert prepared_wake_time_s == pytest.approx(wake_time_s + model.rig.sample_period_s, abs=1e-12)
    assert np.abs(states[:, model.nq - 2:model.nq]).max() > 0.1   # the foil moved: the wake's force mattered
