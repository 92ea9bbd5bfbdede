"""Gains for other LQ weights: the stored ones reproduce, a common scale of Q, R, S leaves the law unchanged."""
import dataclasses

import numpy as np
import pytest

from swim_control.riccati import LqrWeights
from swim_planner.errors import PlannerError
from swim_planner.gains import RetunedLibrary, load_lqr_weights
from swim_planner.maneuver import concatenate, expand_sequence

PRIMITIVE = "constrained/cruise_to_cruise/E0.05-E0.10"
SEQUENCE = ["constrained/cruise/E0.05", PRIMITIVE, "constrained/cruise/E0.10"]


def test_same_weights_reproduce_the_stored_gains(library):
    """Every primitive's P and G'P for the library's weights equal those stored with it (computed by the library
    build, the shipped library's by integrating eq. 20 with DOP853 at rtol 1e-10), cruises with their lookahead."""
    retuned = RetunedLibrary(library, library.lqr_weights)
    for primitive_id in library.ids():
        stored, recomputed = library.get(primitive_id).gains, retuned.get(primitive_id).gains
        for name in ("riccati", "riccati_input_gain"):
            expected, actual = getattr(stored, name), getattr(recomputed, name)
            relative = np.abs(actual - expected).max() / np.abs(expected).max()
            assert relative < 1e-5, f"{primitive_id} {name}: {relative:.1e}"


def test_a_common_scale_of_q_r_s_scales_p_and_keeps_the_feedback(library, rig):
    """Q, R -> cQ, cR makes P_ARE -> c P_ARE, so S -> cS and P(t) -> c P(t); K = R^-1 G'P is unchanged."""
    base = library.lqr_weights
    factor = 7.0
    scaled = dataclasses.replace(base, **{name: getattr(base, name) * factor for name in (
        "alpha_gain", "lateral_gain", "heave_gain", "pitch_gain", "heave_input_weight", "pitch_input_weight")})
    retuned = RetunedLibrary(library, scaled)
    stored, other = library.get(PRIMITIVE).gains, retuned.get(PRIMITIVE).gains
    assert np.allclose(other.riccati, factor * stored.riccati, rtol=1e-5, atol=1e-9 * factor)
    sequence = expand_sequence(SEQUENCE, [])
    plan, retuned_plan = concatenate(library, rig, sequence, 1.2), concatenate(retuned, rig, sequence, 1.2)
    scale = np.abs(plan.lqr_gain).max()
    assert np.abs(retuned_plan.lqr_gain - plan.lqr_gain).max() < 1e-5 * scale
    assert retuned_plan.library_digest != plan.library_digest


def test_other_input_weights_change_the_plan_gains(library, rig):
    heavier = dataclasses.replace(library.lqr_weights, heave_input_weight=4 * library.lqr_weights.heave_input_weight)
    sequence = expand_sequence(SEQUENCE, [])
    plan = concatenate(library, rig, sequence)
    retuned = concatenate(RetunedLibrary(library, heavier), rig, sequence)
    # a costlier heave input: smaller heave feedback, on average over the plan
    heave = np.abs(plan.lqr_gain[:, 0]).mean()
    assert np.abs(retuned.lqr_gain[:, 0]).mean() < 0.8 * heave


def test_weights_file(tmp_path):
    path = tmp_path / "weights.yaml"
    path.write_text("alpha_rate_per_s: 2.0\nheave_input_weight: 0.05\n")
    weights = load_lqr_weights(path)
    assert weights == dataclasses.replace(LqrWeights(), alpha_rate_per_s=2.0, heave_input_weight=0.05)


@pytest.mark.parametrize("text, message", [
    ("alpha_rate: 2.0\n", "unknown fields"),
    ("alpha_rate_per_s: -1.0\n", "positive finite"),
    ("alpha_rate_per_s: [1, 2]\n", "not a valid"),
    ("- 1\n- 2\n", "not a valid"),
])
def test_bad_weights_files_are_refused(tmp_path, text, message):
    path = tmp_path / "weights.yaml"
    path.write_text(text)
    with pytest.raises(PlannerError, match=message):
        load_lqr_weights(path)
    with pytest.raises(PlannerError, match="not a valid"):
        load_lqr_weights(tmp_path / "missing.yaml")


def test_one_primitives_gains_being_computed_holds_up_only_those_asking_for_it(library, monkeypatch):
    """While one primitive's gains are computed, another's are served; a second asker of the first waits for
    the same computation instead of starting another."""
    import threading

    import swim_planner.gains as gains_module
    release, computing, jobs = threading.Event(), threading.Event(), []
    real_job = gains_module.gains_job

    def slow_job(rig, primitive, weights):
        jobs.append(primitive.spec.primitive_id)
        if primitive.spec.primitive_id == PRIMITIVE:
            computing.set()
            assert release.wait(30.0)
        return real_job(rig, primitive, weights)
    monkeypatch.setattr(gains_module, "gains_job", slow_job)
    retuned = RetunedLibrary(library, dataclasses.replace(library.lqr_weights, heave_input_weight=0.05))
    results = {}
    threads = [threading.Thread(target=lambda key=key: results.__setitem__(key, retuned.get(PRIMITIVE)))
               for key in ("first", "second")]
    threads[0].start()
    assert computing.wait(30.0)
    threads[1].start()
    other = retuned.get("constrained/cruise/E0.05")        # answered while PRIMITIVE's gains are held up
    assert other.gains is not None and not results
    release.set()
    for thread in threads:
        thread.join(30.0)
    assert results["first"] is results["second"] and jobs.count(PRIMITIVE) == 1


def test_stored_riccati_input_gain_is_g_transpose_p(library, rig):
    from swim_control.riccati import linearize
    from swim_model import VehicleModel
    primitive = library.get("free/cruise_to_cruise/R0.43/E0.05-E0.10")
    model = VehicleModel(rig, constrained=False, lane_radius_m=primitive.spec.lane_radius_m)
    lin = linearize(model, primitive.q, primitive.qdot, primitive.foil_acceleration)
    expected = np.einsum("kni,knm->kim", lin.input_matrix, primitive.gains.riccati)
    np.testing.assert_allclose(primitive.gains.riccati_input_gain, expected, rtol=1e-12,
                               atol=1e-12 * np.abs(expected).max())


def test_stored_gains_of_weights_without_a_later_field_are_those_of_its_default(library):
    """A record of gains computed before a weight field existed is read with that field at its default (the gains
    were computed as with it): the shipped ideal library needs no gains; another value of the field asks for them."""
    assert not any(library.needs_gains(primitive_id) for primitive_id in library.ids())
    record = dict(library.entry(library.ids()[0]))
    stored = dict(record["gains_lqr_weights"])
    stored.pop("rest_lateral_terminal_weight", None)
    stored.pop("rest_alpha_terminal_weight", None)
    assert LqrWeights(**stored) == LqrWeights() == library.lqr_weights
    other = dataclasses.replace(library.lqr_weights, rest_lateral_terminal_weight=1.0)
    library.lqr_weights, kept = other, library.lqr_weights
    try:
        assert all(library.needs_gains(primitive_id) for primitive_id in library.ids())
    finally:
        library.lqr_weights = kept


def test_the_circulatory_library_weights_its_decelerates_task_at_rest(circulatory_library, rig):
    """The circulatory library's gains are for its catalog weights; a decelerate's P at its end has the rest weight
    beyond the gains without the rest weights, on e_R for a free one and on e_alpha for a constrained one; a
    cruise's does not."""
    from swim_control.riccati import HUB_ERROR_INDEX_CONSTRAINED, LATERAL_ERROR_INDEX
    from swim_planner.catalog import CIRCULATORY_LQR_WEIGHTS
    assert circulatory_library.lqr_weights == CIRCULATORY_LQR_WEIGHTS
    assert CIRCULATORY_LQR_WEIGHTS.rest_lateral_terminal_weight > 0.0
    assert CIRCULATORY_LQR_WEIGHTS.rest_alpha_terminal_weight > 0.0
    assert not any(circulatory_library.needs_gains(primitive_id) for primitive_id in circulatory_library.ids())
    without = RetunedLibrary(circulatory_library, dataclasses.replace(
        CIRCULATORY_LQR_WEIGHTS, rest_lateral_terminal_weight=0.0, rest_alpha_terminal_weight=0.0))
    rest = {"free/decelerate/R0.43/E0.05": (LATERAL_ERROR_INDEX,
                                            CIRCULATORY_LQR_WEIGHTS.rest_lateral_terminal_weight),
            "constrained/decelerate/E0.10": (HUB_ERROR_INDEX_CONSTRAINED,
                                             CIRCULATORY_LQR_WEIGHTS.rest_alpha_terminal_weight),
            "free/cruise/R0.43/E0.05": None, "constrained/cruise/E0.10": None}
    tolerance = 1e-6 * max(CIRCULATORY_LQR_WEIGHTS.rest_lateral_terminal_weight,
                           CIRCULATORY_LQR_WEIGHTS.rest_alpha_terminal_weight)
    for primitive_id, weighted in rest.items():
        stored = circulatory_library.get(primitive_id).gains.riccati[-1]
        plain = without.get(primitive_id).gains.riccati[-1]
        added = stored - plain
        expected = np.zeros_like(added)
        if weighted is not None:
            index, weight = weighted
            expected[index, index] = weight
        np.testing.assert_allclose(added, expected, atol=tolerance)


def test_a_weights_file_leaves_the_fields_it_does_not_name_at_the_base(tmp_path):
    """The planner reads a weights file over its library's weights: the circulatory library's rest weight stays
    unless the file names it."""
    from swim_planner.catalog import CIRCULATORY_LQR_WEIGHTS
    path = tmp_path / "weights.yaml"
    path.write_text("heave_input_weight: 0.04\n")
    weights = load_lqr_weights(path, CIRCULATORY_LQR_WEIGHTS)
    assert weights == dataclasses.replace(CIRCULATORY_LQR_WEIGHTS, heave_input_weight=0.04)
    assert load_lqr_weights(path) == LqrWeights(heave_input_weight=0.04)
