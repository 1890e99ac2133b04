"""Connected reach: the component of the home node against a literal breadth-first search over the
grid, for each neighbourhood, on a set built to split, and end to end on a job's points."""

from collections import deque
from itertools import product

import numpy as np
import pandas as pd
import pyarrow as pa
import pytest

from pipeline.api import workspace
from pipeline.workspace.grid import box_grid
from pipeline.workspace.shape import GridShape

OFFSETS = {6: [d for d in product((-1, 0, 1), repeat=3) if sum(map(abs, d)) == 1],
           18: [d for d in product((-1, 0, 1), repeat=3) if 1 <= sum(map(abs, d)) <= 2],
           26: [d for d in product((-1, 0, 1), repeat=3) if any(d)]}


def flood(feasible: np.ndarray, home: tuple, neighbourhood: int) -> np.ndarray:
    """The nodes a breadth-first search reaches from ``home`` through feasible nodes, one
    neighbour offset at a time."""
    reached = np.zeros_like(feasible)
    if not feasible[home]:
        return reached
    reached[home] = True
    queue = deque([home])
    while queue:
        node = queue.popleft()
        for offset in OFFSETS[neighbourhood]:
            nxt = tuple(a + b for a, b in zip(node, offset))
            if all(0 <= i < n for i, n in zip(nxt, feasible.shape)) and feasible[nxt] and not reached[nxt]:
                reached[nxt] = True
                queue.append(nxt)
    return reached


def _reach(feasible: np.ndarray, home, neighbourhood: int, chunk: int = 50):
    """Feed ``feasible`` (its grid's shape) to a GridShape in chunks of ``chunk`` rows, as a job does."""
    n = feasible.shape[0]
    grid = box_grid(np.zeros(3), np.ones(3), n)
    shape = GridShape(grid, None, home, neighbourhood)
    flags = feasible.ravel()
    write = shape.watching(None)
    for start in range(0, len(flags), chunk):
        write(pa.table({"feasible": flags[start:start + chunk]}))
    return shape, shape.summary()


def test_a_set_that_touches_only_along_an_edge_or_at_a_corner():
    feasible = np.zeros((9, 9, 9), dtype=bool)
    feasible[0:4, 0:4, 0:4] = True  # the home block
    feasible[4:6, 4:6, 0:4] = True  # shares only an edge (x = 4, y = 4) with it
    feasible[6:9, 6:9, 4:9] = True  # shares only a corner with the second block
    feasible[0:3, 6:9, 6:9] = True  # apart from everything
    expected = {6: 64, 18: 64 + 16, 26: 64 + 16 + 45}
    for neighbourhood, count in expected.items():
        reach, summary = _reach(feasible, (0.0, 0.0, 0.0), neighbourhood)
        assert summary["n_connected"] == count
        np.testing.assert_array_equal(reach.connected, flood(feasible, (0, 0, 0), neighbourhood).ravel())
        assert summary["connected_pct"] == pytest.approx(100 * count / 729)
        assert summary["connected_volume_m3"] == pytest.approx(count / 729)


@pytest.mark.parametrize("neighbourhood", [6, 18, 26])
def test_random_sets_against_a_breadth_first_search(neighbourhood):
    rng = np.random.default_rng(neighbourhood)
    for _ in range(5):
        feasible = rng.random((11, 11, 11)) < 0.45
        home = tuple(rng.integers(0, 11, size=3))
        feasible[home] = True
        reach, summary = _reach(feasible, [h / 10 for h in home], neighbourhood, chunk=97)
        reached = flood(feasible, home, neighbourhood)
        np.testing.assert_array_equal(reach.connected, reached.ravel())
        assert 1 <= summary["n_connected"] == reached.sum() <= feasible.sum()


def test_a_home_that_is_not_feasible_connects_nothing(caplog):
    feasible = np.ones((5, 5, 5), dtype=bool)
    feasible[2, 2, 2] = False
    reach, summary = _reach(feasible, (0.5, 0.5, 0.5), 26)
    assert summary["n_connected"] == 0 and not reach.connected.any()
    assert "is not feasible: no pose is connected to it" in caplog.text


def test_a_job_reports_the_component_in_its_summary_and_points(tmp_path):
    """The CPR-8 with 5 cm cables: the job's column ``connected`` is the breadth-first search
    over its own ``feasible`` column, row by row, and the summary counts it; without points the
    summary is the same."""
    args = ["robot.cable_diameter=0.05", "grid.n=10", "workspace.home=[1.6,1.1,-1.1]", "workspace.neighbourhood=26"]
    done = workspace(args, tmp_path / "points")
    points = done.points.sort_values(["x", "y", "z"])
    feasible = points["feasible"].to_numpy().reshape(10, 10, 10)
    home = tuple(np.abs(np.unique(points[axis]) - value).argmin() for axis, value in zip("xyz", (1.6, 1.1, -1.1)))
    np.testing.assert_array_equal(points["connected"].to_numpy(), flood(feasible, home, 26).ravel())
    assert done.summary["n_connected"] == points["connected"].sum() > 0
    assert (points["connected"] <= points["feasible"]).all()
    summary_only = workspace([*args, "output.points=false"], tmp_path / "summary")
    for key in ("n_connected", "connected_pct", "connected_volume_m3", "home_x", "home_y", "home_z"):
        assert summary_only.summary[key] == done.summary[key]
    assert list((tmp_path / "points").glob(".*unfinished*")) == []  # the scratch file is gone
    assert isinstance(done.points, pd.DataFrame)


def test_the_cloud_fills_the_connected_poses_and_leaves_the_others_hollow():
    import matplotlib.pyplot as plt

    from pipeline.analyses.figures import _cloud_panel

    points = pd.DataFrame({"x": [0.0, 1.0, 2.0, 3.0], "y": 0.0, "z": 0.0, "psi": 0.0, "theta": 0.0, "phi": 0.0,
                           "feasible": [True, True, True, False], "connected": [True, True, False, False],
                           "limiting": pd.Categorical(["speed"] * 3 + ["torque"])})
    fig = plt.figure()
    ax = fig.add_subplot(projection="3d")
    _cloud_panel(ax, points, "feasible", False)
    drawn = {c.get_label(): c for c in ax.collections}
    assert set(drawn) == {"connected to home (2)", "feasible, not connected (1)", "torque (1)"}
    assert drawn["feasible, not connected (1)"].get_facecolor().size == 0  # hollow
    plt.close(fig)
