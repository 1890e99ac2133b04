"""Whole processes of two checkouts of the project, interleaved in one run: is a change slower?

    python benchmarks/bench_versions.py OLD_CHECKOUT [NEW_CHECKOUT] [--repeat 3] [--no-all]

Each command runs with its working folder in the checkout (Python imports ``pipeline`` from
there, whatever is installed) and writes into a fresh scratch folder, so nothing is reused:

- the main job, ``python -m pipeline -m actuator=1,2,3,4,5``;
- a 40-job sweep, ``python -m pipeline -m load.mass=1,...,8 actuator=1,...,5``;
- every declared study, ``python -m pipeline.study --all`` (unless ``--no-all``).

Prints the median wall and CPU seconds with their ranges, and new / old per command. NEW_CHECKOUT
defaults to this one. Both must have numba's cache warm (run the main job once in each).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_process import timed  # noqa: E402

COMMANDS = {
    "main job": ["-m", "pipeline", "-m", "actuator=1,2,3,4,5", "hydra.sweep.dir={out}"],
    "40-job sweep": ["-m", "pipeline", "-m", "load.mass=1,2,3,4,5,6,7,8", "actuator=1,2,3,4,5",
                     "hydra.sweep.dir={out}"],
    "study --all": ["-m", "pipeline.study", "--all", "--out", "{out}"],
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("old", type=Path)
    parser.add_argument("new", type=Path, nargs="?", default=Path(__file__).resolve().parents[1])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--no-all", action="store_true", help="skip study --all (about 80 s a run)")
    args = parser.parse_args()
    names = [name for name in COMMANDS if not (args.no_all and name == "study --all")]
    times = {(name, side): [] for name in names for side in ("old", "new")}
    for _ in range(args.repeat):
        for name in names:
            for side, checkout in (("old", args.old), ("new", args.new)):  # interleaved
                with tempfile.TemporaryDirectory() as scratch:
                    argv = [sys.executable, *(a.format(out=Path(scratch) / "out") for a in COMMANDS[name])]
                    wall, cpu, _ = timed(argv, checkout.resolve())
                times[(name, side)].append((wall, cpu))
    for name in names:
        row = []
        for side in ("old", "new"):
            walls = [w for w, _ in times[(name, side)]]
            cpus = [c for _, c in times[(name, side)]]
            row.append(f"{side} {statistics.median(walls):.2f} s ({min(walls):.2f}-{max(walls):.2f}), "
                       f"CPU {statistics.median(cpus):.2f} s")
        ratio = statistics.median(w for w, _ in times[(name, "new")]) / statistics.median(
            w for w, _ in times[(name, "old")])
        print(f"{name}: {'; '.join(row)}; new/old wall x{ratio:.2f}")


if __name__ == "__main__":
    main()
