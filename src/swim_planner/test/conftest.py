"""Fixtures of the planner's tests: the rig, the shipped primitive library, vehicle models, and the DDS fixtures
every package's tests share (swim_ros.testing.fixtures)."""
import pytest

from swim_model import load_rig
from swim_planner.library import PrimitiveLibrary
from swim_planner.paths import default_library_path
from swim_ros.testing.fixtures import rclpy_context, ros_domain  # noqa: F401


@pytest.fixture(scope="session")
def rig():
    return load_rig()


@pytest.fixture(scope="session")
def library(rig):
    return PrimitiveLibrary.load(default_library_path(), rig)


@pytest.fixture(scope="session")
def circulatory_library(rig):
    """The shipped library of the circulatory flow model."""
    return PrimitiveLibrary.load(default_library_path("circulatory"), rig, "circulatory")


@pytest.fixture(scope="session")
def model_for(rig):
    """VehicleModel for a primitive's spec and a flow model, built once per (constrained, lane, flow)."""
    from swim_model import VehicleModel
    cache = {}

    def make(spec, flow="ideal"):
        key = (spec.constrained, spec.lane_radius_m, flow)
        if key not in cache:
            cache[key] = VehicleModel(rig, constrained=spec.constrained, lane_radius_m=spec.lane_radius_m, flow=flow)
        return cache[key]
    return make
