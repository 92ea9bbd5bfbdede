"""Gains and plans of primitives solved with the circulatory flow model: the LQ stage on the extended error state
(int e_y, e_q, edot_q, e_z) stabilizes the cruise, and concatenation and time scaling carry the lag states.

The constrained E = 0.05 cruise is solved here with the catalog's spec (a few seconds), not read from a library;
the plans are concatenated from an in-memory library of it (the PlanLibrary protocol of swim_planner.maneuver).
"""
import dataclasses
import hashlib
from pathlib import Path

import numpy as np
import pytest

from swim_control.riccati import LqrWeights, error_state_size, linearize, primitive_gains
from swim_control.time_scaling import scaling_diagonal
from swim_model import VehicleModel
from swim_planner.catalog import constrained_specs
from swim_planner.errors import ManeuverError, PlannerError
from swim_planner.gains import RetunedLibrary, gains_job
from swim_planner.maneuver import concatenate, expand_sequence, vary_time_scale
from swim_planner.primitive_solver import solve_primitive
from swim_planner.primitives import PlanningLimits, Primitive, PrimitiveSpec

CRUISE = "constrained/cruise/E0.05"
N_LAG = 2


class MemoryLibrary:
    """Primitives held in memory, answering what concatenation and RetunedLibrary read of a library."""

    def __init__(self, rig, primitives: list[Primitive], lqr_weights: LqrWeights) -> None:
        self.rig, self.lqr_weights, self.path = rig, lqr_weights, Path("memory")
        self._primitives = {p.spec.primitive_id: p for p in primitives}

    def ids(self) -> list[str]:
        return sorted(self._primitives)

    def __contains__(self, primitive_id: str) -> bool:
        return primitive_id in self._primitives

    def spec(self, primitive_id: str) -> PrimitiveSpec:
        return self._primitives[primitive_id].spec

    def get(self, primitive_id: str) -> Primitive:
        return self._primitives[primitive_id]

    def sample_count(self, primitive_id: str) -> int:
        return len(self._primitives[primitive_id].time_s)

    def digest(self) -> str:
        return hashlib.sha256(" ".join(self.ids()).encode()).hexdigest()


@pytest.fixture(scope="module")
def circulatory_cruise(rig):
    spec = next(s for s in constrained_specs(rig) if s.primitive_id == CRUISE)
    model = VehicleModel(rig, constrained=True, lane_radius_m=spec.lane_radius_m, flow="circulatory")
    solved = solve_primitive(model, spec, PlanningLimits.of(model.rig))
    return model, gains_job(rig, solved, LqrWeights())


def _one_cycle(primitive: Primitive) -> slice:
    return slice(0, 2 * primitive.spec.intervals + 1)


def test_gains_job_uses_the_circulatory_model_for_a_primitive_with_lag(circulatory_cruise):
    model, cruise = circulatory_cruise
    n = error_state_size(model.nq, model.n_unactuated, N_LAG)
    assert cruise.gains is not None and cruise.gains.riccati.shape == (len(cruise.time_s), n, n)
    direct = primitive_gains(model, cruise.time_s, cruise.q, cruise.qdot, cruise.foil_acceleration, LqrWeights(),
                             2 * cruise.spec.intervals + 1, cruise.lag)
    np.testing.assert_array_equal(cruise.gains.riccati, direct.riccati)


def _closed_loop_monodromy(model, cruise, feedback=True):
    """The transition over the cruise's first cycle of xdot = (F - G R^-1 G'P) x (of xdot = F x without feedback),
    F, G, P linear between samples, by RK4 with 8 steps per sample interval."""
    cycle = _one_cycle(cruise)
    time_s = cruise.time_s[cycle]
    lin = linearize(model, cruise.q[cycle], cruise.qdot[cycle], cruise.foil_acceleration[cycle], cruise.lag[cycle])
    input_inverse = np.linalg.inv(LqrWeights().input_weight_matrix())
    closed = lin.state_matrix.copy()
    if feedback:
        closed -= np.einsum("kia,ab,kbj->kij", lin.input_matrix, input_inverse,
                            cruise.gains.riccati_input_gain[cycle])
    n = closed.shape[1]
    transition = np.eye(n)
    steps = 8
    for k in range(len(time_s) - 1):
        h = (time_s[k + 1] - time_s[k]) / steps

        def a(w, k=k):
            return closed[k] + w * (closed[k + 1] - closed[k])
        for j in range(steps):
            w0 = j / steps
            k1 = a(w0) @ transition
            k2 = a(w0 + 0.5 / steps) @ (transition + 0.5 * h * k1)
            k3 = a(w0 + 0.5 / steps) @ (transition + 0.5 * h * k2)
            k4 = a(w0 + 1.0 / steps) @ (transition + h * k3)
            transition = transition + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    return transition


def test_the_gains_stabilize_the_linearized_cruise(circulatory_cruise):
    """Floquet multipliers of the closed loop over one cycle (the cruise is periodic: F, G, P repeat) are inside
    the unit circle; without feedback they are not (the integral of e_alpha and e_alpha itself drift)."""
    model, cruise = circulatory_cruise
    cycle = _one_cycle(cruise)
    np.testing.assert_allclose(cruise.lag[cycle][-1], cruise.lag[0], atol=1e-6)   # periodic lag states
    closed = np.abs(np.linalg.eigvals(_closed_loop_monodromy(model, cruise)))
    open_loop = np.abs(np.linalg.eigvals(_closed_loop_monodromy(model, cruise, feedback=False)))
    assert closed.max() < 0.9, closed
    assert open_loop.max() > 0.999, open_loop


@pytest.fixture(scope="module")
def memory_library(rig, circulatory_cruise):
    return MemoryLibrary(rig, [circulatory_cruise[1]], LqrWeights())


def test_concatenation_carries_the_lag_states(memory_library, rig, circulatory_cruise):
    _, cruise = circulatory_cruise
    plan = concatenate(memory_library, rig, expand_sequence([CRUISE], [2]))
    samples = len(cruise.time_s)
    assert plan.flow_model == "circulatory" and plan.n_lag == N_LAG
    assert plan.lag.shape == (2 * samples - 1, N_LAG)
    np.testing.assert_array_equal(plan.lag[:samples], cruise.lag)
    np.testing.assert_array_equal(plan.lag[samples:], cruise.lag[1:])
    n = error_state_size(3, 1, N_LAG)
    assert plan.lqr_gain.shape == (2 * samples - 1, 2, n)
    np.testing.assert_array_equal(plan.riccati_input_gain[:samples], cruise.gains.riccati_input_gain)


@pytest.mark.parametrize("time_scale", [0.8, 1.2])
def test_a_time_scaled_circulatory_plan(memory_library, rig, time_scale):
    """lambda z, and the gains by Theorem 1 with Gamma's lag block I (swim_control.time_scaling)."""
    sequence = expand_sequence([CRUISE], [2])
    nominal, scaled = concatenate(memory_library, rig, sequence), concatenate(memory_library, rig, sequence,
                                                                             time_scale)
    np.testing.assert_allclose(scaled.lag, time_scale * nominal.lag, rtol=1e-15)
    gamma = scaling_diagonal(time_scale, 1, 3, N_LAG)
    np.testing.assert_allclose(scaled.riccati_input_gain, nominal.riccati_input_gain * gamma, rtol=1e-14)
    varied = vary_time_scale(nominal, lambda s: 1.0 + 0.1 * s / nominal.duration_s, rig)
    scale = 1.0 + 0.1 * nominal.time_s / nominal.duration_s
    np.testing.assert_allclose(varied.lag, nominal.lag * scale[:, None], rtol=1e-14)


def test_a_plan_cannot_mix_flow_models(rig, library, circulatory_cruise):
    _, cruise = circulatory_cruise
    ideal = library.get(CRUISE)
    renamed = dataclasses.replace(cruise, spec=dataclasses.replace(cruise.spec, primitive_id="circulatory/cruise"))
    mixed = MemoryLibrary(rig, [ideal, renamed], library.lqr_weights)
    with pytest.raises(ManeuverError, match="cannot mix primitives of the ideal and the circulatory flow models"):
        concatenate(mixed, rig, expand_sequence([CRUISE, "circulatory/cruise"], [1, 1]))
    assert issubclass(ManeuverError, PlannerError)


def test_a_retuned_circulatory_library_recomputes_the_extended_gains(memory_library, circulatory_cruise):
    """RetunedLibrary's gains for other weights are on the extended state; for the same weights, the same."""
    _, cruise = circulatory_cruise
    same = RetunedLibrary(memory_library, LqrWeights()).get(CRUISE)
    np.testing.assert_array_equal(same.gains.riccati, cruise.gains.riccati)
    heavier = dataclasses.replace(LqrWeights(), heave_input_weight=4 * LqrWeights().heave_input_weight)
    retuned = RetunedLibrary(memory_library, heavier).get(CRUISE)
    assert retuned.gains.riccati.shape == cruise.gains.riccati.shape
    # a costlier heave input: smaller heave feedback K = R^-1 G'P, on average over the cruise
    heave_feedback = np.abs(cruise.gains.riccati_input_gain[:, 0]).mean() / LqrWeights().heave_input_weight
    retuned_feedback = np.abs(retuned.gains.riccati_input_gain[:, 0]).mean() / heavier.heave_input_weight
    assert retuned_feedback < 0.8 * heave_feedback
