"""Speed of the feasible tension model (cables only pull): hyperplane shifting against the LPs
it replaces, in one run, on one core.

    python benchmarks/bench_feasible.py

Cases: the CPR-8 on the paper's box (actuator 1, a 20^3 grid, 8 acceleration vertices, the
slack, torque and voltage margins nested) at zero orientation with both readings of eq. (20)'s
columns and at 0.5 rad about every axis with moments; and a random 8-cable robot (anchors in a
4 m cube, attachments on a 0.3 m platform, statics on a 10^3 grid, t in [1, 500] N, a 30 kg
platform). For each: poses/s of the tension margins (each criterion's least over the
acceleration vertices) by hyperplane shifting with its LP fallback (second call, so neither
numba's cached search nor scipy's import is counted), of the LPs alone (on every 10th pose:
they are slow), their ratio, and the share of poses the fast path sent to the LP; then poses/s
of the whole kernel (every criterion, chunks of 4 096 poses) under that model, the share of the
kernel's time in the compiled crossing search (a profile of one pass) and the kernel's poses/s
without it (``rest/s``: the ceiling a free search would leave, set by the numpy around it).
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # honest per-core figures: set before numpy is imported

import cProfile  # noqa: E402
import pstats  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from hydra import compose, initialize_config_dir  # noqa: E402

from pipeline.model.catalogue import load_catalogue  # noqa: E402
from pipeline.app.config import register  # noqa: E402
from pipeline.app.problem import typed_config  # noqa: E402
from pipeline.workspace.kernel import evaluate_chunk  # noqa: E402
from pipeline.app.resources import CONF_DIR  # noqa: E402
from pipeline.model.tensions import feasible_tensions  # noqa: E402
from pipeline.workspace.criteria import force_families  # noqa: E402
from pipeline.workspace.dispatch import bounded_chunk_size  # noqa: E402
from pipeline.app.problem import build_problem  # noqa: E402

LP_SAMPLE = 10  # the LPs run on every 10th pose


def composed(*overrides: str):
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        cfg = typed_config(compose("config", overrides=["tension=feasible", *overrides]))
    return build_problem(cfg, load_catalogue())


def random_robot(seed: int = 8) -> list[str]:
    rng = np.random.default_rng(seed)
    anchors = np.round(rng.uniform(-2.0, 2.0, (8, 3)) + [0, 0, 2.0], 3).tolist()
    attachments = np.round(rng.uniform(-0.15, 0.15, (8, 3)), 3).tolist()
    return ["robot=points", f"robot.anchors={anchors}", f"robot.attachments={attachments}",
            "robot.search.lo=[-1,-1,1]", "robot.search.hi=[1,1,3]", "robot.search.step=0.2",
            "load.mass=30", "tension.t_min=1", "tension.t_max=500"]


CASES = {
    "CPR-8 20^3, forces only, zero orientation": ["grid.n=20", "grid.n_vel=6", "model.pinv_columns=translational"],
    "CPR-8 20^3, with moments, zero orientation": ["grid.n=20", "grid.n_vel=6", "model.pinv_columns=full"],
    "CPR-8 20^3, with moments, 0.5 rad": ["grid.n=20", "grid.n_vel=6", "model.pinv_columns=full",
                                          "orientation.psi=0.5", "orientation.theta=0.5",
                                          "orientation.phi=0.5"],
    "random 8-cable robot, statics 11^3": random_robot(),
}


def margins_rates(problem, grid) -> tuple[float, float, float]:
    """(fast poses/s, LP poses/s, share of poses sent to the LP) for the tension margins."""
    def inputs(positions):  # the structure matrices, wrenches and limits, built before timing
        state = problem.spec.state(problem.robot, positions, problem.orientation)
        return (state.structure, *state.wrench_pinv, state.required_wrenches,
                force_families(state, problem.limits))

    arguments = inputs(grid[:])
    feasible_tensions(*arguments)  # warm-up: load the compiled search, import the LP solver
    start = time.perf_counter()
    *_, by_lp = feasible_tensions(*arguments)
    fast = grid.n_points / (time.perf_counter() - start)
    sampled = inputs(grid[:][::LP_SAMPLE])
    start = time.perf_counter()
    feasible_tensions(*sampled, distribution=True)
    lp = len(sampled[0]) / (time.perf_counter() - start)
    return fast, lp, by_lp.mean()


def kernel_rate(problem, grid) -> float:
    size = bounded_chunk_size(problem, 20_000)
    evaluate_chunk(problem, grid[:size])  # warm-up
    start = time.perf_counter()
    for begin in range(0, grid.n_points, size):
        evaluate_chunk(problem, grid[begin:begin + size])
    return grid.n_points / (time.perf_counter() - start)


def profiled_share(problem, grid, names: tuple[str, ...]) -> float:
    """The share of the whole kernel's time spent in the functions ``names`` (their own time,
    e.g. a compiled loop), from a profile of one pass over the grid in chunks: what bounds the
    kernel when they are fast, 1 / (1 - share) the most that making them free would gain."""
    profile = cProfile.Profile()
    size = bounded_chunk_size(problem, 20_000)
    profile.enable()
    for begin in range(0, grid.n_points, size):
        evaluate_chunk(problem, grid[begin:begin + size])
    profile.disable()
    stats = pstats.Stats(profile).stats
    total = sum(row[2] for row in stats.values())  # every function's own time
    return sum(row[2] for key, row in stats.items() if key[2] in names) / total


def main() -> None:
    register()
    print(f"{'case':45s} {'poses':>6s} {'shifting/s':>11s} {'LP/s':>7s} {'ratio':>6s} "
          f"{'to LP':>6s} {'kernel/s':>9s} {'search':>7s} {'rest/s':>9s}")
    for name, overrides in CASES.items():
        problem, grid = composed(*overrides)
        fast, lp, share = margins_rates(problem, grid)
        kernel, search = kernel_rate(problem, grid), profiled_share(problem, grid, ("least_margins",))
        print(f"{name:45s} {grid.n_points:6d} {fast:11,.0f} {lp:7,.0f} {fast / lp:6.1f} "
              f"{share:6.1%} {kernel:9,.0f} {search:7.1%} {kernel / (1 - search):9,.0f}")


if __name__ == "__main__":
    main()
