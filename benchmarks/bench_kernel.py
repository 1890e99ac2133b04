"""Throughput of the workspace kernels against the literal per-pose reference, in one run.

    python benchmarks/bench_kernel.py          # reference on 6^3, CPR-WWA on 6^3 and 40^3, IRPM,
                                               # both with tension.model=feasible (LPs)
    python benchmarks/bench_kernel.py --full   # also CPR-WWA 100^3 on 2 workers

CPR-WWA: the paper's sets, 93 velocities (7 per axis, |v| < V) and 8 acceleration corners,
actuator 2, psi = theta = phi = 0.5 rad (rank-6 Jacobian); "zero orientation": the default
orientation, where every J^T is one rank short (numpy: an SVD per pose; the fused kernel: its
deflated route). "fused": the compiled kernel of ``pipeline.workspace.fused``, compiled
before timing. IRPM: statics on the paper's box
(31 x 31 x 26 points), gamma = 15 deg. "1 core" rows run with one BLAS thread. Ratios are against
the reference's poses/s measured here, in the same process. After the table, for each fused
row, the share of its time in the compiled loop (a profile of one pass) and the kernel's rate
without it: what bounds it; for the full-rank CPR-WWA row, its flop rate and its share of this
core's double-precision peak (a one-thread dgemm, same run). Peak memory is this process's
maximum resident set size (workers not included).
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # honest per-core figures: set before numpy is imported

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import resource  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from hydra import compose, initialize_config_dir  # noqa: E402

from pipeline.model.catalogue import load_catalogue  # noqa: E402
from pipeline.app.config import register  # noqa: E402
from pipeline.app.problem import typed_config  # noqa: E402
from pipeline.workspace.kernel import evaluate_chunk  # noqa: E402
from pipeline.workspace.parallel import iter_chunks  # noqa: E402
from pipeline.app.resources import CONF_DIR  # noqa: E402
from pipeline.workspace.reference import literal_margins  # noqa: E402
from pipeline.workspace.dispatch import bounded_chunk_size  # noqa: E402
from pipeline.app.problem import build_problem  # noqa: E402
from bench_feasible import profiled_share  # noqa: E402


def problem_for(n: int, *extra: str, angle: float = 0.5):
    return composed(f"grid.n={n}", "grid.n_vel=6", "actuator=2",
                    *(f"orientation.{a}={angle}" for a in ("psi", "theta", "phi")), *extra)


def composed(*overrides: str):
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        cfg = typed_config(compose("config", overrides=list(overrides)))
    return build_problem(cfg, load_catalogue())


def serial_rate(problem, grid, repeat: int = 5) -> float:
    """Seconds for the whole grid in chunks, one process, after one warm-up chunk: the median
    of ``repeat`` passes (a pass of the fused kernels lasts milliseconds)."""
    size = bounded_chunk_size(problem, 20_000)
    evaluate_chunk(problem, grid[:size])  # warm-up (imports, caches)

    def serial():  # each chunk's positions from the axes, as a job reads them (workspace.compute)
        for start in range(0, grid.n_points, size):
            evaluate_chunk(problem, grid[start:start + size])

    return float(np.median([timed(serial) for _ in range(repeat)]))


def cpr_wwa_flops(problem) -> int:
    """Floating-point operations of one full-rank pose in the compiled CPR-WWA loop, counted from
    its source (docs/performance.md): each cable's geometry and row of J (46), the lower triangle
    of G (21 entries, 2 m each), its scaled Cholesky factor (about 170), the solve for four
    right-hand sides (4 x 2 x 36), the torques (2 x 4 x 6 a cable) and the criteria (7 a cable and
    extreme velocity, 36 more a cable)."""
    m, velocities = problem.robot.n_cables, len(problem.spec.velocity_extremes)
    return m * 46 + 21 * 2 * m + 170 + 4 * 2 * 36 + m * 2 * 4 * 6 + m * (7 * velocities + 36)


def dgemm_rate(n: int = 1200, repeat: int = 5) -> float:
    """This core's double-precision peak as numpy's BLAS reaches it (one thread): flop/s of an
    n x n matrix product, the median of ``repeat``."""
    a, b = np.random.default_rng(0).random((2, n, n))
    a @ b  # warm-up
    return 2 * n**3 / float(np.median([timed(lambda: a @ b) for _ in range(repeat)]))


def timed(function) -> float:
    start = time.perf_counter()
    function()
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--full", action="store_true", help="include the 100^3 grid")
    args = parser.parse_args()
    register()
    rows = []
    loops = []  # the fused rows, with what their compiled loop is called

    problem, grid = problem_for(6)
    seconds = timed(lambda: literal_margins(problem.robot, grid[:], problem.orientation,
                                            problem.spec, problem.limits))
    reference = grid.n_points / seconds
    rows.append(("literal reference, 1 core", grid.n_points, seconds))

    for n in (6, 40):
        problem, grid = problem_for(n)
        rows.append((f"CPR-WWA kernel {n}^3, 1 core", grid.n_points, serial_rate(problem, grid)))
    for angle, label in ((0.5, ""), (0.0, " zero orientation")):
        problem, grid = problem_for(40, angle=angle)
        if angle == 0.0:
            rows.append((f"CPR-WWA kernel 40^3{label}, 1 core", grid.n_points, serial_rate(problem, grid)))
        fused = dataclasses.replace(problem, fused=True)
        rows.append((f"CPR-WWA fused 40^3{label}, 1 core", grid.n_points, serial_rate(fused, grid)))
        loops.append((rows[-1], fused, grid, "cpr_wwa"))
    for n in (6, 20):  # cables only pull: 8 acceleration vertices x 3 nested LPs per pose
        problem, grid = problem_for(n, "tension.model=feasible")
        rows.append((f"CPR-WWA feasible tensions {n}^3, 1 core", grid.n_points, serial_rate(problem, grid)))
    problem, grid = composed("robot=irpm6", "robot.gamma_deg=15")
    rows.append(("IRPM statics 31x31x26, 1 core", grid.n_points, serial_rate(problem, grid)))
    fused = dataclasses.replace(problem, fused=True)
    rows.append(("IRPM statics fused 31x31x26, 1 core", grid.n_points, serial_rate(fused, grid)))
    loops.append((rows[-1], fused, grid, "statics"))
    problem, grid = composed("robot=irpm6", "robot.gamma_deg=15", "tension.model=feasible")
    rows.append(("IRPM feasible tensions, 1 core", grid.n_points, serial_rate(problem, grid)))
    for i, n in enumerate((40, 100) if args.full else (40,)):
        problem, grid = problem_for(n)
        size = bounded_chunk_size(problem, 20_000)

        def parallel():
            for _ in iter_chunks(evaluate_chunk, problem, grid[:], n_jobs=2, chunk_size=size):
                pass

        if i == 0:
            parallel()  # start the loky worker pool once, outside the timing
        rows.append((f"CPR-WWA kernel {n}^3, 2 workers", grid.n_points, timed(parallel)))

    print(f"{'case':46s} {'poses':>9s} {'seconds':>9s} {'poses/s':>11s} {'x reference':>12s}")
    for name, poses, secs in rows:
        rate = poses / secs
        print(f"{name:46s} {poses:9d} {secs:9.3f} {rate:11,.0f} {rate / reference:12,.0f}")
    peak_flops = dgemm_rate()
    for (name, poses, secs), problem, grid, loop in loops:  # what bounds a fused kernel (a profile)
        share = profiled_share(problem, grid, (loop,))
        print(f"{name}: the compiled loop {share:.0%} of the time, the rest alone {poses / secs / (1 - share):,.0f} poses/s")
        if loop == "cpr_wwa" and "zero" not in name:  # every pose full rank: the count above holds
            flops = cpr_wwa_flops(problem)
            kernel, alone = poses / secs * flops, poses / secs / share * flops
            print(f"  {flops:,} flop a pose: the kernel {kernel / 1e9:.1f} GFLOP/s, {kernel / peak_flops:.0%} of this "
                  f"core's dgemm ({peak_flops / 1e9:.1f} GFLOP/s, one thread); the loop {alone / 1e9:.1f} GFLOP/s, "
                  f"{alone / peak_flops:.0%}")
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak resident memory of this process: {peak:.0f} MiB")


if __name__ == "__main__":
    main()
