"""The wake figure: vortices coloured by the sign of their circulation, sized by its magnitude, over the path; bad
arrays refused with nothing written."""
import numpy as np
import pytest

from swim_bringup.wake_figure import (
    CLOCKWISE_COLOUR,
    COUNTER_CLOCKWISE_COLOUR,
    LARGEST_MARKER_AREA_PT2,
    marker_areas_pt2,
    marker_colours,
    write_wake_figure,
)


def test_marker_area_is_proportional_to_the_strength_and_colour_follows_the_sign():
    circulations = np.array([0.004, -0.002, 0.001, -0.004, 0.0])
    areas = marker_areas_pt2(circulations)
    np.testing.assert_allclose(areas, LARGEST_MARKER_AREA_PT2 * np.array([1.0, 0.5, 0.25, 1.0, 0.0]), rtol=1e-15)
    assert marker_colours(circulations) == [COUNTER_CLOCKWISE_COLOUR, CLOCKWISE_COLOUR, COUNTER_CLOCKWISE_COLOUR,
                                            CLOCKWISE_COLOUR, COUNTER_CLOCKWISE_COLOUR]
    assert COUNTER_CLOCKWISE_COLOUR != CLOCKWISE_COLOUR
    assert not marker_areas_pt2(np.zeros(3)).any() and marker_areas_pt2([]).shape == (0,)


def test_a_wake_over_a_path_is_drawn(tmp_path):
    alpha = np.linspace(0.0, 1.5, 200)
    path = 0.43 * np.column_stack([np.cos(alpha), np.sin(alpha)])
    rng = np.random.default_rng(0)
    vortices = path[::4] + 0.01 * rng.standard_normal((50, 2))     # a street along the path
    vortices[-1] = (5.0, -4.0)                                       # a pair that drifted off: outside the view
    circulations = 0.003 * np.where(np.arange(50) % 2 == 0, 1.0, -1.0) * rng.uniform(0.2, 1.0, 50)
    output = write_wake_figure(tmp_path / "figures" / "wake.png", path, vortices, circulations,
                               reference_xy_m=path * 1.001, tank_radius_m=0.875)
    assert output == tmp_path / "figures" / "wake.png"
    assert output.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and output.stat().st_size > 10_000
    empty = write_wake_figure(tmp_path / "empty.png", path, np.zeros((0, 2)), np.zeros(0))   # no vortex shed yet
    assert empty.stat().st_size > 5_000


@pytest.mark.parametrize("vortices, circulations, match", [
    (np.zeros((3, 2)), np.zeros(2), "one finite value per vortex"),
    (np.zeros((2, 2)), np.array([0.0, np.nan]), "one finite value per vortex"),
    (np.array([[0.0, np.inf]]), np.zeros(1), "vortices_xy_m"),
])
def test_bad_arrays_are_refused_and_nothing_is_written(tmp_path, vortices, circulations, match):
    with pytest.raises(ValueError, match=match):
        write_wake_figure(tmp_path / "wake.png", np.zeros((5, 2)), vortices, circulations)
    with pytest.raises(ValueError, match="path_xy_m"):
        write_wake_figure(tmp_path / "wake.png", np.zeros(5), np.zeros((0, 2)), np.zeros(0))
    assert not (tmp_path / "wake.png").exists()
