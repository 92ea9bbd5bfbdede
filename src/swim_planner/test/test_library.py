"""The library on disk: round trip, and every way a library can be bad."""
import dataclasses
import json
import shutil

import numpy as np
import pytest

from swim_planner.errors import LibraryError
from swim_planner.library import FORMAT_VERSION, MANIFEST, PrimitiveLibrary

SOME = ["constrained/cruise/E0.05", "constrained/accelerate/E0.05"]


@pytest.fixture()
def copy(library, rig, tmp_path):
    """A new library holding two primitives of the shipped one."""
    new = PrimitiveLibrary.create_or_open(tmp_path / "lib", rig)
    for primitive_id in SOME:
        new.add(library.get(primitive_id))
    return tmp_path / "lib"


def test_round_trip(library, rig, copy):
    loaded = PrimitiveLibrary.load(copy, rig)
    assert loaded.ids() == sorted(SOME)
    for primitive_id in SOME:
        original, read = library.get(primitive_id), loaded.get(primitive_id)
        np.testing.assert_array_equal(read.q, original.q)
        np.testing.assert_array_equal(read.torque, original.torque)
        assert read.spec == original.spec and read.index_j == original.index_j
        np.testing.assert_array_equal(read.gains.riccati, original.gains.riccati)
        np.testing.assert_array_equal(read.gains.riccati_input_gain, original.gains.riccati_input_gain)
    manifest = json.loads((copy / MANIFEST).read_text())
    assert manifest["rig_digest"] == rig.digest() and manifest["format_version"] == FORMAT_VERSION
    assert manifest["lqr_weights"] == dataclasses.asdict(library.lqr_weights)


def test_solver_settings_round_trip_and_older_manifests_say_casadi(library, rig, copy):
    """A manifest records how its primitives were solved; one without ``derivatives`` (the shipped library's)
    was solved by CasADi's own AD, and loads saying so."""
    assert "derivatives" not in json.loads((library.path / MANIFEST).read_text())["solver"]
    assert library.solver.derivatives == "casadi"
    assert PrimitiveLibrary.load(copy, rig).solver.derivatives == "pointwise"


def _edit_manifest(path, change):
    manifest = json.loads((path / MANIFEST).read_text())
    change(manifest)
    (path / MANIFEST).write_text(json.dumps(manifest))


def test_other_rig_is_refused(rig, copy):
    with pytest.raises(LibraryError, match="other rig parameters"):
        PrimitiveLibrary.load(copy, rig.replace(platform_mass_kg=rig.platform_mass_kg + 0.1))


@pytest.mark.parametrize("change, message", [
    (lambda m: m.__setitem__("format_version", 99), "library format 99"),
    (lambda m: m.__setitem__("model_version", "0"), "swim_model version"),
    (lambda m: m.__setitem__("primitives", []), "must be a mapping"),
    (lambda m: m["solver"].__setitem__("derivatives", "symbolic"), "derivatives must be"),
])
def test_bad_manifest_is_refused(rig, copy, change, message):
    _edit_manifest(copy, change)
    with pytest.raises(LibraryError, match=message):
        PrimitiveLibrary.load(copy, rig)


def test_truncated_array_file_is_refused(rig, copy):
    target = next((copy / "primitives").iterdir())
    target.write_bytes(target.read_bytes()[:200])
    loaded = PrimitiveLibrary.load(copy, rig)
    with pytest.raises(LibraryError, match="corrupt or truncated"):
        for primitive_id in loaded.ids():
            loaded.get(primitive_id)


def test_missing_library_and_garbage_manifest(rig, tmp_path):
    with pytest.raises(LibraryError, match="no primitive library"):
        PrimitiveLibrary.load(tmp_path / "absent", rig)
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / MANIFEST).write_text("{not json")
    with pytest.raises(LibraryError, match="not JSON"):
        PrimitiveLibrary.load(tmp_path / "bad", rig)


def test_unknown_primitive(rig, copy):
    with pytest.raises(LibraryError, match="no primitive 'nope'"):
        PrimitiveLibrary.load(copy, rig).get("nope")


def test_missing_array_file(rig, copy):
    shutil.rmtree(copy / "primitives")
    with pytest.raises(LibraryError, match="cannot read"):
        PrimitiveLibrary.load(copy, rig).get(SOME[0])


def _with_lag(primitive):
    """A primitive carrying lag states, as one of the circulatory flow model would (values: a known pattern)."""
    lag = np.column_stack([np.linspace(0.0, 0.1, len(primitive.time_s)), np.linspace(0.2, -0.1, len(primitive.time_s))])
    return dataclasses.replace(primitive, lag=lag)


def test_a_library_records_its_flow_model_and_keeps_the_lag_states(library, rig, tmp_path):
    new = PrimitiveLibrary.create_or_open(tmp_path / "lib", rig, flow_model="circulatory")
    stored = [_with_lag(library.get(primitive_id)) for primitive_id in SOME]
    for primitive in stored:
        new.add(primitive)
    assert json.loads((tmp_path / "lib" / MANIFEST).read_text())["flow_model"] == "circulatory"
    loaded = PrimitiveLibrary.load(tmp_path / "lib", rig, "circulatory")
    assert loaded.flow_model == "circulatory"
    for primitive in stored:
        np.testing.assert_array_equal(loaded.get(primitive.spec.primitive_id).lag, primitive.lag)
    assert PrimitiveLibrary.load(tmp_path / "lib", rig, None).flow_model == "circulatory"


def test_a_library_of_another_flow_model_is_refused(library, rig, tmp_path, copy):
    with pytest.raises(LibraryError, match="ideal flow model, not the circulatory one"):
        PrimitiveLibrary.load(copy, rig, "circulatory")
    with pytest.raises(LibraryError, match="ideal flow model, not the circulatory one"):
        PrimitiveLibrary.create_or_open(copy, rig, flow_model="circulatory")
    with pytest.raises(LibraryError, match="unknown flow model 'viscous'"):
        PrimitiveLibrary.load(copy, rig, "viscous")
    _edit_manifest(copy, lambda m: m.__setitem__("flow_model", "viscous"))
    with pytest.raises(LibraryError, match="unknown flow model 'viscous'"):
        PrimitiveLibrary.load(copy, rig, None)


def test_primitives_of_the_other_flow_model_are_not_added(library, rig, tmp_path):
    ideal = PrimitiveLibrary.create_or_open(tmp_path / "ideal", rig)
    circulatory = PrimitiveLibrary.create_or_open(tmp_path / "circulatory", rig, flow_model="circulatory")
    primitive = library.get(SOME[0])
    with pytest.raises(LibraryError, match="has lag states"):
        ideal.add(_with_lag(primitive))
    with pytest.raises(LibraryError, match="has no lag states"):
        circulatory.add(primitive)
    assert len(ideal) == len(circulatory) == 0


def test_the_shipped_format_2_library_is_the_ideal_flow_models(library, rig):
    manifest = json.loads((library.path / MANIFEST).read_text())
    assert manifest["format_version"] == 2 and "flow_model" not in manifest
    assert library.flow_model == "ideal"
    with pytest.raises(LibraryError, match="not the circulatory one"):
        PrimitiveLibrary.load(library.path, rig, "circulatory")


def test_a_cruise_records_its_mean_speed(library, rig, copy):
    """The manifest's speed is the cruise's alpha advance over its duration times its lane radius."""
    cruise = library.get(SOME[0])
    entry = PrimitiveLibrary.load(copy, rig).entry(SOME[0])
    duration_s = cruise.time_s[-1] - cruise.time_s[0]
    assert entry["mean_speed_m_s"] == pytest.approx(
        (cruise.q[-1, 0] - cruise.q[0, 0]) / duration_s * cruise.spec.lane_radius_m, rel=1e-12)
    assert "mean_speed_m_s" not in PrimitiveLibrary.load(copy, rig).entry(SOME[1])
