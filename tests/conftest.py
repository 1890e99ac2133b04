"""Shared fixtures: configs composed from the real conf/ directory, as the command line does."""

from __future__ import annotations

import contextlib
import importlib
import io
import logging
import os
import subprocess
import sys

import numpy as np
import pytest
from hydra import compose, initialize_config_dir

from pipeline.model.catalogue import load_catalogue
from pipeline.model.dynamics import load_wrenches
from pipeline.app.config import register
from pipeline.app.plan import Composition, parse, structural
from pipeline.app.problem import build_problem
from pipeline.app.resources import CONF_DIR
from pipeline.workspace.compute import grid_workspace

register()


def compute_workspace(cfg, catalogue, sink=None, sweep_pays: bool = False):
    """The points and the summary of a typed config's workspace, computed in this process: the
    grid analysis of :func:`pipeline.app.problem.build_problem`'s problem (the job's own path
    without its files)."""
    return grid_workspace(cfg, *build_problem(cfg, catalogue), sink, sweep_pays)


@pytest.fixture(scope="session")
def catalogue():
    return load_catalogue()


COMPOSED: dict = {}  # the compositions of make_cfg, by their config files (one per test process)


def make_cfg(*overrides: str):
    """The composed, typed config a job sees (serial compute for in-process tests), not
    validated. Each set of config files is composed once per test process and each config
    derived from it by its plain overrides (``pipeline.app.plan.Composition``, checked equal to
    typing Hydra's own composition in tests/test_plan.py); a config whose files set a value by
    interpolation is typed from Hydra's composition, as the plan does."""
    parsed = parse(["compute.n_jobs=1", *overrides])
    files = tuple(o.input_line for o in parsed if structural(o))
    if files not in COMPOSED:
        with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
            COMPOSED[files] = Composition(compose(config_name="config", overrides=list(files),
                                                  return_hydra_config=True))
    return COMPOSED[files].job(parsed)[0]


@pytest.fixture(name="make_cfg", scope="session")
def make_cfg_fixture():
    """:func:`make_cfg` as a fixture."""
    return make_cfg


MAINS = {"pipeline": ("pipeline.app.cli", "cli"), "pipeline.study": ("pipeline.study", "main"),
         "pipeline.caspr": ("pipeline.caspr", "main"), "pipeline.report": ("pipeline.report", "main"),
         "pipeline.wirex": ("pipeline.wirex", "main")}


def command(cwd, module: str, *args: str) -> subprocess.CompletedProcess:
    """``python -m MODULE ARGS`` in ``cwd``, run in this test process (its entry point with
    ``sys.argv``, stdout and stderr as the process would have them): the exit status, stdout and
    stderr as ``subprocess.run`` gives them, without a process start's imports. The working
    folder, ``sys.argv`` and the root logger are restored after it. Tests of what only a process
    shows (its imports, signals, two at once, the console script) start one."""
    where, name = MAINS[module]
    entry = getattr(importlib.import_module(where), name)
    root = logging.getLogger()
    handlers, level, before, argv = root.handlers[:], root.level, os.getcwd(), sys.argv
    out, err = io.StringIO(), io.StringIO()
    status = 0
    try:
        os.chdir(cwd)
        sys.argv = [module, *args]
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                entry(list(args)) if module != "pipeline" else entry()
            except SystemExit as exc:
                status = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    finally:
        os.chdir(before)
        sys.argv = argv
        for handler in root.handlers[:]:
            if handler not in handlers:
                root.removeHandler(handler)
                handler.close()
        for handler in handlers:
            if handler not in root.handlers:
                root.addHandler(handler)
        root.setLevel(level)
    return subprocess.CompletedProcess([module, *args], status, out.getvalue(), err.getvalue())


def job_imports(cwd, *args: str, modules=("pandas", "numba", "scipy")) -> str:
    """Run ``python -m pipeline *args`` in ``cwd`` in a process that reports at exit, on
    stderr, ``<module> imported: True|False`` for each of ``modules``; its output."""
    return job_at_exit(cwd, *args, report=", ".join(
        f"print('{m} imported:', '{m}' in sys.modules, file=sys.stderr)" for m in modules))


def job_at_exit(cwd, *args: str, report: str, status: int = 0) -> str:
    """Run ``python -m pipeline *args`` in ``cwd`` in a process that evaluates ``report`` (an
    expression, ``sys`` and ``gc`` imported) when it exits, after the command; its stdout and
    stderr. The process must end with ``status``."""
    script = ("import atexit, gc, runpy, sys\n"
              f"atexit.register(lambda: ({report}))\n"
              f"sys.argv = ['pipeline', *{list(args)!r}]\n"
              "runpy.run_module('pipeline', run_name='__main__', alter_sys=True)\n")
    done = subprocess.run([sys.executable, "-c", script], cwd=cwd, capture_output=True, text=True)
    assert done.returncode == status, done.stderr[-2000:]
    return done.stdout + done.stderr


def shaft_torque(dyn) -> np.ndarray:
    """(n, m, k_a) the load torques M = (J^T)^+ F of eq. (20) at every acceleration of the set,
    enumerated (the reference of ``PoseDynamics.torque_affine``'s ranges)."""
    wrenches = load_wrenches(dyn.motion, dyn.motion.accelerations, dyn.robot.up, dyn.orientation)
    pinv = dyn.wrench_pinv[0]
    return np.einsum("nmc,ac->nma", pinv, wrenches[:, :pinv.shape[2]])


def shaft_accel_from_acceleration(dyn) -> np.ndarray:
    """(n, m, k_a) J p_ddot at every acceleration of the set, enumerated."""
    return np.einsum("nmj,aj->nma", dyn.jacobian[:, :, :3], dyn.motion.accelerations)


def wrenches(dyn) -> np.ndarray:
    """(k_a, 6) F of eq. (31) at every acceleration of the set."""
    return load_wrenches(dyn.motion, dyn.motion.accelerations, dyn.robot.up, dyn.orientation)


# An 8-cable frame of IPAnema 1's size with a platform 0.2 x 0.2 x 0.1 m (attachments apart in
# height, so moments are balanced for real): the robot of the payload, wrench-set and tension
# distribution tests, each adding its own load, orientation and limits.
SPREAD_ANCHORS = [[-2, 1.5, 2], [2, 1.5, 2], [2, -1.5, 2], [-2, -1.5, 2],
                  [-2, 1.5, 0], [2, 1.5, 0], [2, -1.5, 0], [-2, -1.5, 0]]
SPREAD_PLATFORM = [[-0.1, 0.1, 0.05], [0.1, 0.1, 0.05], [0.1, -0.1, 0.05], [-0.1, -0.1, 0.05],
                   [-0.1, 0.1, -0.05], [0.1, 0.1, -0.05], [0.1, -0.1, -0.05], [-0.1, -0.1, -0.05]]
SPREAD_ROBOT = ["robot=points", f"robot.anchors={SPREAD_ANCHORS}", f"robot.attachments={SPREAD_PLATFORM}",
                "robot.search.lo=[-1.5,-1,0.25]", "robot.search.hi=[1.5,1,1.75]"]


# The same frame with each upper cable crossed to the platform's far corner: its structure matrix
# has full rank across the box (the spread robot's has rank 5: it holds only the wrenches in its
# range), so the tensions balance every wrench of a moving platform exactly
CROSSED_PLATFORM = [[0.1, 0.1, 0.05], [-0.1, 0.1, 0.05], [-0.1, -0.1, 0.05], [0.1, -0.1, 0.05],
                    [0.1, 0.1, -0.05], [-0.1, 0.1, -0.05], [-0.1, -0.1, -0.05], [0.1, -0.1, -0.05]]
CROSSED_ROBOT = ["robot=points", f"robot.anchors={SPREAD_ANCHORS}", f"robot.attachments={CROSSED_PLATFORM}",
                 "robot.search.lo=[-1.5,-1,0.25]", "robot.search.hi=[1.5,1,1.75]", "robot.search.step=0.25"]


def eq9_rotation(psi: float, theta: float, phi: float) -> np.ndarray:
    """Eq. (9), R = Rz(phi) Ry(theta) Rx(psi), written out for the independent references (no
    code of the model)."""
    cx, sx, cy, sy, cz, sz = np.cos(psi), np.sin(psi), np.cos(theta), np.sin(theta), np.cos(phi), np.sin(phi)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx

