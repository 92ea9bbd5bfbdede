"""The emulated rig's water (PlantSettings.flow_only) against independent integrations: the ideal flow is
swim_model's RK4 of the ideal VehicleModel, the circulatory flow that of VehicleModel(flow="circulatory") with its
lag states; the wake flow is the ideal model with the wake's held force and the foil's separation drag, integrated
here by an RK4 of our own on the model's forward dynamics; the plant's settings given as device options are
refused. Each test advances the rig over one read interval of set length (no wall clock)."""
import numpy as np
import pytest

from swim_hw_bridge.backends import make_device
from swim_model import VehicleModel
from swim_model.disturbances import FLAT_PLATE_BROADSIDE_DRAG_COEFFICIENT, THIN_SECTION_AXIAL_DRAG_COEFFICIENT
from swim_model.plant import PlantSettings
from swim_model.wake_coupling import WakeCoupling

READ_INTERVAL_S = 0.008
CURRENTS_A = (0.4, -0.3)
#: the rig moving at the start of the interval: hub, rail, heave and pitch rates (rad/s, m/s)
START_VELOCITIES = np.array([0.2, 0.01, 1.5, -2.0])
#: the same RK4 as compiled code and as numpy: round-off on states of order 1
ROUND_OFF = 1e-12


def advanced_device(config, flow):
    """An emulated rig of this flow, opened and moving, after one read interval with CURRENTS_A flowing."""
    device = make_device("emulated", {**config.device_config("emulated"), "plant": PlantSettings.flow_only(flow)})
    device.open()
    plant = device.plant
    plant.reset(plant.q, START_VELOCITIES)
    start = (plant.q.copy(), plant.qdot.copy(), plant.lag.copy())
    device.enable()
    device.toggle_enable()
    device.write_currents(*CURRENTS_A)
    # the interval starts at the enable edge (the amplifiers conduct), on a clock at zero so that its length is
    # READ_INTERVAL_S exactly
    device._time_s = device._last_toggle_s = 0.0
    device._advance(READ_INTERVAL_S)
    return device, start


def joint_torques(config):
    """tau = N Kt i over the interval, N m (heave, pitch)."""
    return np.array(CURRENTS_A) * np.array(config.motor_torque_gains_n_m_per_a)


def test_circulatory_rig_is_the_circulatory_models_rk4_with_its_lag_states(config):
    device, (q, qdot, lag) = advanced_device(config, "circulatory")
    plant = device.plant
    assert plant.model.flow == "circulatory" and np.array_equal(lag, np.zeros(2))   # the flow at rest at open
    torques = np.tile(joint_torques(config), (plant.substeps, 1))
    model = VehicleModel(constrained=False, flow="circulatory")
    q_ref, qdot_ref, lag_ref = model.integrate_rk4(q, qdot, torques, READ_INTERVAL_S / plant.substeps, lag=lag)
    np.testing.assert_allclose(plant.q, q_ref[-1], rtol=0.0, atol=ROUND_OFF)
    np.testing.assert_allclose(plant.qdot, qdot_ref[-1], rtol=0.0, atol=ROUND_OFF)
    np.testing.assert_allclose(plant.lag, lag_ref[-1], rtol=0.0, atol=ROUND_OFF)
    assert np.abs(plant.lag).max() > 1e-4   # the foil's motion drove the lag states


def test_wake_rig_is_the_ideal_model_with_the_wakes_force_and_the_separation_drag(config):
    device, (q, qdot, _) = advanced_device(config, "wake")
    model = VehicleModel(constrained=False)
    wake = WakeCoupling(model)
    held = wake.step(q, qdot, READ_INTERVAL_S)   # the first interval: the wake stepped over it, at its start
    assert np.abs(held).max() > 1e-3   # the shed vortex's force is there: the comparison includes it
    rig = model.rig
    half_rho_area = 0.5 * rig.water_density_kg_m3 * rig.foil_chord_m * rig.foil_span_m
    factors = half_rho_area * np.array([THIN_SECTION_AXIAL_DRAG_COEFFICIENT, FLAT_PLATE_BROADSIDE_DRAG_COEFFICIENT])
    tau = joint_torques(config)

    def rate(x):
        position, velocity = x[:4], x[4:]
        q2 = model.foil_velocity_map(position)
        u, v, _ = q2 @ velocity
        drag = q2.T @ np.array([-factors[0] * abs(u) * u, -factors[1] * abs(v) * v, 0.0])
        qddot = (model.forward_dynamics(position, velocity, tau)
                 + np.linalg.solve(model.mass_matrix(position), drag + held))
        return np.concatenate([velocity, qddot])

    plant = device.plant
    x, h = np.concatenate([q, qdot]), READ_INTERVAL_S / plant.substeps
    for _ in range(plant.substeps):
        k1 = rate(x)
        k2 = rate(x + 0.5 * h * k1)
        k3 = rate(x + 0.5 * h * k2)
        k4 = rate(x + h * k3)
        x = x + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    np.testing.assert_allclose(plant.q, x[:4], rtol=0.0, atol=ROUND_OFF)
    np.testing.assert_allclose(plant.qdot, x[4:], rtol=0.0, atol=ROUND_OFF)
    assert plant.wake is not None and plant.wake.wake.vortex_count() == 1 and plant.lag.size == 0


def test_ideal_rig_has_no_wake_and_no_lag_states(config):
    device, (q, qdot, _) = advanced_device(config, "ideal")
    plant = device.plant
    assert plant.wake is None and plant.lag.size == 0 and plant.model.flow == "ideal"
    torques = np.tile(joint_torques(config), (plant.substeps, 1))
    q_ref, qdot_ref = VehicleModel(constrained=False).integrate_rk4(q, qdot, torques,
                                                                    READ_INTERVAL_S / plant.substeps)
    np.testing.assert_allclose(plant.q, q_ref[-1], rtol=0.0, atol=ROUND_OFF)
    np.testing.assert_allclose(plant.qdot, qdot_ref[-1], rtol=0.0, atol=ROUND_OFF)


def test_an_unknown_flow_and_the_plants_settings_as_device_options_are_refused(config):
    with pytest.raises(ValueError, match="ideal, circulatory, wake"):
        PlantSettings.flow_only("potential")
    for option in ("flow", "substeps", "hard_stops", "foil_normal_drag_coefficient"):
        with pytest.raises(ValueError, match=f"{option} are the plant's settings"):
            make_device("emulated", {**config.device_config("emulated"), option: 1})
