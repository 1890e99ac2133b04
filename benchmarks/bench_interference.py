"""What the interference criteria, the connected reach, the per-pose metrics and the boundary
mesh cost (issue 40), the real cables' models (swivelling pulleys, the stiffness of elastic
cables, the sag rule of heavy ones: issues 54, 55) and the dynamic workspace (issue 56), in whole
processes against the wrench-feasibility job without them, in the same run.

    python benchmarks/bench_interference.py [--repeat 3] [--n 40]

The reference is ``python -m pipeline analysis=statics tension=feasible grid.n=N`` on the CPR-8
(N^3 poses: its carrier's weight held by cables that only pull, the exact check of
``pipeline.model.tensions``); each other line adds one feature, the last all of them. Printed:
wall and CPU seconds (medians and ranges of ``--repeat`` runs), each line's ratio to the
reference, and the extra CPU per pose (the cable models, which refuse each other, are not in
"all of them"). The boundary mesh is drawn by every job of a 3-D grid
(the reference too): its own time, marching cubes on the reference's margins in this process,
is printed apart.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

from bench_process import measured  # noqa: E402

FEATURES = {
    "cable_cable (robot.cable_diameter=0.01)": ["robot.cable_diameter=0.01"],
    "cable_platform (robot.platform.shape=hull)": ["robot.platform.shape=hull"],
    "cable_obstacle (a floor and a table)": [
        "obstacles=[{name: floor, point: [0, 0, -2.3], normal: [0, 0, 1]}, {name: table, lo: [1.2, 0.6, -3], "
        "hi: [2.2, 1.4, -1.5]}]"],
    "connected reach (workspace.home)": ["workspace.home=[1.6,1.1,-1.1]"],
    "per-pose metrics (output.metrics=true)": ["output.metrics=true"],
}
CABLE_MODELS = {
    "swivelling pulleys (robot.pulleys, r = 5 cm)": ["robot.pulleys={axis: [0, 0, -1], radius: 0.05}"],
    "stiffness (robot.cable_ea, criteria.stiffness)": [
        "robot.cable_ea=1e5", "+criteria.stiffness={translational: 1000, rotational: 10, frequency: 0}"],
    "sag rule (robot.cable_mass, criteria.sag)": ["robot.cable_mass=0.05", "+criteria.sag={ratio: 0.02}"],
    "dynamic workspace (platform_motion, +-1 m/s^2 in x, y, z)": [
        "platform_motion.acceleration={min: [-1, -1, -1, 0, 0, 0], max: [1, 1, 1, 0, 0, 0]}"],
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--n", type=int, default=40, help="grid points per axis")
    args = parser.parse_args()
    py = sys.executable
    base = [py, "-m", "pipeline", "analysis=statics", "tension=feasible", f"grid.n={args.n}"]
    poses = args.n ** 3
    with tempfile.TemporaryDirectory() as scratch:
        cwd = Path(scratch)
        reference = measured(f"reference: statics, tension=feasible, {poses} poses", [*base, "hydra.run.dir=ref{run}"],
                             args.repeat, cwd)
        everything = [o for extra in FEATURES.values() for o in extra]
        for label, extra in [*FEATURES.items(), ("all of them", everything), *CABLE_MODELS.items()]:
            wall, cpu = measured(label, [*base, *extra, f"hydra.run.dir=run{{run}}_{len(extra)}_{abs(hash(label))}"],
                                 args.repeat, cwd)
            print(f"  / reference: wall x{wall / reference[0]:.2f}, CPU x{cpu / reference[1]:.2f}; "
                  f"{1e6 * (cpu - reference[1]) / poses:+.1f} us CPU per pose")
        _mesh_time(cwd / "ref0" / "points.parquet", args.n)


def _mesh_time(points: Path, n: int) -> None:
    """Marching cubes on the reference job's least margins, in this process (median of 5)."""
    import numpy as np
    import pyarrow.parquet as pq

    from pipeline.workspace.boundary import boundary_mesh

    table = pq.read_table(points)
    margins = np.min([table.column(c).to_numpy() for c in table.column_names if c.startswith("margin_")], axis=0)
    axes = tuple(np.unique(table.column(a).to_numpy()) for a in "xyz")
    field = margins.reshape(n, n, n)
    times = []
    for _ in range(5):
        start = time.perf_counter()
        boundary_mesh(field, axes, np.array([a[0] for a in axes]), np.array([a[-1] for a in axes]))
        times.append(time.perf_counter() - start)
    print(f"boundary mesh of the reference's {n ** 3} margins (in process): {sorted(times)[2] * 1e3:.1f} ms "
          f"({min(times) * 1e3:.1f}-{max(times) * 1e3:.1f})")


if __name__ == "__main__":
    main()
