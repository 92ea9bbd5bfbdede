"""Fixtures of the simulator's tests: the rig, the vehicle models, and the DDS fixtures every package's tests
share (swim_ros.testing.fixtures)."""
import pytest

from swim_model import VehicleModel, load_rig
from swim_ros.testing.fixtures import rclpy_context, ros_domain  # noqa: F401


@pytest.fixture(scope="module")
def rig():
    return load_rig()


@pytest.fixture(scope="module", params=[True, False], ids=["constrained", "free"])
def model(request, rig):
    return VehicleModel(rig, constrained=request.param)
