"""Workspace tests: shared fixtures. DDS traffic stays on this host and in a domain of our own."""
import os
import random
from pathlib import Path

import pytest

WORKSPACE = Path(__file__).resolve().parents[1]
PACKAGES = ("swim_model", "swim_planner", "swim_controller", "swim_sim", "swim_hw_bridge", "swim_interfaces")


@pytest.fixture(scope="session")
def ros_domain():
    """A ROS_DOMAIN_ID of our own for this test session, discovery limited to localhost."""
    domain = random.Random(os.getpid()).randint(1, 100)
    os.environ["ROS_DOMAIN_ID"] = str(domain)
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    return domain


@pytest.fixture()
def rclpy_context(ros_domain):
    import rclpy
    context = rclpy.Context()
    rclpy.init(context=context)
    yield context
    rclpy.shutdown(context=context)
