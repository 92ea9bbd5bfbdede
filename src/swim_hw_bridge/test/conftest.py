"""Fixtures: the shipped bridge config, its conversions and a safety layer at the 8 ms period."""
import pytest

from swim_hw_bridge.conversions import Conversions, load_bridge_config
from swim_hw_bridge.safety import SafetyLayer, SafetyLimits

PERIOD_S = 0.008
WATCHDOG_PERIODS = 5
STALE_READ_LIMIT = 3
READ_FAILURE_LIMIT = 3


@pytest.fixture(scope="session")
def config():
    return load_bridge_config()


@pytest.fixture(scope="session")
def conversions(config):
    return Conversions(config)


@pytest.fixture(scope="session")
def limits(config):
    return SafetyLimits.from_config(config, PERIOD_S, WATCHDOG_PERIODS, STALE_READ_LIMIT, READ_FAILURE_LIMIT)


@pytest.fixture()
def safety(limits):
    return SafetyLayer(limits)


# the shared DDS fixtures of every package's tests (a ROS domain of the process's own, a context, a node process)
from swim_ros.testing.fixtures import rclpy_context, ros_domain  # noqa: E402, F401
