"""What a path costs (issue 56, ``analysis=trajectory``): whole processes against the statics of
as many grid poses in the same run.

    python benchmarks/bench_trajectory.py [--repeat 3] [--step 0.2]

The reference is IPAnema 1 of the README (``robot=points``, its anchors and attachments,
[1, 100] N, cables that only pull, a 1 kg platform) on a grid of ``--step`` (3 000 poses at 0.2 m);
the other lines follow a path through three way-points with as many samples (quintics, 4 s a
segment, the step ``dt`` set for the count): the statics of every sample with the platform's
momentum and the cables' speeds and accelerations, then with a Table 1 actuator on every winch
(its four criteria and the drive's columns), then the same under the minimum-norm tensions.
Printed: wall and CPU seconds (medians and ranges of ``--repeat`` runs), each line's ratio to the
reference and the extra CPU per sample.
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

PATH = ["analysis=trajectory", "trajectory.points=[[-1,-0.5,0.5],[1,0.5,1.5],[0.5,-1,1]]", "trajectory.times=4"]
LINES = {
    "path, statics with the momentum": [],
    "path with actuator 1 on every winch": ["actuator=1"],
    "path with actuator 1, minimum-norm tensions": ["actuator=1", "tension=pinv", "tension.t_min=0"],
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--step", type=float, default=0.2)
    args = parser.parse_args()
    base = [sys.executable, "-m", "pipeline", *IPANEMA, "robot.platform.mass=1"]
    poses = round(4 / args.step) * round(3 / args.step) * round(2 / args.step)
    dt = 4.0 / (poses / 2 - 1)  # two segments, each both ends sampled: about as many samples as poses
    with tempfile.TemporaryDirectory() as scratch:
        cwd = Path(scratch)
        reference = measured(f"statics, {poses} grid poses (reference)",
                             [*base, f"robot.search.step={args.step}", "hydra.run.dir=ref{run}"], args.repeat, cwd)
        for number, (label, extra) in enumerate(LINES.items()):
            wall, cpu = measured(f"{label}, {poses} samples",
                                 [*base, "robot.search.step=0.5", *PATH, f"trajectory.dt={dt:.12g}", *extra,
                                  f"hydra.run.dir=p{number}_{{run}}"], args.repeat, cwd)
            print(f"  / reference: wall x{wall / reference[0]:.2f}, CPU x{cpu / reference[1]:.2f}; "
                  f"{1e6 * (cpu - reference[1]) / poses:+.0f} us CPU per sample")


if __name__ == "__main__":
    main()
