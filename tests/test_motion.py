import numpy as np
import pytest

from pipeline.motion import acceleration_set, velocity_set


@pytest.mark.parametrize("boundary, count", [("exclude", 93), ("include", 123)])
def test_velocity_set_size_and_symmetry(boundary, count):
    v = velocity_set(1.3, 6, boundary)
    assert len(v) == count
    speeds = np.linalg.norm(v, axis=1)
    assert speeds.max() <= 1.3 * (1 + 1e-9)
    as_set = {tuple(np.round(row, 9)) for row in v}
    assert all(tuple(np.round(-row, 9)) in as_set for row in v)  # symmetric under v -> -v


def test_velocity_grid_step_is_2v_over_n():
    axis = np.unique(np.round(velocity_set(1.3, 6, "include")[:, 0], 12))
    np.testing.assert_allclose(np.diff(axis), 2 * 1.3 / 6)


def test_acceleration_corners_and_colon():
    corners = acceleration_set(1.3, 1.82, 1.82, "corners")
    assert corners.shape == (8, 3)
    np.testing.assert_allclose(np.unique(corners), [-1.3 / 1.82, 1.3 / 1.82])
    colon = acceleration_set(1.3, 1.82, 1.82, "colon")
    np.testing.assert_allclose(np.unique(colon), [-1.3 / 1.82, -1.3 / 1.82 + 1.0])
