"""Fixtures of the simulator's tests: the rig and the vehicle models."""
import pytest

from swim_model import VehicleModel, load_rig


@pytest.fixture(scope="module")
def rig():
    return load_rig()


@pytest.fixture(scope="module", params=[True, False], ids=["constrained", "free"])
def model(request, rig):
    return VehicleModel(rig, constrained=request.param)
