"""Issue 57's falsification at scale: 10^6 random poses of certified boxes on four robots (the
tests' IPAnema 1, tilted platform with a payload, planar body with a wrench set and crane, each
paved two levels deeper than in tests/test_certified.py), 125 000 in the inside boxes and 125 000
in the outside boxes of each, against the exact per-pose test; prints the contradictions (0 on
2026-11-28; 0 on 2026-11-29 with the second-order certificates, about 4 minutes on two cores).
Then the robust pavings of the tests' three robots within build tolerances (planar body, crane,
IPAnema 1), two levels deeper: 10^6 robots drawn within the tolerances, each at a random pose of
a robust inside box, and 20 000 poses each against its worst robot to first order (every
coordinate of every error at the end of its interval where the exact margin of the robot built
with that single error is the lower), all by the law (``test_certified._law_feasible``): 0 in
3.06 * 10^6 on 2026-11-29 with the anchors followed to first order (about 4 more minutes).

    python scripts/falsify_certified.py
"""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

import numpy as np  # noqa: E402
from conftest import make_cfg  # noqa: E402
from test_certified import ROBOTS, ROBUST, _law_feasible, _min_margins, _problem  # noqa: E402

from pipeline.model.certificates import INSIDE, OUTSIDE  # noqa: E402
from pipeline.workspace import paving  # noqa: E402
from pipeline.workspace.tolerances import errors  # noqa: E402
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

def robots(problem, tolerances, mass, signs):
    """Anchors, attachments, masses and centres of mass (n rows) of the robots whose coordinates
    are at ``signs`` (n, m, 3), (n, m, 3), (n,), (n, 3) times their tolerances."""
    robot = problem.robot
    return (robot.anchors + tolerances.anchors * signs[0], robot.attachments + tolerances.attachments * signs[1],
            mass + tolerances.mass * signs[2], tolerances.com * signs[3])


for name in sorted(ROBUST):
    overrides, depth, tolerances = ROBUST[name]
    problem = _problem(make_cfg, overrides, "compute.n_jobs=2")
    robot, m = problem.robot, problem.robot.n_cables
    mass = float(next((o.split("=")[1] for o in overrides if o.startswith("robot.platform.mass")), 0.0))
    found, _ = paving.pave(problem, depth + 2, 900.0, make_cfg(*overrides, "compute.n_jobs=2").compute, tolerances)
    rows = np.flatnonzero(found.verdict == INSIDE)
    rng = np.random.default_rng(12)
    held = 0
    for _ in range(10):  # 10^5 robots at a time, each at one pose of a box drawn alike
        n = 100_000
        pick = rng.choice(rows, n)
        pts = found.lo[pick] + rng.uniform(0, 1, (n, 3)) * (found.hi[pick] - found.lo[pick])
        signs = (rng.uniform(-1, 1, (n, m, 3)), rng.uniform(-1, 1, (n, m, 3)), rng.uniform(-1, 1, n), rng.uniform(-1, 1, (n, 3)))
        corner = rng.uniform(size=n) < 1 / 3
        signs = tuple(np.where(corner.reshape(-1, *[1] * (s.ndim - 1)), np.sign(s), s) for s in signs)
        held += int(_law_feasible(name, *robots(problem, tolerances, mass, signs), pts).sum())
    wrong = 10 * n - held
    print(name, "robust inside", len(rows), "boxes", 10 * n, "random robots", wrong, "contradictions", flush=True)
    total, bad = total + 10 * n, bad + wrong
    pick = rng.choice(rows, 20_000)
    pts = found.lo[pick] + rng.uniform(0, 1, (20_000, 3)) * (found.hi[pick] - found.lo[pick])
    signs = (np.zeros((20_000, m, 3)), np.zeros((20_000, m, 3)), np.zeros(20_000), np.zeros((20_000, 3)))
    least = {}
    for label, at in errors(problem, tolerances):  # 'anchor <cable> x+', 'mass-', 'com y+'
        least[label] = _min_margins(at(1.0), pts)
    for label in least:
        if not label.endswith("+"):
            continue
        words = label.split()
        lower = least[label] < least[label[:-1] + "-"]  # + is the worse end
        sign = np.where(lower, 1.0, -1.0)
        if words[0] in ("anchor", "attachment"):
            signs[0 if words[0] == "anchor" else 1][:, robot.cable_names.index(words[1]), "xyz".index(words[2][0])] = sign
        elif words[0] == "mass+":
            signs[2][:] = sign
        else:
            signs[3][:, "xyz".index(words[1][0])] = sign
    wrong = int((~_law_feasible(name, *robots(problem, tolerances, mass, signs), pts)).sum())
    print(name, "robust inside", 20_000, "poses against their worst robot to first order", wrong, "contradictions", flush=True)
    total, bad = total + 20_000, bad + wrong
print("total", total, "contradictions", bad)
