"""The pointwise NLP (swim_planner.pointwise): its assembled derivatives against CasADi's own AD, its bounds,
and the same primitive from both derivative paths."""
import dataclasses

import casadi as ca
import numpy as np
import pytest

from swim_model import VehicleModel
from swim_planner import pointwise
from swim_planner.catalog import constrained_specs
from swim_planner.pointwise import PointwiseFunction, PointwiseNlp, Structure
from swim_planner.primitive_solver import primitive_nlp, solve_primitive
from swim_planner.primitives import SolverSettings


@pytest.fixture(scope="module")
def small_cruise(rig):
    """The default E = 0.05 cruise on a coarse grid (8 intervals), and its model."""
    spec = next(s for s in constrained_specs(rig) if s.primitive_id == "constrained/cruise/E0.05")
    spec = dataclasses.replace(spec, intervals=8)
    return VehicleModel(rig, constrained=True, lane_radius_m=spec.lane_radius_m), spec


def _casadi_derivatives(nlp: PointwiseNlp, keep: list[int]):
    """grad f, jac g and the Lagrangian's Hessian by CasADi's AD of the NLP written with the SX phi."""
    f, g = nlp.substitute(nlp.f, nlp.g, symbolic=True)
    g = g[keep]
    sigma, lam = ca.MX.sym("sigma"), ca.MX.sym("lam", len(keep))
    hessian = ca.hessian(sigma * f + ca.dot(lam, g), nlp.z)[0]
    return ca.Function("ad", [nlp.z, sigma, lam], [f, ca.gradient(f, nlp.z), g, ca.jacobian(g, nlp.z), hessian])


def test_assembled_derivatives_equal_casadis_own_ad(small_cruise):
    model, spec = small_cruise
    problem = primitive_nlp(model, spec)
    structure = Structure.of(problem.nlp)
    keep, _, _ = pointwise.simple_bounds(structure, problem.lbg, problem.ubg)
    reduced = dataclasses.replace(problem.nlp, g=problem.nlp.g[keep])
    assembled = pointwise.derivative_functions(reduced, structure.rows(keep))
    rng = np.random.default_rng(3)
    z = problem.z0 + 0.05 * rng.standard_normal(problem.z0.size)
    sigma, lam = 0.7, rng.standard_normal(len(keep))
    f, grad_f, g, jac_g, hessian = (np.asarray(ca.densify(v)) for v in
                                    _casadi_derivatives(problem.nlp, keep)(z, sigma, lam))
    f_a, grad_f_a = (np.asarray(ca.densify(v)) for v in assembled["grad_f"](z, []))
    g_a, jac_g_a = (np.asarray(ca.densify(v)) for v in assembled["jac_g"](z, []))
    hess_triu = np.asarray(ca.densify(assembled["hess_lag"](z, [], sigma, lam)))
    np.testing.assert_allclose(f_a, f, rtol=1e-12)
    np.testing.assert_allclose(grad_f_a, grad_f, rtol=1e-9, atol=1e-9 * np.abs(grad_f).max())
    np.testing.assert_allclose(g_a, g, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(jac_g_a, jac_g, rtol=1e-9, atol=1e-9 * np.abs(jac_g).max())
    assert np.count_nonzero(np.tril(hess_triu, -1)) == 0
    hess_full = hess_triu + np.triu(hess_triu, 1).T
    np.testing.assert_allclose(hess_full, hessian, rtol=1e-8, atol=1e-9 * np.abs(hessian).max())


def test_single_variable_rows_become_bounds_on_that_variable():
    z, phi = ca.MX.sym("z", 3), ca.MX.sym("phi", 1, 2)
    y, theta = ca.SX.sym("y"), ca.SX.sym("theta", 0)
    square = PointwiseFunction.compiled(y ** 2, y, theta, tag="test_square")
    # rows: 2 z0 + 1 in [-3, 5] -> z0 in [-2, 2]; -z0 <= 1 -> z0 >= -1; -z1 + 1 in [0, 4] -> z1 in [-3, 1];
    # z0 + z2 couples two variables; phi_0 (= z0^2) is nonlinear: both stay constraints
    g = ca.vertcat(2 * z[0] + 1, -z[0], -z[1] + 1, z[0] + z[2], phi[0])
    nlp = PointwiseNlp(z=z, f=ca.sumsqr(z) + phi[1], g=g, points=ca.horzcat(z[0], z[1]), phi_placeholder=phi,
                       pointwise=square, theta=np.zeros(0))
    keep, lbx, ubx = pointwise.simple_bounds(Structure.of(nlp), np.array([-3, -np.inf, 0, 0, 0.0]),
                                             np.array([5, 1, 4, 1, 1.0]))
    assert keep == [3, 4]
    np.testing.assert_allclose(lbx, [-1, -3, -np.inf])
    np.testing.assert_allclose(ubx, [2, 1, np.inf])


def test_rows_that_would_cross_a_bound_stay_constraints():
    """z0 = -1e-9 (a joined state, to rounding) and z0 >= 0: crossed bounds; the second row stays a row."""
    z, phi = ca.MX.sym("z", 1), ca.MX.sym("phi", 1, 1)
    y, theta = ca.SX.sym("y"), ca.SX.sym("theta", 0)
    nlp = PointwiseNlp(z=z, f=phi[0], g=ca.vertcat(z[0], z[0]), points=z[0], phi_placeholder=phi,
                       pointwise=PointwiseFunction.compiled(y ** 2, y, theta, tag="test_square"), theta=np.zeros(0))
    keep, lbx, ubx = pointwise.simple_bounds(Structure.of(nlp), np.array([-1e-9, 0.0]), np.array([-1e-9, np.inf]))
    assert keep == [1]
    np.testing.assert_allclose([lbx[0], ubx[0]], [-1e-9, -1e-9])


def test_a_constraint_nonlinear_outside_phi_is_refused():
    z, phi = ca.MX.sym("z", 2), ca.MX.sym("phi", 1, 1)
    y, theta = ca.SX.sym("y"), ca.SX.sym("theta", 0)
    nlp = PointwiseNlp(z=z, f=phi[0], g=z[0] * z[1], points=z[0], phi_placeholder=phi,
                       pointwise=PointwiseFunction.compiled(ca.sin(y), y, theta, tag="test_sine"), theta=np.zeros(0))
    with pytest.raises(ValueError, match="dg/dz is not constant"):
        Structure.of(nlp)


def test_a_small_nlp_solves_to_its_closed_form():
    """min (z0 - 2)^2 + phi, phi = z1^2, s.t. z0 + z1 = 1: stationarity gives z0 - 2 = z1, so z = (1.5, -0.5);
    with the row z0 <= 1.2 (made a bound) that bound is active: z = (1.2, -0.2)."""
    z, phi = ca.MX.sym("z", 2), ca.MX.sym("phi", 1, 1)
    y, theta = ca.SX.sym("y"), ca.SX.sym("theta", 0)
    nlp = PointwiseNlp(z=z, f=(z[0] - 2) ** 2 + phi[0], g=ca.vertcat(z[0] + z[1], z[0]), points=z[1],
                       phi_placeholder=phi, pointwise=PointwiseFunction.compiled(y ** 2, y, theta, tag="test_square"),
                       theta=np.zeros(0))
    result = pointwise.solve(nlp, np.zeros(2), np.array([1.0, -np.inf]), np.array([1.0, 1.2]),
                             {"print_level": 0, "sb": "yes", "tol": 1e-10})
    assert result.status == "Solve_Succeeded"
    np.testing.assert_allclose(result.z, [1.2, -0.2], atol=1e-7)


def test_both_derivative_paths_reach_the_same_cruise(rig, small_cruise):
    model, spec = small_cruise
    spec = dataclasses.replace(spec, intervals=20)
    assembled = solve_primitive(model, spec)
    by_casadi = solve_primitive(model, spec, settings=SolverSettings(derivatives="casadi"))
    assert abs(assembled.index_j - by_casadi.index_j) < 1e-6
    np.testing.assert_allclose(assembled.q, by_casadi.q, atol=1e-5)
    np.testing.assert_allclose(assembled.torque, by_casadi.torque, atol=1e-4)


def test_unknown_derivatives_are_refused():
    with pytest.raises(ValueError, match="derivatives"):
        SolverSettings(derivatives="finite differences")


def test_a_start_state_with_nan_is_refused_with_a_clear_message(rig, small_cruise):
    model, cruise_spec = small_cruise
    spec = next(s for s in constrained_specs(rig) if s.primitive_type.value == "decelerate")
    spec = dataclasses.replace(spec, intervals=8)
    start = (np.zeros(model.nq), np.array([np.nan] + [0.0] * (model.nq - 1)))
    with pytest.raises(ValueError, match="start state must be .* finite"):
        solve_primitive(model, spec, start=start)
    with pytest.raises(ValueError, match="end state"):
        solve_primitive(model, dataclasses.replace(cruise_spec, primitive_type=spec.primitive_type.ACCELERATE),
                        end=(np.zeros(model.nq), np.zeros(model.nq + 1)))
