import pytest

from swim_model import load_rig
from swim_planner.library import PrimitiveLibrary
from swim_planner.paths import default_library_path


@pytest.fixture(scope="session")
def rig():
    return load_rig()


@pytest.fixture(scope="session")
def library(rig):
    return PrimitiveLibrary.load(default_library_path(), rig)
