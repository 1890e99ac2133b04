import numpy as np
import pytest

from pipeline.model.motion import acceleration_set, velocity_set


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


def test_velocity_grid_decoupled_from_position_grid(make_cfg, catalogue):
    from pipeline.app.problem import build_problem

    problem, grid = build_problem(make_cfg("grid.n=12", "grid.n_vel=6"), catalogue)
    assert grid.n_points == 12**3 and len(problem.spec.velocities) == 93
    tied, _ = build_problem(make_cfg("grid.n=12"), catalogue)
    assert len(tied.spec.velocities) == len(velocity_set(1.3, 12, "exclude"))


def test_chunk_size_bounded_by_memory_budget(make_cfg, catalogue):
    """grid.n=100 with the velocity grid tied to it keeps 101^3 candidates (2 376 of them extremes,
    which the kernel evaluates) per pose; chunks shrink so one chunk's largest array stays within
    5e5 floats, counted on the extremes (on every velocity with J-dot, which is not linear in v)."""
    from pipeline.workspace.dispatch import CHUNK_BUDGET_FLOATS, bounded_chunk_size
    from pipeline.app.problem import build_problem

    dense, _ = build_problem(make_cfg("grid.n=100"), catalogue)
    size = bounded_chunk_size(dense, 20_000)
    assert len(dense.spec.velocity_extremes) == 2376 and size * 8 * 2376 <= CHUNK_BUDGET_FLOATS
    assert size == 500_000 // (8 * 2376)
    paper, _ = build_problem(make_cfg(), catalogue)
    assert bounded_chunk_size(paper, 20_000) == 500_000 // (8 * 12)  # 8 x 12 extremes
    centripetal, _ = build_problem(make_cfg("grid.n_vel=20", "model.jdot=true"), catalogue)
    assert bounded_chunk_size(centripetal, 20_000) == 500_000 // (8 * len(centripetal.spec.velocities))


@pytest.mark.parametrize("n", [2, 5, 6, 9, 12])
@pytest.mark.parametrize("boundary", ["exclude", "include"])
def test_extreme_velocities_give_the_extremes_of_every_linear_function(n, boundary):
    from pipeline.model.motion import extreme_points

    velocities = velocity_set(1.3, n, boundary)
    extremes = extreme_points(velocities, 2 * 1.3 / n)
    directions = np.random.default_rng(n).normal(size=(500, 3))
    np.testing.assert_allclose((directions @ extremes.T).max(axis=1),
                               (directions @ velocities.T).max(axis=1), rtol=0, atol=1e-12)
    np.testing.assert_allclose((directions @ extremes.T).min(axis=1),
                               (directions @ velocities.T).min(axis=1), rtol=0, atol=1e-12)
    assert len(extremes) < len(velocities) or len(velocities) <= 8
    if (n, boundary) == (6, "exclude"):
        assert len(extremes) == 12
