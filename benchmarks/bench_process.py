"""Whole-process speed: what a user waits for, measured on the process tree (wall and CPU
seconds of the child processes, from ``os.wait4``), each against a reference run in the same
invocation.

    python benchmarks/bench_process.py [--repeat 3] [--studies]

- the main job ``python -m pipeline -m actuator=1,2,3,4,5`` against ``lean_main_job.py``, a
  script that computes the same five verdicts with the same kernel and writes nothing: the
  ratio is what Hydra, the preflight, the checks and the Parquet files cost on top;
- a 125 000-pose job (``grid.n=50 grid.n_vel=6``) with ``compute.n_jobs=1`` and ``2``: the ratio
  says whether the two worker processes pay for themselves on this machine;
- ``--studies``: every declared study, one ``python -m pipeline.study NAME`` each, and the
  whole ``python -m pipeline.study --all`` (in a scratch folder), against the main job's wall
  time in the same run.

Medians and ranges of ``--repeat`` runs; the machine may be shared, so compare ratios.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def timed(argv: list[str], cwd: Path) -> tuple[float, float]:
    """(wall s, CPU s of the process and its children) of one command that must succeed."""
    start = time.perf_counter()
    proc = subprocess.Popen(argv, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"{' '.join(argv)} failed: {proc.stderr.read().decode()[-2000:]}")
    return wall, usage.ru_utime + usage.ru_stime


def measured(label: str, argv: list[str], repeat: int, cwd: Path) -> tuple[float, float]:
    runs = [timed(argv, cwd) for _ in range(repeat)]
    walls, cpus = [r[0] for r in runs], [r[1] for r in runs]
    wall, cpu = statistics.median(walls), statistics.median(cpus)
    print(f"{label:58s} wall {wall:6.2f} s ({min(walls):.2f}-{max(walls):.2f})   "
          f"CPU {cpu:6.2f} s ({min(cpus):.2f}-{max(cpus):.2f})")
    return wall, cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--studies", action="store_true", help="also every study and --all")
    args = parser.parse_args()
    py = sys.executable
    with tempfile.TemporaryDirectory() as scratch:
        cwd = Path(scratch)
        sweep = [py, "-m", "pipeline", "-m", "actuator=1,2,3,4,5"]
        lean = measured("lean script, same 5 verdicts (reference)", [py, str(HERE / "lean_main_job.py")],
                        args.repeat, cwd)
        main_job = measured("python -m pipeline -m actuator=1,2,3,4,5", sweep, args.repeat, cwd)
        print(f"  main job / lean script: wall x{main_job[0] / lean[0]:.2f}, CPU x{main_job[1] / lean[1]:.2f}")
        big = [py, "-m", "pipeline", "grid.n=50", "grid.n_vel=6"]
        one = measured("125 000 poses, compute.n_jobs=1", [*big, "compute.n_jobs=1"], args.repeat, cwd)
        two = measured("125 000 poses, compute.n_jobs=2", [*big, "compute.n_jobs=2"], args.repeat, cwd)
        print(f"  n_jobs=2 / n_jobs=1: wall x{two[0] / one[0]:.2f}, CPU x{two[1] / one[1]:.2f}")
        if not args.studies:
            return
        sys.path.insert(0, str(HERE.parent))
        from pipeline.study import available

        total = 0.0
        for name in available():
            wall, _ = measured(f"study {name}", [py, "-m", "pipeline.study", name, "--out", "one"], 1, cwd)
            total += wall
        print(f"  sum of the studies one by one: {total:.1f} s wall")
        wall, cpu = measured("python -m pipeline.study --all", [py, "-m", "pipeline.study", "--all",
                                                                "--out", "all"], 1, cwd)
        print(f"  --all / main job: wall x{wall / main_job[0]:.1f}")


if __name__ == "__main__":
    main()
