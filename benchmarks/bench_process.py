"""Whole-process speed: what a user waits for, measured on the process tree (wall and CPU
seconds of the child processes, from ``os.wait4``), each against a reference run in the same
invocation.

    python benchmarks/bench_process.py [--repeat 3] [--studies]

- the main job ``python -m pipeline -m actuator=1,2,3,4,5`` against ``lean_main_job.py``, a
  script that computes the same five verdicts with the same kernel and writes nothing: the
  ratio is what Hydra, the preflight, the checks and the Parquet files cost on top;
- a 125 000-pose job (``grid.n=50 grid.n_vel=6 actuator=3``) against ``straightforward_job.py``, an
  independent plain-numpy implementation of the same job (same verdicts, checked here), and
  with ``compute.n_jobs=1`` and ``2``: whether the two worker processes pay on this machine;
- a 10^6-pose job (``grid.n=100 grid.n_vel=6``): poses per second end to end and the peak
  resident memory of the whole process tree (parent and workers, sampled every 0.05 s);
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
import threading
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def timed(argv: list[str], cwd: Path) -> tuple[float, float, float]:
    """(wall s, CPU s of the process and its children, peak MiB of the process tree) of one
    command that must succeed. Its stderr goes to a file: a pipe nobody reads while waiting
    fills at 64 KiB and stops a talkative command (``study --all``) for good."""
    with tempfile.TemporaryFile() as errors:
        start = time.perf_counter()
        proc = subprocess.Popen(argv, cwd=cwd, stdout=subprocess.DEVNULL, stderr=errors)
        peak = [0.0]
        sampler = threading.Thread(target=_sample_tree, args=(proc.pid, peak), daemon=True)
        sampler.start()
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - start
        sampler.join()
        if os.waitstatus_to_exitcode(status) != 0:
            errors.seek(0)
            raise SystemExit(f"{' '.join(argv)} failed: {errors.read().decode()[-2000:]}")
    return wall, usage.ru_utime + usage.ru_stime, peak[0]


def _sample_tree(root: int, peak: list) -> None:
    """Largest sum of resident memory (MiB) over ``root`` and its descendants, every 0.05 s
    while ``root`` lives (Linux /proc; 0 elsewhere)."""
    while os.path.exists(f"/proc/{root}"):
        try:
            parents = {}
            for entry in os.listdir("/proc"):
                if entry.isdigit():
                    with open(f"/proc/{entry}/stat") as handle:
                        parents[int(entry)] = int(handle.read().rsplit(")", 1)[1].split()[1])
            tree, grown = {root}, True
            while grown:
                more = {pid for pid, parent in parents.items() if parent in tree} - tree
                tree |= more
                grown = bool(more)
            total = 0
            for pid in tree:
                with open(f"/proc/{pid}/statm") as handle:
                    total += int(handle.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
            peak[0] = max(peak[0], total / 2**20)
        except (OSError, ValueError, IndexError):  # a process ended while being read
            pass
        time.sleep(0.05)


def measured(label: str, argv: list[str], repeat: int, cwd: Path) -> tuple[float, float]:
    """Median (wall, CPU) of ``repeat`` runs; ``{run}`` in an argument is the run's number (a
    fresh folder each time: a finished job's folder would be reused, not recomputed)."""
    runs = [timed([a.replace("{run}", str(i)) for a in argv], cwd) for i in range(repeat)]
    walls, cpus, peaks = [r[0] for r in runs], [r[1] for r in runs], [r[2] for r in runs]
    wall, cpu = statistics.median(walls), statistics.median(cpus)
    print(f"{label:58s} wall {wall:6.2f} s ({min(walls):.2f}-{max(walls):.2f})   "
          f"CPU {cpu:6.2f} s ({min(cpus):.2f}-{max(cpus):.2f})   peak {max(peaks):5.0f} MiB")
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
        main_job = measured("python -m pipeline -m actuator=1,2,3,4,5", [*sweep, "hydra.sweep.dir=main{run}"],
                            args.repeat, cwd)
        print(f"  main job / lean script: wall x{main_job[0] / lean[0]:.2f}, CPU x{main_job[1] / lean[1]:.2f}")
        plain = measured("125 000 poses, straightforward_job.py (reference)",
                         [py, str(HERE / "straightforward_job.py"), "50", "plain.parquet", "3"], args.repeat, cwd)
        big = [py, "-m", "pipeline", "grid.n=50", "grid.n_vel=6", "actuator=3"]
        one = measured("125 000 poses, compute.n_jobs=1", [*big, "compute.n_jobs=1", "hydra.run.dir=one{run}"],
                       args.repeat, cwd)
        two = measured("125 000 poses, compute.n_jobs=2 (default)", [*big, "hydra.run.dir=big{run}"],
                       args.repeat, cwd)
        print(f"  straightforward / job: wall x{plain[0] / two[0]:.2f}, CPU x{plain[1] / two[1]:.2f}; "
              f"n_jobs=2 / n_jobs=1: wall x{two[0] / one[0]:.2f}, CPU x{two[1] / one[1]:.2f}")
        _same_verdicts(cwd / "plain.parquet", cwd / "big0" / "points.parquet")
        million = measured("10^6 poses (grid.n=100 grid.n_vel=6)", [py, "-m", "pipeline", "grid.n=100",
                                                                     "grid.n_vel=6", "hydra.run.dir=million{run}"],
                           args.repeat, cwd)
        print(f"  {1e6 / million[0]:,.0f} poses/s end to end")
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


def _same_verdicts(plain: Path, job: Path) -> None:
    """The straightforward implementation and the job agree pose by pose (else the ratio means
    nothing)."""
    import pyarrow.parquet as pq

    a, b = pq.read_table(plain).to_pydict(), pq.read_table(job, columns=["x", "y", "z", "feasible"]).to_pydict()
    if a["feasible"] != b["feasible"] or any(max(abs(p - q) for p, q in zip(a[k], b[k])) > 1e-12 for k in "xyz"):
        raise SystemExit("straightforward_job.py and the job disagree: the ratio would mean nothing")
    print(f"  same verdicts pose by pose ({sum(a['feasible'])}/{len(a['feasible'])} feasible)")


if __name__ == "__main__":
    main()
