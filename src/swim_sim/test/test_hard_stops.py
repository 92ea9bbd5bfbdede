"""The plant's hard stops: held full torque never takes a joint past its limit, a joint at its stop has no speed
into it, leaves it when pulled back, contact only removes energy, and a run that never reaches a stop is
integrated bit for bit as without stops."""
import numpy as np
import pytest

from swim_model import StateError, load_rig
from swim_model.disturbances import Disturbances
from swim_model.plant import Plant
from swim_sim.sensors import Sensors

HARD_LIMITS = load_rig().hard_limits_rad
#: 0.5 s of held torque: a light link at full torque crosses its whole range in about 0.2 s (measured: the heave
#: link from mid-range reaches its stop after 0.19 s)
HELD_PERIODS = 63
#: where each run starts: fractions of each joint's range, from near one stop to near the other
START_FRACTIONS = (-0.9, -0.5, 0.0, 0.5, 0.9)
#: held commands: full torque (10 N m, past both motor limits, so clipped to them) on one joint or both
HELD_TORQUES = ((10.0, 0.0), (-10.0, 0.0), (0.0, 10.0), (0.0, -10.0), (10.0, 10.0), (-10.0, 10.0))


@pytest.fixture(scope="module")
def plant(model):
    return Plant(model, Disturbances(), hard_limits_rad=HARD_LIMITS)


def start_positions(plant, fraction):
    q = plant.rest_positions()
    for offset, (lower, upper) in zip((2, 1), HARD_LIMITS):
        q[-offset] = 0.5 * (lower + upper) + fraction * 0.5 * (upper - lower)
    return q


@pytest.mark.parametrize("torque", HELD_TORQUES)
def test_full_torque_held_from_anywhere_never_passes_a_stop(plant, torque):
    lower, upper = np.array(HARD_LIMITS).T
    for fraction in START_FRACTIONS:
        plant.reset(start_positions(plant, fraction), np.zeros(plant.model.nq))
        joints = []
        for _ in range(HELD_PERIODS):
            state = plant.step(torque)
            joints.append(state.q[-2:])
            # the tolerance is zero: a joint meeting its stop is put at the limit, never past it
            assert np.all(state.q[-2:] >= lower) and np.all(state.q[-2:] <= upper), (fraction, state.q)
            for offset, side in zip((2, 1), (plant.at_stop[plant.model.nq - 2], plant.at_stop[plant.model.nq - 1])):
                if side:   # held at a stop: at its limit with no speed into it
                    assert state.q[-offset] == (upper if side > 0 else lower)[2 - offset]
                    assert state.qdot[-offset] == 0.0
        for joint in (0, 1):   # a joint driven outward by its own full torque ends at the stop it is driven to
            if torque[joint]:
                assert joints[-1][joint] == (upper if torque[joint] > 0 else lower)[joint], (fraction, joints[-1])


def test_a_joint_leaves_its_stop_when_its_torque_turns_back(plant):
    index = plant.model.nq - 1
    plant.reset(start_positions(plant, 0.5), np.zeros(plant.model.nq))
    for _ in range(HELD_PERIODS):
        plant.step([0.0, 10.0])
    assert plant.at_stop[index] == 1 and plant.q[index] == HARD_LIMITS[1][1]
    plant.step([0.0, -10.0])
    assert plant.at_stop[index] == 0 and plant.q[index] < HARD_LIMITS[1][1] and plant.qdot[index] < 0.0


def test_contact_only_removes_energy(model):
    """No torque, no disturbances: the energy is conserved between contacts and lost at them."""
    plant = Plant(model, Disturbances.none(), hard_limits_rad=HARD_LIMITS)
    qdot = np.zeros(model.nq)
    qdot[0], qdot[-2], qdot[-1] = 0.3, 4.0, -6.0   # well inside the rig's physically possible speeds
    plant.reset(plant.rest_positions(), qdot)
    energies, contacts = [plant.energy()], 0
    for _ in range(HELD_PERIODS):
        before = dict(plant.at_stop)
        plant.step([0.0, 0.0])
        energies.append(plant.energy())
        contacts += sum(1 for i in before if plant.at_stop[i] and not before[i])
    assert contacts >= 2   # both joints met a stop
    assert np.all(np.diff(energies) <= 1e-9 * energies[0])
    assert energies[-1] < 0.5 * energies[0]


def test_a_run_that_never_reaches_a_stop_is_unchanged_bit_for_bit(rig):
    """The free vehicle with every disturbance (friction stopping and breaking away included), its joints swung by
    a PD law around sines (torques from the state, so both runs get the same ones only if the states are equal)."""
    from swim_model import VehicleModel
    model = VehicleModel(rig, constrained=False)

    def run(hard_limits):
        plant = Plant(model, Disturbances(), seed=7, hard_limits_rad=hard_limits)
        qdot = np.zeros(model.nq)
        qdot[0], qdot[-2], qdot[-1] = 0.3, 1.0, -1.5
        plant.reset(plant.rest_positions(), qdot)
        sensors = Sensors(model)
        states = []
        for k in range(500):
            target = np.array([0.6 * np.sin(0.05 * k), 0.9 * np.sin(0.07 * k)])
            plant.step(0.5 * (target - plant.q[2:]) - 0.05 * plant.qdot[2:])
            states.append(np.concatenate([plant.q, plant.qdot, sensors.measure(plant.q, plant.qdot, plant.rng)[0]]))
        return np.array(states)

    with_stops, without = run(HARD_LIMITS), run(None)
    swing = np.abs(without[:, 2:4]).max(axis=0)
    assert np.all(swing > 0.5) and np.all(swing < [upper for _, upper in HARD_LIMITS])   # swung, never to a stop
    assert np.array_equal(with_stops, without)


def test_a_state_past_a_stop_is_refused_and_nothing_changes(plant):
    plant.reset(start_positions(plant, 0.5), np.zeros(plant.model.nq))
    before = plant.state
    past = plant.rest_positions()
    past[-1] = HARD_LIMITS[1][1] + 1e-6
    with pytest.raises(StateError, match="theta .* past its hard stop"):
        plant.reset(past, np.zeros(plant.model.nq))
    assert np.array_equal(plant.q, before.q) and plant.time_s == before.time_s
    with pytest.raises(ValueError, match="lower < upper"):
        Plant(plant.model, hard_limits_rad=((0.5, -0.5), HARD_LIMITS[1]))
