"""Speed of the layout search (issue 58): the fast verdict against the registry's in the same run,
and the search's trials on one and two workers.

    python benchmarks/bench_layout.py [--repeat 5] [--trials 40] [--workers 1,2]

Kernel cases, one core (``OPENBLAS_NUM_THREADS=1``): IPAnema 1 at 0.06 m steps (108 900 poses,
[1, 10] N, massless) as built and with its anchors pulled in at random (most poses infeasible, the
slow side of the test), and a random 8-cable robot carrying 30 kg at a tilted orientation. Per
case: poses/s of ``feasible_flags`` (geometry, the other criteria and the null-space test) and of
the registry's verdicts (``evaluate_chunk`` and ``classify``: hyperplane shifting with its LPs, on
every 5th pose), medians and ranges of ``--repeat`` passes, their ratio, and the verdicts compared
pose by pose on the registry's poses. Then the search itself: ``--trials`` trials of the
space of the anchors anywhere in IPAnema 1's frame (quadrants, 12 variables, TPE) on the same
108 900 poses with each ``--workers`` count: wall and CPU seconds (this process and its workers), trials a second, and
what 1 000 trials of 10^5 poses would take at that rate; the process tree's peak memory.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # honest per-core figures: set before numpy is imported

import argparse  # noqa: E402
import resource  # noqa: E402
import time  # noqa: E402
from dataclasses import replace  # noqa: E402

import numpy as np  # noqa: E402
from joblib.externals.loky import get_reusable_executor  # noqa: E402

from bench_feasible import composed, random_robot  # noqa: E402  (the same robots as the tension margins' bench)
from pipeline.analyses.layout import Box, LayoutSpec, search_layouts  # noqa: E402
from pipeline.workspace.feasibility import feasible_flags  # noqa: E402
from pipeline.workspace.kernel import evaluate_chunk  # noqa: E402
from pipeline.workspace.verdict import classify  # noqa: E402

IPANEMA = ["robot=points", "robot.anchors=[[-2,1.5,2],[2,1.5,2],[2,-1.5,2],[-2,-1.5,2],[-2,1.5,0],[2,1.5,0],"
           "[2,-1.5,0],[-2,-1.5,0]]", "robot.attachments=[[-0.06,0.06,0],[0.06,0.06,0],[0.06,-0.06,0],[-0.06,-0.06,0],"
           "[-0.06,0.06,0],[0.06,0.06,0],[0.06,-0.06,0],[-0.06,-0.06,0]]", "robot.search.lo=[-2,-1.5,0]",
           "robot.search.hi=[2,1.5,2]", "robot.search.step=0.06", "robot.search.spacing=centres",
           "tension=feasible", "tension.t_min=1", "tension.t_max=10"]
REGISTRY_SAMPLE = 5  # the registry's verdicts on every 5th pose: they are slow
CHUNK = 4096


def in_chunks(function, positions: np.ndarray) -> np.ndarray:
    return np.concatenate([function(positions[start:start + CHUNK]) for start in range(0, len(positions), CHUNK)])


def rates(problem, positions: np.ndarray, repeat: int) -> tuple[list[float], list[float], int, int]:
    """Poses/s of the fast flags and of the registry, and the verdicts compared (differences, poses)."""
    def registry(rows):
        raw = evaluate_chunk(problem, rows)
        return classify({name: raw[f"margin_{name}"] for name in problem.criteria}, problem.margin_atol)[1]

    sample = positions[::REGISTRY_SAMPLE]
    fast = in_chunks(lambda rows: feasible_flags(problem, rows), positions[:CHUNK])  # warm-up: numba's cache
    fast_rates, registry_rates = [], []
    for _ in range(repeat):
        start = time.perf_counter()
        fast = in_chunks(lambda rows: feasible_flags(problem, rows), positions)
        fast_rates.append(len(positions) / (time.perf_counter() - start))
        start = time.perf_counter()
        reference = in_chunks(registry, sample)
        registry_rates.append(len(sample) / (time.perf_counter() - start))
    return fast_rates, registry_rates, int((fast[::REGISTRY_SAMPLE] != reference).sum()), len(sample)


def spread(values: list[float]) -> str:
    return f"{np.median(values):10,.0f} ({min(values):,.0f}-{max(values):,.0f})"


def cpu_seconds() -> float:
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--trials", type=int, default=40)
    parser.add_argument("--workers", default="1,2", help="the search's n_jobs to measure, e.g. 2")
    args = parser.parse_args()
    problem, grid = composed(*IPANEMA)
    positions = grid[0:len(grid)]
    rng = np.random.default_rng(1)
    pulled = replace(problem, robot=replace(problem.robot, anchors=problem.robot.anchors * rng.uniform(0.6, 1.0, (8, 1))))
    other, other_grid = composed(*random_robot(), "robot.search.step=0.05", "orientation.psi=0.2", "orientation.theta=-0.1")
    print(f"{'case':40s} {'poses':>7s} {'fast poses/s (range)':>30s} {'registry poses/s (range)':>26s} {'ratio':>6s} "
          "differ")
    for name, case, rows in (("IPAnema 1 as built", problem, positions), ("IPAnema 1, anchors pulled in", pulled, positions),
                             ("random 8 cables, 30 kg, tilted", other, other_grid[0:len(other_grid)])):
        fast, registry, differ, compared = rates(case, rows, args.repeat)
        print(f"{name:40s} {len(rows):7d} {spread(fast):>30s} {spread(registry):>26s} "
              f"{np.median(fast) / np.median(registry):6.1f} {differ}/{compared}")
    spec = LayoutSpec(anchors=Box([-2, -1.5, 0], [2, 1.5, 2]), attachments=Box([-0.06, -0.06, 0], [0.06, 0.06, 0]),
                      symmetry="quadrants", budget=args.trials, sampler="tpe")
    for workers in (int(w) for w in args.workers.split(",")):
        cpu, start = cpu_seconds(), time.perf_counter()
        table = search_layouts(spec, problem, positions, grid.cell_volume, workers)
        get_reusable_executor().shutdown(wait=True)  # its workers end: their CPU counts among the children
        wall, cpu = time.perf_counter() - start, cpu_seconds() - cpu
        per_trial = wall / len(table)
        print(f"search, {len(table)} trials of {len(positions)} poses, n_jobs={workers}: {wall:.1f} s wall, {cpu:.1f} s CPU "
              f"(this process and its workers), {len(table) / wall:.2f} trials/s, "
              f"{len(table) * len(positions) / wall:,.0f} poses/s; 1 000 trials of 10^5 poses: "
              f"{per_trial * 1000 * 1e5 / len(positions) / 60:.1f} min; best {table['volume_m3'].max():.3f} m^3")
    peak = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss + resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss) / 1024
    print(f"peak memory: this process and its largest worker together {peak:.0f} MiB")


if __name__ == "__main__":
    main()
