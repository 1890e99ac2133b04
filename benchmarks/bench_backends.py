"""The chunk workers' backends, whole processes in the same run: a job of 10^7 poses (the fused
kernel, ``output.points=false``) and a five-job sweep whose jobs are split into chunks, each on two
worker threads (``compute.backend=threading``, the default: the reference), on two loky worker
processes, and on a local Dask cluster of two workers (one cluster for the sweep; issue 41).

    python benchmarks/bench_backends.py [--repeat 3] [--n 216]

Printed: wall and CPU seconds and the peak memory of the process tree (medians and ranges of
``--repeat`` runs, one backend after another), and each other line's ratio to its threads' reference.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_process import measured  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--n", type=int, default=216, help="grid points per axis of the large job (216: 10^7)")
    args = parser.parse_args()
    py = sys.executable
    large = [py, "-m", "pipeline", f"grid.n={args.n}", "grid.n_vel=6", "output.points=false"]
    sweep = [py, "-m", "pipeline", "-m", "actuator=1,2,3,4,5", "grid.n=30", "compute.kernel=numpy"]
    cases = [(f"{args.n ** 3} poses", large, "hydra.run.dir"), ("five-job sweep, numpy kernel", sweep, "hydra.sweep.dir")]
    with tempfile.TemporaryDirectory() as scratch:
        cwd = Path(scratch)
        for label, argv, folder in cases:
            threads = measured(f"{label}, threads (reference)", [*argv, f"{folder}=threads{{run}}_{len(argv)}"],
                               args.repeat, cwd)
            for backend in ("loky", "dask"):
                other = measured(f"{label}, {backend}", [*argv, f"compute.backend={backend}",
                                                         f"{folder}={backend}{{run}}_{len(argv)}"], args.repeat, cwd)
                print(f"  {backend} / threads: wall x{other[0] / threads[0]:.2f}, CPU x{other[1] / threads[1]:.2f}")

if __name__ == "__main__":
    main()
