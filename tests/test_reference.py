"""The vectorised kernel equals the literal per-pose procedure of section 3 on the paper's grid."""

import numpy as np
import pytest

from pipeline.workspace.kernel import evaluate_chunk
from pipeline.workspace.reference import literal_margins
from pipeline.app.problem import build_problem

pytestmark = pytest.mark.slow  # the literal loop takes about 1 s per case

ROTATED = ("orientation.psi=0.5", "orientation.theta=0.5", "orientation.phi=0.5")
FULL_JDOT = ("model.pinv_columns=full", "model.jdot=true")
CASES = [(a, o, ()) for a in (1, 2, 3, 4, 5) for o in ((), ROTATED)]
CASES += [(1, ROTATED, FULL_JDOT), (5, (), FULL_JDOT)]


@pytest.mark.parametrize("actuator, orientation, reading", CASES)
def test_kernel_equals_literal_reference(make_cfg, catalogue, actuator, orientation, reading):
    problem, grid = build_problem(make_cfg(f"actuator={actuator}", *orientation, *reading), catalogue)
    poses = grid[:][::5]  # 44 of the 6 x 6 x 6 poses: every x, y and z value, every (x, y) and (x, z) pair
    fast = evaluate_chunk(problem, poses)
    slow = literal_margins(problem.robot, poses, problem.orientation, problem.spec, problem.limits)
    for name, margin in slow.items():
        np.testing.assert_allclose(fast[f"margin_{name}"], margin, rtol=0, atol=1e-9)
        np.testing.assert_array_equal(fast[f"margin_{name}"] >= 0, margin >= 0)
