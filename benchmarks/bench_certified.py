"""What a certified workspace costs (issue 57, ``analysis=certified``): whole processes against
the statics of IPAnema 1's grid in the same run.

    python benchmarks/bench_certified.py [--repeat 3] [--depths 15,18]

IPAnema 1 of the README (``robot=points``, [1, 10] N, cables that only pull, massless): the
reference is the statics of its 0.1 m grid (24 000 poses, the README's 9 752 feasible); each other
line paves the same 24 m^3 box to a depth; the last, at the first depth, within a tolerance on the
anchors (``--robust``, m), against the nominal paving of that depth: what the robust enclosures and
naming the build error of each undecided box (``lost_to``) add. Printed: wall and CPU seconds
(medians and ranges of ``--repeat`` runs), each line's ratio to the reference, the boxes certified
per CPU second, and the bracket of the volume and the undecided share of the last run.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

from bench_process import measured  # noqa: E402
from bench_sagging import IPANEMA  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--depths", default="15,18")
    parser.add_argument("--robust", type=float, default=0.01, help="anchors' tolerance (m) of the last paving")
    args = parser.parse_args()
    import pandas as pd

    base = [sys.executable, "-m", "pipeline", *[o for o in IPANEMA if o != "tension.t_max=100"], "tension.t_max=10"]
    with tempfile.TemporaryDirectory() as scratch:
        cwd = Path(scratch)
        reference = measured("statics, 24000 grid poses at 0.1 m (reference)",
                             [*base, "robot.search.step=0.1", "hydra.run.dir=ref{run}"], args.repeat, cwd)
        depths = [int(d) for d in args.depths.split(",")]
        nominal = {}
        for depth in depths:
            wall, cpu = nominal[depth] = measured(f"certified, depth {depth}",
                                                  [*base, "analysis=certified", f"certified.depth={depth}",
                                                   "certified.time=3600", f"hydra.run.dir=d{depth}_{{run}}"], args.repeat, cwd)
            summary = pd.read_parquet(cwd / f"d{depth}_{args.repeat - 1}" / "summary.parquet").iloc[0]
            print(f"  / reference: wall x{wall / reference[0]:.2f}, CPU x{cpu / reference[1]:.2f}; "
                  f"{summary.n_points} boxes, {summary.n_points / cpu:.0f} boxes per CPU s; volume in "
                  f"[{summary.inside_m3:.3f}, {summary.inside_m3 + summary.undecided_m3:.3f}] m^3, "
                  f"{summary.undecided_pct:.2f} % undecided")
        first = depths[0]
        wall, cpu = measured(f"certified, depth {first}, anchors within {args.robust} m",
                             [*base, "analysis=certified", f"certified.depth={first}", "certified.time=3600",
                              f"robust.anchors={args.robust}", f"hydra.run.dir=r{first}_{{run}}"], args.repeat, cwd)
        summary = pd.read_parquet(cwd / f"r{first}_{args.repeat - 1}" / "summary.parquet").iloc[0]
        print(f"  / nominal depth {first}: wall x{wall / nominal[first][0]:.2f}, CPU x{cpu / nominal[first][1]:.2f}; "
              f"inside {summary.inside_m3:.3f} m^3, undecided {summary.undecided_m3:.3f} m^3 of which "
              f"{summary.lost_named_m3:.3f} lost for certain, most to {summary.lost_to_top} ({summary.lost_to_top_m3:.4f} m^3)")


if __name__ == "__main__":
    main()
