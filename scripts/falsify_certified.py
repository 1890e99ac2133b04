"""Issue 57's falsification at scale: 10^6 random poses of certified boxes on four robots (the
tests' IPAnema 1, tilted platform with a payload, planar body with a wrench set and crane, each
paved two levels deeper than in tests/test_certified.py), 125 000 in the inside boxes and 125 000
in the outside boxes of each, against the exact per-pose test; prints the contradictions (0 on
2026-11-28; 0 on 2026-11-29 with the second-order certificates, about 4 minutes on two cores).

    python scripts/falsify_certified.py
"""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

import numpy as np  # noqa: E402
from conftest import make_cfg  # noqa: E402
from test_certified import ROBOTS, _min_margins, _problem  # noqa: E402

from pipeline.model.certificates import INSIDE, OUTSIDE  # noqa: E402
from pipeline.workspace import paving  # noqa: E402
total = bad = 0  # a script: it runs from the top
for name in ("ipanema", "tilted payload", "planar body", "crane"):
    overrides, depth = ROBOTS[name]
    problem = _problem(make_cfg, overrides, "compute.n_jobs=2")
    found, _ = paving.pave(problem, depth + 2, 900.0, make_cfg(*overrides, "compute.n_jobs=2").compute)
    rng = np.random.default_rng(11)
    axes = np.flatnonzero(problem.robot.box_hi > problem.robot.box_lo)
    for verdict in (INSIDE, OUTSIDE):
        rows = np.flatnonzero(found.verdict == verdict)
        w = found.volumes(axes)[rows]
        pick = rng.choice(rows, 125_000, p=w / w.sum())
        pts = found.lo[pick] + rng.uniform(0, 1, (125_000, 3)) * (found.hi[pick] - found.lo[pick])
        least = np.concatenate([_min_margins(problem, pts[i:i + 25000]) for i in range(0, 125_000, 25_000)])
        wrong = (least < -problem.margin_atol).sum() if verdict == INSIDE else (least >= -problem.margin_atol).sum()
        total, bad = total + len(least), bad + int(wrong)
        print(name, "inside" if verdict == INSIDE else "outside", len(rows), "boxes", len(least), "poses", wrong,
              "contradictions", flush=True)
print("total", total, "contradictions", bad)
