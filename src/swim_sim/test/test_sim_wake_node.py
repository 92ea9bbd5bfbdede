"""sim_node with the vortex wake on (flow wake) over DDS: one wake_statistics message per period, equal bit for
bit to the library's plant and wake driven by the same commands; reset clears the wake; bad wake parameters refuse
to start with a message naming them."""
import numpy as np
import pytest
from test_sim_flow_node import library_run
from test_sim_node import Driver, running_sim

from swim_ros.calls import spin_until
from swim_ros.testing.fixtures import MESSAGE_TIMEOUT_S, running_node

SEED = 11
PERIODS = 120
#: sim_node refusing bad parameters exits as soon as it has read them: seconds of Python imports on a loaded host;
#: 60 s only stops a node that did not exit
REFUSED_START_TIMEOUT_S = 60


@pytest.fixture(scope="module")
def wake_sim(ros_domain, tmp_path_factory):
    log = tmp_path_factory.mktemp("sim_node_wake") / "log.txt"
    with running_sim(log, "-p", f"seed:={SEED}", "-p", "flow:=wake") as process:
        yield process


@pytest.fixture()
def driver(wake_sim, rclpy_context):
    from swim_interfaces.msg import WakeStatistics
    with Driver(rclpy_context) as driver:
        driver.wakes = []
        driver.node.create_subscription(WakeStatistics, "wake_statistics", driver.wakes.append, PERIODS + 10)
        driver.reset_and_wait()
        yield driver


def wait_for_wakes(driver, count, timeout_s=MESSAGE_TIMEOUT_S):
    spin_until(driver.executor, lambda: len(driver.wakes) >= count, timeout_s)


def test_wake_statistics_every_period_equal_to_the_librarys(driver):
    torques = 0.3 * np.sin(np.arange(PERIODS)[:, None] * np.array([0.05, 0.08]))
    start = driver.states[-1].header.stamp
    states = driver.drive(torques)
    wait_for_wakes(driver, PERIODS)
    wakes = driver.wakes
    assert len(wakes) == PERIODS
    # each message belongs to the period that starts at the state before it: its force was held over that period
    assert [w.header.stamp for w in wakes] == [start] + [s.header.stamp for s in states[:-1]]
    assert [w.vortex_count for w in wakes] == list(range(1, PERIODS + 1))   # one shed per period, none merged yet
    expected, _ = library_run("wake", SEED, torques, lambda plant, _: plant.wake.statistics())
    assert [list(w.generalized_force) for w in wakes] == [list(e.generalized_force) for e in expected]
    assert [(w.force_x_n, w.force_y_n, w.moment_n_m) for w in wakes] == [e.foil_force for e in expected]
    assert [w.thrust_n for w in wakes] == [e.thrust_n for e in expected]
    assert [w.shed_circulation_m2_s for w in wakes] == [e.shed_circulation_m2_s for e in expected]
    assert list(wakes[-1].joint_names) == ["alpha", "phi", "theta"]
    assert max(abs(w.total_circulation_m2_s) for w in wakes) < 1e-12          # Kelvin, to round-off
    assert max(abs(w.force_y_n) for w in wakes) > 1e-3                        # the foil did shed a wake
    assert wakes[-1].clipped_count == 0


def test_reset_clears_the_wake(driver):
    from std_srvs.srv import Trigger
    driver.drive(np.full((20, 2), 0.2))
    assert driver.call(Trigger, "reset", Trigger.Request()).success
    assert driver.wait_for_states(len(driver.states) + 1)
    count = len(driver.wakes)
    driver.drive(np.full((1, 2), 0.2))
    wait_for_wakes(driver, count + 1)
    assert [w.vortex_count for w in driver.wakes[count - 2:]] == [19, 20, 1]


def test_bad_wake_parameters_refuse_to_start_with_a_message(ros_domain, tmp_path):
    log = tmp_path / "log.txt"
    with running_node("swim_sim", "sim_node", log, "-p", "flow:=wake",
                      "-p", "wake.core_radius_m:=-1.0") as process:
        assert process.wait(timeout=REFUSED_START_TIMEOUT_S) == 2
    assert "core_radius_m" in log.read_text()

