"""Library builds: dependency order, the longest solves first, resumability, and a Dask cluster through the Executor
interface; local workers that die with the build."""
import concurrent.futures
import ctypes
import dataclasses
import os
import subprocess
import sys
import textwrap
import threading
import uuid

import casadi
import numpy as np
import pytest

from swim_planner.build import build_library, critical_work, expected_work, local_executor, solve_job
from swim_planner.library import PrimitiveLibrary
from swim_planner.primitives import PrimitiveSpec, PrimitiveType
from swim_ros.processes import start_child
from swim_ros.testing.processes import processes_left

LANE = 0.43
#: how long a build's workers may take to end once it is killed: their parent-death signal is immediate
WORKER_END_TIMEOUT_S = 10.0
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


class RecordingExecutor(concurrent.futures.ThreadPoolExecutor):
    """Records the spec of every solve submitted, in order, and the most solves in flight at once."""

    def __init__(self, max_workers: int) -> None:
        super().__init__(max_workers=max_workers)
        self.solved: list[str] = []
        self.in_flight = self.most_in_flight = 0
        self._lock = threading.Lock()

    def submit(self, fn, /, *args, **kwargs):
        if fn is not solve_job:
            return super().submit(fn, *args, **kwargs)
        with self._lock:
            self.solved.append(args[1].primitive_id)
            self.in_flight += 1
            self.most_in_flight = max(self.most_in_flight, self.in_flight)
        future = super().submit(fn, *args, **kwargs)
        future.add_done_callback(self._ended)
        return future

    def _ended(self, _future) -> None:
        with self._lock:
            self.in_flight -= 1


LONGER = PrimitiveSpec("small/accelerate_longer", PrimitiveType.ACCELERATE, True, 3.0, LANE, LANE,
                       end_at="small/cruise", intervals=36)
LONE_CRUISE = PrimitiveSpec("small/cruise_alone", PrimitiveType.CRUISE, True, 1.0, LANE, LANE, energy_j=0.06,
                            intervals=20)


@pytest.mark.parametrize("workers, order", [
    (None, ["small/cruise", "small/cruise_alone", "small/accelerate_longer", "small/accelerate"]),
    (1, ["small/cruise", "small/accelerate_longer", "small/accelerate", "small/cruise_alone"])])
def test_the_longest_chain_is_submitted_first(rig, tmp_path, workers, order):
    """The cruise two accelerates join goes before the lone cruise, though the lone one has more intervals, and the
    accelerate with more intervals before the other, whatever the order of the specs. Told the worker count, the
    build keeps no more solves than that in flight (and so starts the accelerates before the lone cruise); not told
    it, it submits whatever is ready at once."""
    library = PrimitiveLibrary.create_or_open(tmp_path / "lib", rig)
    with RecordingExecutor(max_workers=2) as executor:
        assert build_library(library, [LONE_CRUISE] + SMALL + [LONGER], executor, workers=workers) == []
    assert executor.solved == order
    if workers is None:
        assert executor.most_in_flight >= 2
    else:
        assert executor.most_in_flight == workers


def test_critical_work_is_a_specs_work_and_the_longest_chain_after_it():
    assert critical_work([LONE_CRUISE] + SMALL + [LONGER]) == {
        "small/cruise_alone": 20, "small/cruise": 16 + 36, "small/accelerate": 24, "small/accelerate_longer": 36}


def test_a_worker_count_below_one_is_refused(rig, tmp_path):
    library = PrimitiveLibrary.create_or_open(tmp_path / "lib", rig)
    with pytest.raises(ValueError, match="workers must be at least 1"):
        build_library(library, SMALL, concurrent.futures.ThreadPoolExecutor(1), workers=0)
    assert library.ids() == []


def test_expected_work_counts_every_solve_of_a_continuation_and_a_refinement():
    """Intervals times solves: one solve; a continuation of two looser bounds is four (none, the two, the limit);
    on a coarser grid, those four there and one on the spec's own grid."""
    plain = SMALL[1]
    assert expected_work(plain) == 24
    continued = PrimitiveSpec("small/decelerate", PrimitiveType.DECELERATE, True, 2.0, LANE, LANE,
                              start_from="small/cruise", intervals=40, angle_of_attack_continuation_rad=(0.6, 0.5))
    assert expected_work(continued) == 4 * 40
    assert expected_work(dataclasses.replace(continued, coarse_intervals=20)) == 4 * 20 + 40


def _ipopt_blas_threads() -> int:
    """The thread count of the OpenBLAS CasADi's IPOPT runs on, in this process, after a solve has loaded it."""
    x = casadi.MX.sym("x")
    casadi.nlpsol("s", "ipopt", {"x": x, "f": x ** 2}, {"ipopt.print_level": 0, "ipopt.sb": "yes",
                                                        "print_time": False})(x0=1.0)
    with open("/proc/self/maps") as maps:
        path = next(line.split()[-1] for line in maps if "casadi-tp-openblas" in line)
    return ctypes.CDLL(path).openblas_get_num_threads()


def test_local_workers_run_ipopts_blas_on_one_thread():
    """Even after this process has run IPOPT on its BLAS's default threads (one per core)."""
    _ipopt_blas_threads()
    with local_executor(1) as executor:
        assert executor.submit(_ipopt_blas_threads).result() == 1


def test_local_workers_die_with_the_build():
    """A build killed outright leaves no worker: an idle one waits for its next job on a queue whose writing end it
    holds itself, so no end of file ever tells it the build is gone; its parent-death signal does."""
    tag = uuid.uuid4().hex
    build = start_child([sys.executable, "-c", textwrap.dedent("""
        import os, time
        from swim_planner.build import local_executor
        executor = local_executor(2)
        print(executor.submit(os.getpid).result(), flush=True)
        time.sleep(600)
        """)], stdout=subprocess.PIPE, text=True, env={**os.environ, "SWIM_BUILD_TEST": tag})
    try:
        worker = int(build.stdout.readline())
    finally:
        build.kill()
        build.wait()
    assert worker > 0 and processes_left("SWIM_BUILD_TEST", tag, WORKER_END_TIMEOUT_S) == []


def test_changed_spec_is_solved_again_with_what_joins_it(rig, tmp_path):
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
