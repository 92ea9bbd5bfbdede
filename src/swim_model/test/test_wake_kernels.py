"""The wake's compiled kernels (swim_model.vortex_force, swim_model.wake) against the closed forms of
vortex_force's docstring evaluated directly with numpy on dense N x N arrays, and the wake coupling's compiled
foil kinematics against the vehicle model's own functions.

The kernels sum in another order than numpy does, so they agree to round-off (relative 1e-12), not bit for bit.
"""
import math

import numpy as np
import pytest

from swim_model import JoukowskiFoil, VehicleModel, load_rig
from swim_model.vortex_force import CirclePlane
from swim_model.wake import _merge_pair
from swim_model.wake_coupling import WakeCoupling

CHORD_M = 0.06
THICKNESS_M = 0.008
SPAN_M = 0.2
CORE_RADIUS_M = 1.5e-3
VORTEX_COUNT = 120     # enough for several SIMD blocks and a remainder
ROUND_OFF = 1e-12      # relative agreement of two summation orders over VORTEX_COUNT terms


@pytest.fixture(scope="module")
def plane() -> CirclePlane:
    return CirclePlane(JoukowskiFoil(CHORD_M, THICKNESS_M, SPAN_M).map)


def scattered_vortices(plane: CirclePlane, count: int, seed: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """count vortices outside the circle (1.02 r to 4 r from its centre), strengths of both signs, m^2/s."""
    rng = np.random.default_rng(seed)
    radius = plane.r_m * rng.uniform(1.02, 4.0, count)
    zeta = radius * np.exp(1j * rng.uniform(0.0, 2.0 * math.pi, count))
    return zeta, rng.normal(0.0, 1e-3, count)


def dense_velocities(plane: CirclePlane, zeta: np.ndarray, gamma: np.ndarray,
                     velocity: tuple[float, float, float], core_radius_m=CORE_RADIUS_M) -> np.ndarray:
    """u + iv at each vortex from the module docstring's formulas, as N x N numpy arrays; core_radius_m: one for
    all, or the source vortex's own (N,)."""
    s = zeta + plane.zeta_c_m
    d1, d2 = 1.0 - plane.a_m ** 2 / s ** 2, 2.0 * plane.a_m ** 2 / s ** 3
    core2 = (core_radius_m / np.abs(d1)) ** 2
    difference = zeta[:, None] - zeta[None, :]
    blob = np.conj(difference) / (np.abs(difference) ** 2 + core2[None, :])
    images = plane.r_m ** 2 / np.conj(zeta)
    dw = ((blob - 1.0 / (zeta[:, None] - images[None, :])) * gamma[None, :]).sum(axis=1) / (2j * math.pi)
    u_b, omega = complex(velocity[0], velocity[1]), velocity[2]
    body = (u_b * plane.r_m ** 2 / zeta ** 2 - np.conj(u_b) * plane.a_m ** 2 / s ** 2
            + 1j * omega * (plane.rotation_pole_origin_m3 / zeta ** 2 + plane.rotation_pole_offset_m3 / s ** 2))
    return np.conj((dw + body) / d1 - gamma * d2 / (4j * math.pi * d1 ** 2))


def relative_error(value: np.ndarray, reference: np.ndarray) -> float:
    return float(np.max(np.abs(value - reference)) / np.max(np.abs(reference)))


@pytest.mark.parametrize("count", [1, 2, 7, VORTEX_COUNT])
def test_vortex_velocities_are_the_dense_sums(plane, count):
    zeta, gamma = scattered_vortices(plane, count)
    velocity = (0.12, -0.03, 0.8)
    assert relative_error(plane.vortex_velocities(zeta, gamma, velocity, CORE_RADIUS_M),
                          dense_velocities(plane, zeta, gamma, velocity)) < ROUND_OFF


def test_each_vortex_desingularizes_with_its_own_core(plane):
    zeta, gamma = scattered_vortices(plane, VORTEX_COUNT)
    cores = np.random.default_rng(5).uniform(1.0e-3, 9.0e-3, VORTEX_COUNT)
    velocity = (0.12, -0.03, 0.8)
    own = plane.vortex_velocities(zeta, gamma, velocity, cores)
    assert relative_error(own, dense_velocities(plane, zeta, gamma, velocity, cores)) < ROUND_OFF
    # and not the common core's: the cores matter at these separations
    assert relative_error(own, dense_velocities(plane, zeta, gamma, velocity)) > 1e3 * ROUND_OFF


def test_a_lone_vortex_moves_only_with_its_image_the_body_and_the_routh_term(plane):
    # one vortex: the blob sum is its own term, which must vanish (D = 0)
    zeta, gamma = scattered_vortices(plane, 1)
    at_rest = plane.vortex_velocities(zeta, gamma, (0.0, 0.0, 0.0), CORE_RADIUS_M)
    s = zeta + plane.zeta_c_m
    d1, d2 = 1.0 - plane.a_m ** 2 / s ** 2, 2.0 * plane.a_m ** 2 / s ** 3
    image_term = -gamma / (zeta - plane.r_m ** 2 / np.conj(zeta)) / (2j * math.pi)
    expected = np.conj(image_term / d1 - gamma * d2 / (4j * math.pi * d1 ** 2))
    assert at_rest == pytest.approx(expected, rel=ROUND_OFF)


def test_vortex_potential_derivative_is_the_dense_sum(plane):
    zeta_k, gamma = scattered_vortices(plane, VORTEX_COUNT)
    points = 5.0 * plane.r_m * np.exp(2j * math.pi * np.arange(16) / 16)
    images = plane.r_m ** 2 / np.conj(zeta_k)
    dense = ((1.0 / (points[:, None] - zeta_k[None, :]) - 1.0 / (points[:, None] - images[None, :]))
             * gamma[None, :]).sum(axis=1) / (2j * math.pi)
    assert relative_error(plane.vortex_potential_derivative(points, zeta_k, gamma), dense) < ROUND_OFF


def test_to_circle_inverts_the_map_onto_the_outside_of_the_circle(plane):
    zeta, _ = scattered_vortices(plane, VORTEX_COUNT)
    z = plane.to_foil(zeta)
    back = plane.to_circle(z)
    assert np.max(np.abs(back - zeta)) < 1e-12 * plane.r_m * 10
    assert np.all(np.abs(back) >= plane.r_m)
    assert plane.to_circle(z[:3].reshape(3, 1)).shape == (3, 1)


def test_impulse_terms_are_the_closed_forms(plane):
    zeta, gamma = scattered_vortices(plane, VORTEX_COUNT)
    images = plane.r_m ** 2 / np.conj(zeta)
    z_k = plane.to_foil(zeta)
    zc = plane.zeta_c_m
    sheet = (-plane.to_foil(images) * np.conj(z_k)
             + plane.rotation_pole_origin_m3 * (1.0 / images - 1.0 / zeta)
             + plane.rotation_pole_offset_m3 * (1.0 / (images + zc) - 1.0 / (zeta + zc)))
    impulse, angular = plane.impulse_terms(zeta, gamma)
    assert relative_error(impulse, gamma * (zeta - images)) < ROUND_OFF
    assert relative_error(angular, gamma * (np.abs(z_k) ** 2 + sheet.real)) < ROUND_OFF


def test_merge_pair_is_the_least_cost_pair():
    rng = np.random.default_rng(7)
    positions = rng.normal(0.0, 0.3, 200) + 1j * rng.normal(0.0, 0.3, 200)
    gamma = rng.normal(0.0, 1e-3, 200)
    origin, candidates, penalty = complex(0.1, -0.2), 150, 10.0
    separation = np.abs(positions[1:candidates] - positions[:candidates - 1])
    distance = np.minimum(np.abs(positions[1:candidates] - origin), np.abs(positions[:candidates - 1] - origin))
    cost = separation / (distance + CHORD_M)
    cost[gamma[1:candidates] * gamma[:candidates - 1] < 0.0] *= penalty
    assert _merge_pair(positions, gamma, origin, candidates, CHORD_M, penalty) == int(np.argmin(cost))


@pytest.mark.parametrize("constrained", [True, False])
def test_coupling_kinematics_are_the_models(constrained):
    rig = load_rig()
    model = VehicleModel(rig, constrained=constrained, lane_radius_m=rig.lane_1_radius_m if constrained else None)
    coupling = WakeCoupling(model)
    rng = np.random.default_rng(2)
    for _ in range(3):
        q = rng.normal(0.0, 0.5, model.nq)
        if not constrained:
            q[1] = rig.lane_1_radius_m
        pose, q2 = coupling._foil_kinematics(q)
        assert np.array_equal(np.array(pose), np.asarray(model.foil_pose_function()(q), dtype=float).ravel())
        assert np.array_equal(q2, model.foil_velocity_map(q))
