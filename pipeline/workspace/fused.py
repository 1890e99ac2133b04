"""The criteria of the ``pinv`` tension model fused into one loop over poses, compiled by numba
(issue 18's fused kernels; the loops are in ``pipeline.workspace.fused_loops``), one per analysis:

- CPR-WWA (Filipovic & Kevac 2018): per pose, the cable vectors and lengths (eqs. 1-17), the
  shaft Jacobian J (eqs. 18-19), M = (J^T)^+ F affine in the acceleration (eqs. 20, 31) and the
  margins of eqs. (30), (32)-(34), the cable rating, the longest and the shortest cable, and the
  share of F the minimum-norm torques miss (the ``unreachable`` gate: zero at full rank, |w . F|
  / |F| on the one-short route below);
- statics (Hamed & Zohoor): the structure matrix A of eq. (8) (either moment arm, either cable
  direction), its gram ratio (the singular gate), the tensions s = A^T (A A^T)^-1 f of eqs.
  (7), (10) and the slack, rating, length and zero-length margins;

in registers: no (poses x cables x set) arrays, no LAPACK call per pose. They compute what the
criteria of ``pipeline.workspace.criteria`` compute from ``PoseDynamics`` and ``PoseStatics``, in
the same order of operations where it matters, and are tested against them (tests/test_fused.py).

The pseudo-inverse of J^T (c x m, c = 3 or 6 rows; A for the statics) takes one of two routes,
each used only where numpy's route (``pipeline.model.linalg.batched_pinv``) is beyond doubt the
same:

- full row rank, gram ratio >= ``BAND`` x rtol and no row shorter than sqrt(``BAND``) x rtol times
  the longest (the row test of ``batched_pinv``): (J^T)^+ F = J G^-1 F with G = J^T J, from the
  Cholesky factor of G scaled to unit diagonal (whose squared diagonal product is the gram
  ratio);
- one short, gram ratio < rtol / ``BAND`` or a row that short (CPR-WWA only): the CPR-8 with all six columns at the
  zero orientation (a turn about a vertical axis, a different one per pose, changes no cable
  length). Two steps of inverse iteration on G + mu I give the unit w with w^T J^T ~ 0; with
  J'^T = (I - w w^T) J^T, the matrix whose pseudo-inverse the SVD returns when it drops that
  direction, (J'^T)^+ = J' (J'^T J' + s^2 w w^T)^-1. Taken only when |w^T J^T| is at most
  ``DROPPED`` x rtol x sigma_max / ``BAND`` (the SVD surely drops it) and the completed matrix
  passes the full-rank test (the SVD surely keeps the rest).

Every other pose (rank two short, a singular statics pose, or a ratio or row within a factor
``BAND`` of its bound) is returned as unsettled, and ``pipeline.workspace.kernel`` evaluates it with numpy.

They apply to the ``pinv`` tension model (CPR-WWA: without J-dot, on the extreme velocities and
a product acceleration set, both readings of eqs. 27-29), without per-pose cable quantities
(``pipeline.workspace.dispatch.fused_unfit``, the specs' ``fused_unfit``); a job uses them when the cost model says they pay
for their start (``compute.kernel=auto``, ``pipeline.workspace.dispatch.use_fused``). A process
loads them from numba's cache, or numba compiles them the first time on a machine
(``pipeline.model.jit.compiled_loops``).
"""

from __future__ import annotations

import numpy as np

from pipeline.model.dynamics import acceleration_box, generalized_load_terms, load_wrench_terms
from pipeline.model.geometry import euler_rate_axes, rotation_matrix
from pipeline.model.jit import compiled_loops
from pipeline.workspace.criteria import (ACCELERATION, LENGTH, SINGULAR, SLACK, SPEED, TENSION_MAX, TORQUE,
                                         UNREACHABLE, VOLTAGE, ZERO_LENGTH)

CRITERIA = (SPEED, TORQUE, ACCELERATION, VOLTAGE, TENSION_MAX, LENGTH, ZERO_LENGTH, UNREACHABLE)  # columns of cpr_wwa
STATICS_CRITERIA = (SINGULAR, SLACK, TENSION_MAX, LENGTH, ZERO_LENGTH)  # columns of statics
COMPILED = {"cpr_wwa": CRITERIA, "statics": STATICS_CRITERIA}  # by the spec's kind: what each kernel evaluates
LOOPS = "pipeline.workspace.fused_loops"  # the compiled loops, and the constants named above


def margins(problem, positions: np.ndarray, number: int) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """``margin_<criterion>`` (n,) (and CPR-WWA's ``jacobian_rank``) at the problem's orientation
    ``number``, and (n,) the poses left unsettled (their entries are NaN: evaluate them with
    numpy); not the criteria that read the geometry alone (``pipeline.workspace.kernel`` adds
    them)."""
    return MARGINS[problem.spec.kind](problem, _writable(positions), problem.fused_arguments[number])


def arguments(problem) -> tuple[tuple, ...]:
    """For each orientation of the problem's set, the loop's arguments that the positions do not
    change (the rotated attachments, the load's terms, the limits as arrays): built once a process
    (``WorkspaceProblem.fused_arguments``), not for every chunk (0.4 ms of Python a chunk, an
    eighth of the loop's time on 16 000 poses)."""
    return tuple(ARGUMENTS[problem.spec.kind](problem, tuple(orientation)) for orientation in problem.orientations)


def _statics_arguments(problem, orientation) -> tuple:
    spec, lim, robot = problem.spec, problem.limits, problem.robot
    rotation = rotation_matrix(*orientation)
    wrench = load_wrench_terms(spec.load, robot.up, rotation)[1]
    m = robot.n_cables
    return (np.ascontiguousarray(robot.anchors, dtype=float), np.ascontiguousarray(robot.attachments @ rotation.T),
            spec.cable_direction == "centre", spec.moment_arm == "base", np.ascontiguousarray(wrench[:, None]),
            float(spec.rank_rtol), float(lim.rank_rtol),
            np.array(np.broadcast_to(spec.tension.t_min, (m,)), dtype=float),  # writable copies
            np.array(np.broadcast_to(lim.t_max, (m,)), dtype=float), float(lim.scale),
            np.inf if robot.l_max is None else float(robot.l_max), float(robot.shortest_cable))


def _statics_margins(problem, positions: np.ndarray, constants: tuple):
    n = len(positions)
    out = np.empty((n, len(STATICS_CRITERIA)))
    unsettled = np.zeros(n, dtype=np.bool_)
    compiled_loops(LOOPS).statics(positions, *constants, out, unsettled)
    return {f"margin_{name}": out[:, STATICS_CRITERIA.index(name)]
            for name in problem.criteria if name in STATICS_CRITERIA}, unsettled


def _cpr_wwa_arguments(problem, orientation) -> tuple:
    spec, act, robot = problem.spec, problem.limits, problem.robot
    rotation = rotation_matrix(*orientation)
    rows = 3 if spec.pinv_columns == "translational" else 6
    slope, at_rest = generalized_load_terms(spec.load, robot.up, orientation)
    loads = np.ascontiguousarray(np.column_stack([slope[:rows], at_rest[:rows]]))
    centre, half = acceleration_box(spec.accelerations)
    m = robot.n_cables
    t_max = np.array(np.broadcast_to(np.inf if spec.tension.t_max is None else spec.tension.t_max, (m,)),
                     dtype=float)  # a writable copy: a read-only array is another type to numba
    return (np.ascontiguousarray(robot.anchors, dtype=float), np.ascontiguousarray(robot.attachments @ rotation.T),
            np.ascontiguousarray(euler_rate_axes(*orientation)), np.ascontiguousarray(spec.winch_radius, dtype=float),
            rows, np.ascontiguousarray(spec.velocity_extremes, dtype=float), centre, half, loads,
            float(spec.rank_rtol),
            np.array([act.speed_limit, act.torque_limit, act.accel_limit, act.voltage_limit], dtype=float),
            np.array([act.G_v, act.L_v, act.load_gain], dtype=float), t_max,
            np.inf if robot.l_max is None else float(robot.l_max), float(robot.shortest_cable),
            float(spec.tension.pinv_residual))


def _cpr_wwa_margins(problem, positions: np.ndarray, constants: tuple):
    n = len(positions)
    out = np.empty((n, len(CRITERIA)))
    rank = np.zeros(n, dtype=np.int8)
    unsettled = np.zeros(n, dtype=np.bool_)
    compiled_loops(LOOPS).cpr_wwa(positions, *constants, out, rank, unsettled)
    result = {f"margin_{name}": out[:, CRITERIA.index(name)] for name in problem.criteria if name in CRITERIA}
    result["jacobian_rank"] = rank
    return result, unsettled


def _writable(positions: np.ndarray) -> np.ndarray:
    """A C-contiguous, writable float array: joblib hands a worker a chunk above 1 MB as a
    read-only memory map, which the loops' signature refuses (a read-only array is another type
    to numba); copied only then."""
    return np.require(positions, dtype=float, requirements=["C_CONTIGUOUS", "WRITEABLE"])


MARGINS = {"cpr_wwa": _cpr_wwa_margins, "statics": _statics_margins}  # by the spec's kind
ARGUMENTS = {"cpr_wwa": _cpr_wwa_arguments, "statics": _statics_arguments}
