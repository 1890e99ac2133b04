"""What sagging cables cost (issue 55): whole processes against the straight cables' job in the
same run, and the catenary solver alone against a batched 3 x 3 solve of as many cables.

    python benchmarks/bench_sagging.py [--repeat 3] [--step 0.2]

The reference is IPAnema 1 of the README (``robot=points``, its anchors and attachments,
[1, 100] N, cables that only pull) on a grid of ``--step``; the other lines add heavy cables of
0.05 kg/m: the sag rule (``criteria.sag``, an approximation), the catenary (``robot.catenary``,
inextensible), and the elastic catenary (``robot.cable_ea``). Printed: wall and CPU seconds
(medians and ranges of ``--repeat`` runs), each line's ratio to the reference and the extra CPU
per pose; then the solver's cables per second (``catenary.solve`` from the chord tension, 10^5
random cables, median of 5) and its ratio to ``numpy.linalg.solve`` of as many 3 x 3 systems
(one Newton step's linear algebra), and its Newton iterations.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

from bench_process import measured  # noqa: E402

IPANEMA = ["robot=points",
           "robot.anchors=[[-2,1.5,2],[2,1.5,2],[2,-1.5,2],[-2,-1.5,2],[-2,1.5,0],[2,1.5,0],[2,-1.5,0],[-2,-1.5,0]]",
           "robot.attachments=[[-0.06,0.06,0],[0.06,0.06,0],[0.06,-0.06,0],[-0.06,-0.06,0],[-0.06,0.06,0],"
           "[0.06,0.06,0],[0.06,-0.06,0],[-0.06,-0.06,0]]",
           "robot.search.lo=[-2,-1.5,0]", "robot.search.hi=[2,1.5,2]", "robot.search.spacing=centres",
           "tension=feasible", "tension.t_min=1", "tension.t_max=100", "output.points=false"]
MODELS = {
    "sag rule (criteria.sag, 2 %)": ["robot.cable_mass=0.05", "+criteria.sag={ratio: 0.02}"],
    "catenary (robot.catenary=0.02)": ["robot.cable_mass=0.05", "robot.catenary=0.02"],
    "elastic catenary (robot.cable_ea=1e5)": ["robot.cable_mass=0.05", "robot.catenary=0.02", "robot.cable_ea=1e5"],
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--step", type=float, default=0.2)
    args = parser.parse_args()
    base = [sys.executable, "-m", "pipeline", *IPANEMA, f"robot.search.step={args.step}"]
    poses = round(4 / args.step) * round(3 / args.step) * round(2 / args.step)
    with tempfile.TemporaryDirectory() as scratch:
        cwd = Path(scratch)
        reference = measured(f"straight cables, {poses} poses (reference)", [*base, "hydra.run.dir=ref{run}"],
                             args.repeat, cwd)
        for number, (label, extra) in enumerate(MODELS.items()):
            wall, cpu = measured(label, [*base, *extra, f"hydra.run.dir=m{number}_{{run}}"], args.repeat, cwd)
            print(f"  / reference: wall x{wall / reference[0]:.2f}, CPU x{cpu / reference[1]:.2f}; "
                  f"{1e6 * (cpu - reference[1]) / poses:+.0f} us CPU per pose")
    _solver()


def _solver(n: int = 100_000) -> None:
    """The catenary solver's cables per second against numpy's batched 3 x 3 solve."""
    import numpy as np

    from pipeline.model.catenary import solve

    rng = np.random.default_rng(0)
    span, rise = rng.uniform(0.2, 20, n), rng.uniform(-15, 15, n)
    weight, ea = rng.uniform(0.01, 5, n), np.where(rng.random(n) < 0.5, np.inf, rng.uniform(1e4, 1e7, n))
    tau = rng.uniform(1.0, 50.0, n) * weight * np.hypot(span, rise)
    matrices, sides = rng.normal(size=(n, 3, 3)), rng.normal(size=(n, 3, 1))

    def best(call) -> float:
        times = []
        for _ in range(5):
            start = time.perf_counter()
            call()
            times.append(time.perf_counter() - start)
        return statistics.median(times)

    solving = best(lambda: solve(span, rise, weight, ea, "chord_tension", tau))
    linear = best(lambda: np.linalg.solve(matrices, sides))
    print(f"catenary.solve: {n / solving:,.0f} cables/s ({solving:.3f} s for {n}); x{solving / linear:.1f} of "
          f"numpy.linalg.solve on as many 3 x 3 systems ({linear * 1e3:.1f} ms)")


if __name__ == "__main__":
    main()
