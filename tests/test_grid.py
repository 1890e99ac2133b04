"""A grid read in chunks gives its points in the product's order (x-major, then y, then z)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from pipeline.workspace.grid import box_grid, step_grid


@pytest.mark.parametrize("grid", [
    step_grid(np.array([-1.0, 0.0, 2.0]), np.array([1.0, 3.0, 5.5]), 0.5),  # 5 x 7 x 8 points
    step_grid(np.array([0.0, 0.0, 0.0]), np.array([0.3, 0.2, 0.0]), 0.1),  # one z point per line
    box_grid(np.array([0.0, -2.0, 1.0]), np.array([1.0, 2.0, 1.5]), 3),
], ids=["asymmetric", "flat", "cube"])
def test_every_chunk_of_a_grid_is_that_span_of_the_product_of_its_axes(grid):
    product = np.array(list(itertools.product(*grid.axes)))  # the law: x-major, then y, then z
    assert len(grid) == len(product)
    rng = np.random.default_rng(7)
    spans = [(0, len(grid)), (0, 1), (len(grid) - 1, len(grid)), (3, 3), (len(grid), len(grid))]
    spans += [tuple(sorted(rng.integers(0, len(grid) + 1, 2))) for _ in range(200)]
    for start, stop in spans:
        chunk = grid[start:stop]
        assert chunk.shape == (stop - start, 3) and chunk.flags.c_contiguous and chunk.flags.writeable
        np.testing.assert_array_equal(chunk, product[start:stop])
    for size in (1, 7, 64):  # chunks end to end are the whole grid
        np.testing.assert_array_equal(np.concatenate([grid[a:a + size] for a in range(0, len(grid), size)]), product)
    with pytest.raises(ValueError, match="contiguous"):
        grid[::2]
