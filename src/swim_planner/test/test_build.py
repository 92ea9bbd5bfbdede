"""Library builds: dependency order, resumability, and a Dask cluster through the Executor interface."""
import concurrent.futures

import numpy as np
import pytest

from swim_planner.build import build_library
from swim_planner.library import PrimitiveLibrary
from swim_planner.primitives import PrimitiveSpec, PrimitiveType

LANE = 0.43
SMALL = [
    PrimitiveSpec("small/cruise", PrimitiveType.CRUISE, True, 1.0, LANE, LANE, energy_j=0.05, intervals=16),
    PrimitiveSpec("small/accelerate", PrimitiveType.ACCELERATE, True, 2.0, LANE, LANE, end_at="small/cruise",
                  intervals=24),
]


def test_build_in_order_then_resume(rig, tmp_path):
    library = PrimitiveLibrary.create_or_open(tmp_path / "lib", rig)
    events = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=2) as executor:
        failed = build_library(library, SMALL, executor, progress=lambda i, s: events.append((i, s)))
    assert failed == []
    assert events == [("small/cruise", "solved"), ("small/accelerate", "solved")]
    accelerate, cruise = library.get("small/accelerate"), library.get("small/cruise")
    np.testing.assert_allclose(accelerate.end_state[1], cruise.start_state[1], atol=1e-6)
    # a second build finds everything cached and solves nothing
    reopened = PrimitiveLibrary.create_or_open(tmp_path / "lib", rig)
    events.clear()
    with concurrent.futures.ThreadPoolExecutor(max_workers=1) as executor:
        assert build_library(reopened, SMALL, executor, progress=lambda i, s: events.append((i, s))) == []
    assert sorted(events) == [("small/accelerate", "cached"), ("small/cruise", "cached")]


def test_changed_spec_is_solved_again_with_what_joins_it(rig, tmp_path):
    import dataclasses
    library = PrimitiveLibrary.create_or_open(tmp_path / "lib", rig)
    with concurrent.futures.ThreadPoolExecutor(max_workers=1) as executor:
        assert build_library(library, SMALL, executor) == []
        changed = [dataclasses.replace(SMALL[0], energy_j=0.06), SMALL[1]]
        events = []
        assert build_library(library, changed, executor, progress=lambda i, s: events.append((i, s))) == []
    assert events == [("small/cruise", "solved"), ("small/accelerate", "solved")]
    assert library.spec("small/cruise").energy_j == 0.06


def test_unknown_dependency_is_refused(rig, tmp_path):
    library = PrimitiveLibrary.create_or_open(tmp_path / "lib", rig)
    with pytest.raises(ValueError, match="depends on unknown primitives: small/cruise"):
        build_library(library, SMALL[1:], concurrent.futures.ThreadPoolExecutor(1))


def test_build_on_a_dask_local_cluster(rig, tmp_path):
    import distributed
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                  host="127.0.0.1") as cluster, distributed.Client(cluster) as client:
        library = PrimitiveLibrary.create_or_open(tmp_path / "lib", rig)
        failed = build_library(library, SMALL, client.get_executor())
    assert failed == [] and library.ids() == ["small/accelerate", "small/cruise"]
    assert library.get("small/cruise").solver_status == "Solve_Succeeded"
