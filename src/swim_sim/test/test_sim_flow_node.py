"""sim_node's flow parameter over DDS: the circulatory flow and the vortex wake publish joint_states equal bit for
bit to the library's plant of that flow; with the wake, wake_vortices carries the wake's vortices, finite and within
the message's bound, at most once per wake.vortices_period_s of simulated time; a flow it does not know stops it
at start with a message naming the choices."""
import math

import numpy as np
import pytest
from test_sim_node import Driver, running_sim

from swim_ros.calls import spin_until
from swim_ros.testing.fixtures import MESSAGE_TIMEOUT_S, running_node

SEED = 13
PERIODS = 60
#: wake_vortices every 5 periods of 8 ms
VORTICES_PERIOD_S = 0.04
PERIODS_PER_MESSAGE = 5
#: sim_node refusing a parameter exits as soon as it has read it; 60 s only stops a node that did not exit
REFUSED_START_TIMEOUT_S = 60


def library_run(flow, seed, torques, after_step):
    """The run sim_node makes for these commands, in this process: the plant of the flow with sim_node's defaults
    (disturbances, sensors drawing on the plant's generator, the shipped rig's hard stops). Returns
    ([after_step(plant, positions measured) after each step], the plant)."""
    from swim_model import load_rig
    from swim_model.disturbances import Disturbances
    from swim_model.plant import Plant, vehicle_model
    from swim_sim.sensors import Sensors
    model = vehicle_model(flow, constrained=True)
    plant = Plant(model, Disturbances(), seed=seed, hard_limits_rad=load_rig().hard_limits_rad,
                  flow=flow)
    sensors = Sensors(model, sample_period_s=plant.sample_period_s)
    plant.reset(plant.rest_positions(), np.zeros(model.nq))
    sensors.measure(plant.q, plant.qdot, plant.rng)       # the state published after the reset
    results = []
    for torque in torques:
        plant.step(torque)
        results.append(after_step(plant, sensors.measure(plant.q, plant.qdot, plant.rng)[0]))
    return results, plant


@pytest.fixture(scope="module", params=["circulatory", "wake"])
def flow_sim(request, ros_domain, tmp_path_factory):
    log = tmp_path_factory.mktemp(f"sim_node_{request.param}") / "log.txt"
    with running_sim(log, "-p", f"seed:={SEED}", "-p", f"flow:={request.param}",
                     "-p", f"wake.vortices_period_s:={VORTICES_PERIOD_S}") as process:
        yield request.param, process


@pytest.fixture()
def driver(flow_sim, rclpy_context):
    from swim_interfaces.msg import WakeVortices
    with Driver(rclpy_context) as driver:
        driver.flow = flow_sim[0]
        driver.vortices = []
        driver.node.create_subscription(WakeVortices, "wake_vortices", driver.vortices.append, PERIODS + 10)
        driver.reset_and_wait()
        yield driver


def test_joint_states_are_the_flows_plant(driver):
    torques = 0.3 * np.sin(np.arange(PERIODS)[:, None] * np.array([0.05, 0.08]))
    states = driver.drive(torques)
    expected, plant = library_run(driver.flow, SEED, torques, lambda plant, positions: list(positions))
    assert [list(s.position) for s in states] == expected
    assert all(math.isfinite(v) for s in states for v in (*s.position, *s.velocity, *s.effort))
    assert np.abs(plant.q[0]) > 1e-6   # the vehicle moved: the comparison compares something
    if driver.flow == "circulatory":
        assert np.abs(plant.lag).max() > 1e-3   # the flow's lag states were driven (not published: not measurable)


def test_wake_vortices_are_sent_at_their_period_finite_and_bounded(driver):
    from swim_interfaces.msg import WakeVortices
    start = driver.states[-1].header.stamp
    states = driver.drive(np.full((PERIODS, 2), 0.2))
    if driver.flow != "wake":
        spin_until(driver.executor, lambda: False, 0.5)
        assert driver.vortices == []   # no wake, no vortices
        return
    # the reset's fresh wake is sent after the first period, then every VORTICES_PERIOD_S: 5 periods of 8 ms
    stamps = [start] + [s.header.stamp for s in states]
    expected = stamps[1::PERIODS_PER_MESSAGE]
    spin_until(driver.executor, lambda: len(driver.vortices) >= len(expected), MESSAGE_TIMEOUT_S)
    messages = [m for m in driver.vortices if (m.header.stamp.sec, m.header.stamp.nanosec) >
                (start.sec, start.nanosec)]
    assert [m.header.stamp for m in messages] == expected
    for message in messages:
        count = len(message.x_m)
        assert count == len(message.y_m) == len(message.circulations_m2_s) == message.vortex_count
        assert 0 < count <= WakeVortices.MAX_VORTEX_COUNT
        values = [*message.x_m, *message.y_m, *message.circulations_m2_s, message.trailing_edge_x_m,
                  message.trailing_edge_y_m]
        assert all(math.isfinite(v) for v in values)
        # in the tank, near the foil: the lane is 0.4-0.5 m from the hub
        assert max(math.hypot(x, y) for x, y in zip(message.x_m, message.y_m)) < 1.0
    # one vortex shed per period: the count grows by the periods between two messages
    assert [m.vortex_count for m in messages] == [1 + PERIODS_PER_MESSAGE * k for k in range(len(messages))]


def test_an_unknown_flow_refuses_to_start_naming_the_choices(ros_domain, tmp_path):
    log = tmp_path / "log.txt"
    with running_node("swim_sim", "sim_node", log, "-p", "flow:=potential") as process:
        assert process.wait(timeout=REFUSED_START_TIMEOUT_S) == 2
    text = log.read_text()
    assert "flow" in text and "'circulatory'" in text and "'wake'" in text
