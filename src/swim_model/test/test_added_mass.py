"""Added mass of the Joukowski foil: closed forms, an independent boundary-element solution, geometry."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swim_model import JoukowskiFoil
from swim_model.added_mass import added_mass_from_circle_map
from swim_model.boundary_element import added_mass_from_polygon
from swim_model.errors import FoilGeometryError
from swim_model.joukowski import AddedMass, JoukowskiMap, ellipse_map

RHO = 998.2


@settings(max_examples=30, deadline=None)
@given(semi_x=st.floats(0.005, 0.2), aspect=st.floats(0.02, 0.95))
def test_ellipse_matches_closed_forms(semi_x, aspect):
    """m11 = rho pi b^2, m22 = rho pi a^2, m66 = rho pi (a^2 - b^2)^2 / 8, m26 = 0 (Milne-Thomson)."""
    a, b = semi_x, semi_x * aspect
    added = ellipse_map(a, b).added_mass_per_span(RHO)
    assert added.m11 == pytest.approx(RHO * math.pi * b * b, rel=1e-6)
    assert added.m22 == pytest.approx(RHO * math.pi * a * a, rel=1e-6)
    assert added.m66 == pytest.approx(RHO * math.pi * (a * a - b * b) ** 2 / 8.0, rel=1e-6)
    assert abs(added.m26) < 1e-9 * added.m22 * a


def test_circle_matches_closed_form():
    """A map with a = 0 leaves the circle: m11 = m22 = rho pi r^2, m66 = m26 = 0."""
    added = JoukowskiMap(a_m=0.0, zeta_c_m=0.0, r_c_m=0.02).added_mass_per_span(RHO)
    assert added.m11 == pytest.approx(RHO * math.pi * 0.02 ** 2, rel=1e-12)
    assert added.m22 == pytest.approx(RHO * math.pi * 0.02 ** 2, rel=1e-12)
    assert abs(added.m66) < 1e-15 and abs(added.m26) < 1e-15


def test_foil_reproduces_its_chord_and_thickness():
    foil = JoukowskiFoil(0.06, 0.008, 0.3)
    assert foil.map.chord() == pytest.approx(0.06, rel=1e-6)
    assert foil.map.max_thickness() == pytest.approx(0.008, rel=1e-9)
    assert foil.trailing_edge_x_m < 0.0 < foil.leading_edge_x_m
    assert foil.leading_edge_x_m - foil.trailing_edge_x_m == pytest.approx(0.06, rel=1e-12)


def test_foil_agrees_with_boundary_elements():
    """Independent check: panel solution in the physical plane, Richardson-extrapolated (first order)."""
    foil = JoukowskiFoil(0.06, 0.008, 1.0)
    coarse = added_mass_from_polygon(foil.profile(1200), RHO)
    fine = added_mass_from_polygon(foil.profile(2400), RHO)
    panels = AddedMass.from_matrix(2.0 * fine - coarse)
    conformal = foil.added_mass_per_span(RHO)
    for name in ("m11", "m22", "m26", "m66"):
        assert getattr(conformal, name) == pytest.approx(getattr(panels, name), rel=5e-3), name


def test_boundary_elements_reproduce_the_ellipse():
    """The panel method itself, on a closed form (guards the independent check)."""
    added = AddedMass.from_matrix(added_mass_from_polygon(ellipse_map(0.03, 0.01).profile(800), RHO))
    assert added.m22 == pytest.approx(RHO * math.pi * 0.03 ** 2, rel=2e-3)
    assert added.m11 == pytest.approx(RHO * math.pi * 0.01 ** 2, rel=2e-3)


@pytest.mark.parametrize("shift_m", [-0.01, 0.004, 0.02])
def test_moving_the_reference_point_transforms_m26_and_m66(shift_m):
    """Reference point moved by d along x: m26' = m26 - d m22, m66' = m66 - 2 d m26 + d^2 m22."""
    foil = JoukowskiFoil(0.06, 0.008, 1.0)
    base = foil.added_mass_per_span(RHO)
    moved = AddedMass.from_matrix(added_mass_from_circle_map(lambda z: foil.map(z) - shift_m, foil.map.r_c_m, RHO))
    assert moved.m22 == pytest.approx(base.m22, rel=1e-10)
    assert moved.m26 == pytest.approx(base.m26 - shift_m * base.m22, rel=1e-9)
    assert moved.m66 == pytest.approx(base.m66 - 2 * shift_m * base.m26 + shift_m ** 2 * base.m22, rel=1e-9)


def test_whole_span_scales_per_span_values():
    foil = JoukowskiFoil(0.06, 0.008, 0.3)
    per_span, whole = foil.added_mass_per_span(RHO), foil.added_mass(RHO)
    np.testing.assert_allclose(whole.matrix(), 0.3 * per_span.matrix(), rtol=1e-14)


def test_thin_foil_tends_to_the_flat_plate():
    """As thickness -> 0, m22 -> rho pi (c/2)^2 and m66 about mid-chord -> rho pi (c/2)^4 / 8."""
    foil = JoukowskiFoil(0.06, 1e-5, 1.0)
    added = foil.added_mass_per_span(RHO)
    assert added.m22 == pytest.approx(RHO * math.pi * 0.03 ** 2, rel=2e-3)


@pytest.mark.parametrize("chord, thickness, span", [(0.06, 0.04, 0.3), (0.0, 0.01, 0.3), (0.06, -0.01, 0.3),
                                                     (0.06, 0.008, float("nan"))])
def test_impossible_foils_are_refused(chord, thickness, span):
    with pytest.raises(FoilGeometryError):
        JoukowskiFoil(chord, thickness, span)
