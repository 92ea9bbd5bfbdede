"""The sliding mode's bound D(t) from the build to the plan: a small circulatory library (the shipped constrained
E = 0.05 accelerate and cruise, copied into a temporary library as a format-3 library holds them) gets each
primitive's D(t) from ``build_library``, once, equal to the envelope of an independent ``flow_force_mismatch``;
the library keeps it with new gains and drops it with a new motion, refuses a corrupt or malformed one, reads a
format-3 library with none; ideal-flow libraries never get one; a plan joins the stored bounds like the torques
and scales them by lambda^2, which is what the flow models give along the primitive run lambda times faster."""
import concurrent.futures
import dataclasses
import json

import numpy as np
import pytest

from swim_planner.build import build_library
from swim_planner.disturbance import (
    ENVELOPE_HALF_WIDTH_S,
    MAX_WAKE_STEP_S,
    bound_envelope,
    flow_force_mismatch,
    lead_in_ids,
    measuring_wake,
    wake_record,
)
from swim_planner.errors import LibraryError
from swim_planner.library import FORMAT_VERSION, MANIFEST, PrimitiveLibrary
from swim_planner.maneuver import concatenate, expand_sequence

ACCELERATE = "constrained/accelerate/E0.05"
CRUISE = "constrained/cruise/E0.05"
IDS = [ACCELERATE, CRUISE]
MEASURED = "disturbance bound measured"
#: the wake is homogeneous of degree 2 in the velocities only up to its core radius and least shedding distance:
#: along the accelerate run 1.5 times faster (the same wake steps in the primitive's own time) lambda^2 D and the
#: direct measurement differed by 1.0 % of the largest D (the reduced model's force: by 1e-12 N)
SCALED_WAKE_AGREEMENT = 0.02
TIME_SCALE = 1.5


def _copy(source, path, rig, ids, flow_model):
    library = PrimitiveLibrary.create_or_open(path, rig, flow_model=flow_model)
    for primitive_id in ids:
        library.add(source.get(primitive_id))
    return library


@pytest.fixture(scope="module")
def bounded(rig, circulatory_library, tmp_path_factory):
    """(library, build events, specs): the two primitives copied, then built: D(t) measured, nothing solved."""
    library = _copy(circulatory_library, tmp_path_factory.mktemp("bounded") / "lib", rig, IDS, "circulatory")
    specs = [circulatory_library.spec(i) for i in IDS]
    events = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=2) as executor:
        assert build_library(library, specs, executor, progress=lambda i, s: events.append((i, s))) == []
    return library, events, specs


def test_the_build_measures_each_circulatory_primitive_once(bounded, rig, model_for):
    library, events, specs = bounded
    assert sorted(i for i, s in events if s.startswith(MEASURED)) == sorted(IDS)
    assert sorted(i for i, s in events if s == "cached") == sorted(IDS)
    assert json.loads((library.path / MANIFEST).read_text())["format_version"] == FORMAT_VERSION == 4
    # measured along the primitive after its lead-in: the accelerate from still water, the cruise after itself
    assert library.entry(ACCELERATE)["disturbance_bound"]["lead_in"] == [] == lead_in_ids(library.spec(ACCELERATE))
    assert library.entry(CRUISE)["disturbance_bound"]["lead_in"] == [CRUISE]
    primitive = library.get(ACCELERATE)
    profile = flow_force_mismatch(model_for(primitive.spec, "circulatory"), primitive)
    stored = library.disturbance_bound(ACCELERATE)
    np.testing.assert_array_equal(stored, bound_envelope(profile.time_s, profile.disturbance_bound_n_m,
                                                         ENVELOPE_HALF_WIDTH_S))
    assert np.all(stored >= profile.disturbance_bound_n_m) and stored.max() == profile.disturbance_bound_n_m.max()
    # read back from disk by a fresh load, and a second build measures nothing again
    reloaded = PrimitiveLibrary.load(library.path, rig, "circulatory")
    np.testing.assert_array_equal(reloaded.disturbance_bound(ACCELERATE), stored)
    again = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=1) as executor:
        assert build_library(reloaded, specs, executor, progress=lambda i, s: again.append((i, s))) == []
    assert sorted(again) == [(ACCELERATE, "cached"), (CRUISE, "cached")]


def test_the_envelope_is_the_running_maximum():
    rng = np.random.default_rng(3)
    time_s = np.cumsum(rng.uniform(0.01, 0.04, size=60))
    bound = rng.uniform(0.0, 1.0, size=60)
    envelope = bound_envelope(time_s, bound, 0.05)
    brute = [max(b for s, b in zip(time_s, bound) if abs(s - t) <= 0.05) for t in time_s]
    np.testing.assert_array_equal(envelope, brute)
    np.testing.assert_array_equal(bound_envelope(time_s, bound, 0.0), bound)


def test_new_gains_keep_the_bound_and_a_new_motion_drops_it(bounded, rig, tmp_path):
    library = _copy(bounded[0], tmp_path / "lib", rig, IDS, "circulatory")
    assert library.needs_disturbance_bound(ACCELERATE)   # a copied primitive comes without its bound
    stored = bounded[0].disturbance_bound(ACCELERATE)
    library.add_disturbance_bound(ACCELERATE, stored, {"how": "copied"})
    primitive = library.get(ACCELERATE)
    library.add(dataclasses.replace(primitive, gains=dataclasses.replace(primitive.gains)))
    np.testing.assert_array_equal(library.disturbance_bound(ACCELERATE), stored)
    moved = primitive.q.copy()
    moved[:, 1] += 1e-9
    library.add(dataclasses.replace(primitive, q=moved))
    assert library.disturbance_bound(ACCELERATE) is None and library.needs_disturbance_bound(ACCELERATE)


def test_a_bound_measured_in_another_wake_is_measured_again(bounded, rig, circulatory_library, tmp_path):
    library = _copy(bounded[0], tmp_path / "lib", rig, IDS, "circulatory")
    stored = bounded[0].disturbance_bound(ACCELERATE)
    assert bounded[0].entry(ACCELERATE)["disturbance_bound"]["wake"] == wake_record(rig)
    library.add_disturbance_bound(ACCELERATE, stored, {"wake": wake_record(rig)})
    assert not library.needs_disturbance_bound(ACCELERATE)
    attached = dataclasses.asdict(dataclasses.replace(measuring_wake(rig), critical_leading_edge_suction=None))
    library.add_disturbance_bound(ACCELERATE, stored, {"wake": attached})
    assert library.needs_disturbance_bound(ACCELERATE)
    # the shipped library's bounds were measured in the default wake
    assert not any(circulatory_library.needs_disturbance_bound(i) for i in circulatory_library.ids())


def test_a_corrupt_or_malformed_bound_is_refused(bounded, rig, tmp_path):
    library = _copy(bounded[0], tmp_path / "lib", rig, IDS, "circulatory")
    samples = len(library.get(CRUISE).time_s)
    for bad in (np.zeros(samples - 1), np.full(samples, -1e-3), np.full(samples, np.nan)):
        with pytest.raises(LibraryError, match=f"must be {samples} finite values >= 0"):
            library.add_disturbance_bound(CRUISE, bad, {})
    assert library.disturbance_bound(CRUISE) is None
    library.add_disturbance_bound(CRUISE, np.full(samples, 0.01), {})
    file = library.path / "primitives" / library.entry(CRUISE)["disturbance_bound"]["file"]
    file.write_bytes(file.read_bytes()[:-3])
    with pytest.raises(LibraryError, match="corrupt or truncated"):
        PrimitiveLibrary.load(library.path, rig, "circulatory").disturbance_bound(CRUISE)


def test_a_format_3_library_reads_with_no_bound(bounded, rig, tmp_path):
    library = _copy(bounded[0], tmp_path / "lib", rig, IDS, "circulatory")
    manifest = json.loads((library.path / MANIFEST).read_text())
    manifest["format_version"] = 3
    (library.path / MANIFEST).write_text(json.dumps(manifest))
    old = PrimitiveLibrary.load(library.path, rig, "circulatory")
    assert [old.disturbance_bound(i) for i in IDS] == [None, None]
    assert all(old.needs_disturbance_bound(i) for i in IDS)
    assert concatenate(old, rig, expand_sequence(IDS, [1, 2])).disturbance_bound is None


def test_ideal_flow_libraries_get_no_bound(library, rig, tmp_path):
    ids = ["constrained/accelerate/E0.05", "constrained/cruise/E0.05"]
    ideal = _copy(library, tmp_path / "lib", rig, ids, "ideal")
    events = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=1) as executor:
        assert build_library(ideal, [library.spec(i) for i in ids], executor,
                             progress=lambda i, s: events.append((i, s))) == []
    assert sorted(events) == [(i, "cached") for i in sorted(ids)]
    assert not any(ideal.needs_disturbance_bound(i) for i in ids)
    assert [ideal.disturbance_bound(i) for i in ids] == [None, None]
    assert not list((tmp_path / "lib" / "primitives").glob("*.disturbance.npz"))
    with pytest.raises(LibraryError, match="stores no disturbance bound"):
        ideal.add_disturbance_bound(ids[0], np.zeros(len(ideal.get(ids[0]).time_s)), {})
    assert concatenate(ideal, rig, expand_sequence(ids, [1, 2])).disturbance_bound is None


def test_a_plan_joins_the_stored_bounds_and_scales_them(bounded, rig):
    library = bounded[0]
    plan = concatenate(library, rig, expand_sequence(IDS, [1, 2]), 1.2)
    accelerate, cruise = (library.disturbance_bound(i) for i in IDS)
    joined = np.concatenate([accelerate, cruise[1:], cruise[1:]])   # a junction sample is the earlier one's
    np.testing.assert_allclose(plan.disturbance_bound, 1.2 ** 2 * joined, rtol=1e-15)
    assert len(plan.disturbance_bound) == len(plan.time_s)


def test_the_bound_of_the_scaled_primitive_is_lambda_squared_times_the_nominal(bounded, rig, model_for):
    """Trajectory.time_scaled's D_l(t) = lambda^2 D(lambda t) against D measured directly along the primitive run
    lambda times faster (t / lambda, lambda qdot, lambda^2 u and tau, lambda z), with the wake stepped at the same
    points of the motion (max_wake_step_s / lambda)."""
    primitive = bounded[0].get(ACCELERATE)
    model = model_for(primitive.spec, "circulatory")
    nominal = flow_force_mismatch(model, primitive)
    lam = TIME_SCALE
    scaled = dataclasses.replace(primitive, spec=dataclasses.replace(primitive.spec,
                                                                     duration_s=primitive.spec.duration_s / lam),
                                 time_s=primitive.time_s / lam, qdot=lam * primitive.qdot,
                                 foil_acceleration=lam ** 2 * primitive.foil_acceleration,
                                 torque=lam ** 2 * primitive.torque, lag=lam * primitive.lag)
    direct = flow_force_mismatch(model, scaled, max_wake_step_s=MAX_WAKE_STEP_S / lam)
    np.testing.assert_allclose(direct.reduced_force, lam ** 2 * nominal.reduced_force, rtol=1e-9, atol=1e-10)
    plan = concatenate(bounded[0], rig, expand_sequence([ACCELERATE], []), 1.0)
    plan = dataclasses.replace(plan, disturbance_bound=nominal.disturbance_bound_n_m).time_scaled(lam,
                                                                                             rig.torque_limits_n_m)
    np.testing.assert_allclose(plan.time_s, direct.time_s, rtol=1e-14)
    peak = float(direct.disturbance_bound_n_m.max())
    assert np.max(np.abs(plan.disturbance_bound - direct.disturbance_bound_n_m)) <= SCALED_WAKE_AGREEMENT * peak
