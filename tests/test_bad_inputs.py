"""Bad input end to end: every case exits non-zero with one line on stderr and adds no file
under outputs/ (config values, override syntax, catalogue files, corrupted earlier results)."""

import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from omegaconf import OmegaConf

from conftest import command
from pipeline.app.plan import plan
from pipeline.errors import ConfigError
from pipeline.model.catalogue import load_catalogue

pytestmark = pytest.mark.slow


def _catalogue_files(folder: Path) -> None:
    table = load_catalogue().table().reset_index()
    table.rename(columns={"power_W": "power_kW"}).to_csv(folder / "unit.csv", index=False)
    table.assign(inertia_g_cm2=-table["inertia_g_cm2"]).to_csv(folder / "inertia.csv", index=False)
    table.astype({"voltage_V": str}).assign(voltage_V="48 V").to_csv(folder / "text.csv", index=False)
    table.assign(id=1).to_csv(folder / "dup.csv", index=False)
    table.drop(columns="gear_ratio").to_csv(folder / "missing.csv", index=False)
    table.assign(efficiency=85).to_csv(folder / "percent.csv", index=False)
    table.to_parquet(folder / "cat.parquet")
    data = (folder / "cat.parquet").read_bytes()
    (folder / "truncated.parquet").write_bytes(data[: len(data) // 2])
    (folder / "empty.csv").write_text("")
    robots = folder / "robots" / "robot"
    robots.mkdir(parents=True)
    (robots / "noanchors.yaml").write_text("defaults: [points, _self_]\nattachments: [[0, 0, 0], [0, 0, 0]]\n"
                                           "search: {lo: [0, 0, 0], hi: [1, 1, 1], step: 0.5}\n")
    (robots / "empty.yaml").write_text("")
    (robots / "square.yaml").write_text(  # 8 cables, a 2 x 2 x 1 m box
        "defaults: [points, _self_]\nanchors: [[-2, 1.5, 2], [2, 1.5, 2], [2, -1.5, 2], [-2, -1.5, 2], "
        "[-2, 1.5, 0], [2, 1.5, 0], [2, -1.5, 0], [-2, -1.5, 0]]\nattachments: [[0, 0, 0], [0, 0, 0], [0, 0, 0], "
        "[0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0]]\nsearch: {lo: [-1, -1, 0.5], hi: [1, 1, 1.5], step: 0.5}\n")
    (robots / "list.yaml").write_text("- 1\n- 2\n")
    (robots / "textnumber.yaml").write_text(  # YAML 1.1 reads -.5 as text
        "defaults: [points, _self_]\nanchors: [[-2, 1.5, 2], [2, 1.5, 2], [2, -1.5, 2]]\n"
        "attachments: [[-.5, 0, 0], [0, 0, 0], [0, 0, 0]]\nsearch: {lo: [-1, -1, 0.5], hi: [1, 1, 1.5], step: 0.5}\n")
    (robots / "nobox.yaml").write_text(
        "defaults: [points, _self_]\nanchors: [[-2, 1.5, 2], [2, 1.5, 2], [2, -1.5, 2]]\n"
        "attachments: [[0, 0, 0], [0, 0, 0], [0, 0, 0]]\ndofs: [x, y, z]\n")


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    """A working directory with catalogue files and the results of an earlier study run, one
    of whose Parquet files is then truncated."""
    root = tmp_path_factory.mktemp("bad")
    _catalogue_files(root)
    done = command(root, "pipeline.study", "actuator_choice")
    assert done.returncode == 0, done.stderr
    shutil.copytree(root / "outputs" / "studies" / "actuator_choice",
                    root / "outputs" / "studies" / "design_mass")
    summary = root / "outputs" / "studies" / "design_mass" / "summary.parquet"
    summary.write_bytes(summary.read_bytes()[:300])
    return root


CASES = [
    ("pipeline", ["actuator=9"], "actuator=9"),
    ("pipeline", ["-m", "actuator=1,2,9"], "actuator=9"),
    ("pipeline", ["load.mass=nan"], "load.mass=nan"),
    ("pipeline", ["load.com=[0,0]"], "load.com"),
    ("pipeline", ["robot.frame.d=inf"], "robot.frame.d=inf"),
    ("pipeline", ["load.mass=abc"], "load.mass=abc"),
    ("pipeline", ["no_such_key=1"], "no_such_key"),
    ("pipeline", ["model.acceleration_set=sphere"], "sphere"),
    ("pipeline", ["robot=irpm7"], "irpm7"),
    ("pipeline", ["-m", "actuator=1,2", "hydra/launcher=submitit_slurm"],
     "hydra/launcher=submitit_slurm: no such option of Hydra's hydra/launcher group (options: basic, cdpr, joblib; "
     "a Hydra plugin adds its own, e.g. pip install 'cdpr-studies[cluster]' (hydra-submitit-launcher))"),
    ("pipeline", ["-m", "actuator=1,2", "hydra.launcher.backend=dask"], "reads hydra.launcher.n_jobs only"),
    ("pipeline", ["robot=irpm6", "robot.r_end=0"], "robot.r_end=0"),
    ("pipeline", ["-m", "robot=irpm6", "tension.t_max=55000,-1"], "tension.t_max=-1"),
    ("pipeline", ["robot=irpm6", "robot.gamma_deg=130"], "robot.gamma_deg=130"),
    ("pipeline", ["robot=irpm6", "robot.search.step=0"], "robot.search.step=0"),
    ("pipeline", ["grid.n=1"], "grid.n=1"),
    ("pipeline", ["compute.backend=spark"], "compute.backend=spark"),
    ("pipeline", ["compute.n_jobs=0"], "compute.n_jobs=0"),
    ("pipeline", ["-m", "actuator=1,2", "hydra.launcher.n_jobs=0"], "hydra.launcher.n_jobs=0"),
    ("pipeline", ["choice.required_pct=150"], "choice.required_pct=150"),
    ("pipeline", ["orientation.total.n=0"], "orientation.total"),
    ("pipeline", ["actuator=[1,2"], "actuator=[1,2"),
    ("pipeline", ["load.mass=1,2"], "load.mass"),
    ("pipeline", ["analysis=dynamics"], "dynamics"),
    ("pipeline", ["analysis=lines", "lines.samples=some"], "lines.samples=some"),
    ("pipeline", ["lines.samples=all"], "lines.samples=all: no such key"),
    ("pipeline", ["load.mas=1"], "load.mas=1: no such key for robot=cpr8 with analysis=cpr_wwa; did you mean load.mass?"),
    ("pipeline", ["robot=irpm6", "limits.s_max=60000"], "limits.s_max=60000: no such key for robot=irpm6 with "
     "analysis=statics; did you mean tension.t_max?"),
    ("pipeline", ["zzz.top=1"], "zzz.top=1: no such key for robot=cpr8 with analysis=cpr_wwa (a key of another"),
    ("pipeline", ["tension.model=lp"], "tension.model"),
    ("pipeline", ["load.external=[0,0,-5]"], "load.external"),
    ("pipeline", ["tension.model=feasible", "tension.t_min=-5"], "tension.t_min=-5"),
    ("pipeline", ["tension.t_min=20", "tension.t_max=10"], "tension.t_max=10"),
    ("pipeline", ["robot=irpm6", "tension.t_max=inf"], "tension.t_max=inf"),
    ("pipeline", ["tension.t_min=50"], "tension.model=feasible"),
    ("pipeline", ["robot=irpm6", "model.moment_arm=base", "load.mass=5"], "load.mass=5"),
    ("pipeline", ["catalogue=nowhere.csv"], "catalogue=nowhere.csv: cannot read"),
    ("pipeline", ["catalogue=unit.csv"], "unit 'kW' is not supported"),
    ("pipeline", ["catalogue=truncated.parquet"], "catalogue=truncated.parquet"),
    ("pipeline", ["catalogue=inertia.csv"], "row 2, column inertia_g_cm2"),
    ("pipeline", ["catalogue=empty.csv"], "catalogue=empty.csv"),
    ("pipeline", ["catalogue=percent.csv"], "column efficiency: 85 must be a fraction in [0.001, 1]"),
    ("pipeline", ["orientation.psi=nan"], "orientation.psi=nan: must be finite"),
    ("pipeline", ["orientation.total.bound=inf"], "orientation.total.bound=inf: must be >= 0 and finite"),
    ("pipeline", ["drive.winch_radius=inf"], "drive.winch_radius=inf"),
    ("pipeline", ["model.rank_rtol=inf"], "model.rank_rtol=inf"),
    ("pipeline", ["model.rank_rtol=1e-300"], "model.rank_rtol=1e-300: must be in [1e-12, 0.1]"),
    ("pipeline", ["model.rank_rtol=5"], "model.rank_rtol=5"),
    ("pipeline", ["robot.lower_anchor_drop=inf"], "robot.lower_anchor_drop=inf"),
    ("pipeline", ["motion.v_max=inf"], "motion.v_max=inf"),
    ("pipeline", ["motion.v_max=1e300"], "motion.v_max=1e+300: must be in [1e-06, 1000] m/s"),  # margins inf
    ("pipeline", ["motion.v_max=5e-324"], "motion.v_max=5e-324: must be in [1e-06, 1000] m/s"),  # a zero grid step
    ("pipeline", ["motion.t_acc=1e-300"], "motion.t_acc=1e-300: v_max / t_acc = 1.3e+300 m/s^2 at v_max=1.3 m/s"),
    ("pipeline", ["analysis=lines", "motion.t_dec=1e-5"], "motion.t_dec=1e-05: v_max / t_dec = 1.3e+05 m/s^2"),
    ("pipeline", ["analysis=lines", "motion.t_acc=1e5"], "the 72 lines take 4.35e+06 samples of 0.01 s"),
    ("pipeline", ["analysis=lines", "motion.t_acc=1e300"], "the 72 lines take 1.37e+154 samples"),
    ("pipeline", ["model.acceleration_set=colon", "motion.t_acc=0.001"],
     "model.acceleration_set=colon: 1301 accelerations per axis"),  # 2.2e9 of them: killed for memory before
    ("pipeline", ["load.mass=inf"], "load.mass=inf"),
    ("pipeline", ["load.external=[0,0,nan,0,0,0]"], "load.external"),
    ("pipeline", ["robot=irpm6", "wrench.fx=nan"], "wrench.fx=nan"),
    ("pipeline", ["robot=irpm6", "robot.search.hi=[6,6,inf]"],
     "robot.search.hi=[6.0, 6.0, inf]: every value must be a finite number"),
    ("pipeline", ["tension.model=feasible", "tension.t_max=inf"], "tension.t_max=inf"),
    # magnitudes past any cable robot (a mistyped exponent) once reached HiGHS: "Model error"
    ("pipeline", ["tension.model=feasible", "tension.t_min=1e308"], "tension.t_min=1e+308: must be at most 1e+09 N"),
    ("pipeline", ["tension.model=feasible", "load.mass=1e200"], "load.mass=1e+200: must be >= 0 and at most 1e+08 kg"),
    ("pipeline", ["tension.model=feasible", "load.external=[0,0,1e200,0,0,0]"], "every value must be at most 1e+09"),
    ("pipeline", ["robot=irpm6", "tension=feasible", "wrench.fz=1e250"], "wrench.fz=1e+250: must be finite and at most 1e+09"),
    ("pipeline", ["grid.n=1000000"], "compute.max_poses=50000000"),
    ("pipeline", ["grid.n_vel=100000"], "grid.n_vel=100000"),
    ("pipeline", ["compute.kernel=gpu"], "compute.kernel=gpu"),
    ("pipeline", ["compute.kernel=fused", "model.jdot=true"], "compute.kernel=fused: it evaluates model.jdot=false only"),
    ("pipeline", ["robot=irpm6", "tension=feasible", "compute.kernel=fused"],
     "compute.kernel=fused: it evaluates tension.model=pinv only"),
    ("pipeline", ["orientation.total.n=1000", "orientation.total.bound=0.1"], "compute.max_poses"),
    ("pipeline", ["-m", "load.mass=1,2,inf"], "load.mass=inf"),
    ("pipeline", ["robot=irpm6", "motion.v_max=1"], "no such key for robot=irpm6 with analysis=statics"),
    # a traceback of OmegaConf's, a misleading "robot.name=None", a limit blamed on the grid, a crash in the job
    ("pipeline", ["--config-dir", "robots", "robot=noanchors"], "robot.anchors: no value given"),
    ("pipeline", ["--config-dir", "robots", "robot=frame9"], "robot=frame9: no such option of the robot group "
     "(options: cpr8, empty, irpm6, list, noanchors, nobox, points, square, textnumber)"),
    ("pipeline", ["--config-dir", "robots", "robot=textnumber"],
     "robot.attachments[0]=['-.5', 0, 0]: must be 3 finite numbers [x, y, z] (m) ('-.5' is text to YAML: write -0.5)"),
    ("pipeline", ["--config-dir", "robots", "robot=nobox"],
     "robot.search.lo: no value given (the box searched needs lo, hi and step; or list the poses to check"),
    ("pipeline", ["--config-dir", "robots", "robot=nobox", "robot.search.lo=[0,0,0]", "robot.search.step=1"],
     "robot.search.hi: no value given"),
    ("pipeline", ["--config-dir", "robots", "robot=empty"], "robot: the robot file gives no robot keys"),
    ("pipeline", ["--config-dir", "robots", "robot=list"], "robot=list: the robot file gives no robot keys"),
    ("pipeline", ["compute.max_poses=-1"], "compute.max_poses=-1: must be >= 1"),
    ("pipeline", ["workspace.home=[0,0,9]"], "workspace.home: z=9 is outside the grid (z from -2.04712 to -0.152882)"),
    ("pipeline", ["workspace.home=[0,0]"], "workspace.home=[0.0, 0.0]: needs 3 values"),
    ("pipeline", ["workspace.home=[0,0,-1]", "poses=[[1,1,-1]]"], "workspace.home: the connected reach needs the robot's grid"),
    ("pipeline", ["workspace.home=[1,1,-1]", "analysis=lines"], "workspace.home: analysis=lines follows straight lines"),
    ("pipeline", ["output.mesh=true", "poses=[[1,1,-1]]"], "output.mesh=true: the grid is a list of poses"),
    ("pipeline", ["output.mesh=true", "analysis=lines"], "output.mesh=true: analysis=lines follows straight lines"),
    ("pipeline", ["--config-dir", "robots", "robot=square", "robot.search.lo=[-1,-1,1]", "robot.search.hi=[1,1,1]",
                  "output.mesh=true"], "output.mesh=true: the grid is flat (one node along an axis)"),
    ("pipeline", ["robot=irpm6", "output.metrics=true", "compute.kernel=fused"],
     "compute.kernel=fused: it does not write the per-pose metrics of output.metrics=true"),
    ("pipeline", ["output.metrics=true"], "output.metrics=true: the tension factor and the largest wrenches are of"),
    ("pipeline", ["workspace.neighbourhood=8"], "workspace.neighbourhood=8: must be 6, 18 or 26"),
    ("pipeline", ["robot=irpm6", "robot.platform.shape=hull"], "robot.platform.shape=hull: the attachment points span no volume"),
    ("pipeline", ["robot.platform.shape={lo:[-0.1,-0.1,-0.1],hi:[0.1,0.1,0.1]}"],
     "robot.platform.shape: attachment 1 [-0.112, -0.077, 0.07] is outside the platform's body"),
    ("pipeline", ["robot.platform.shape=sphere"], "robot.platform.shape=sphere: hull, or a box"),
    ("pipeline", ["obstacles=5"], "obstacles=5: a list of boxes"),
    ("pipeline", ["obstacles=[{lo:[0,0,0]}]"], "obstacles[0]={'lo': [0, 0, 0]}: a box {lo: [3], hi: [3]} or a plane"),
    ("pipeline", ["obstacles=[{name:wall,point:[0,0,-0.1],normal:[0,0,-1]}]"],
     "obstacles[0] (wall): anchor 1 [0.0, 0.0, 0.0] is inside it"),
    ("pipeline", ["obstacles=[{point:[0,0,-3],normal:[0,0,0]}]"], "obstacles[0].normal=[0.0, 0.0, 0.0]: must not be zero"),
    ("pipeline", ["obstacles=[{lo:[0,0,-1],hi:[1,1,inf]}]"], "obstacles[0].hi=[1, 1, inf]: every value must be a finite number"),
    ("pipeline", ["robot.cable_diameter=-0.01"], "robot.cable_diameter=-0.01: must be a number > 0"),
    ("pipeline", ["robot.cable_diameter=nan"], "robot.cable_diameter=nan: must be a number > 0"),
    ("pipeline", ["robot.cable_diameter=abc"], "robot.cable_diameter=abc: must be a number > 0"),
    ("pipeline", ["robot.cable_diameter=[0.01,0.02]"], "robot.cable_diameter=[0.01, 0.02]: 2 values for 8 cables"),
    ("pipeline", ["robot.cable_diameter=1e9"], "robot.cable_diameter=1000000000.0: must be at most a tenth of the robot's size "
     "(0.32 m"),
    ("pipeline", ["obstacles=[" + ",".join(f"{{lo:[{i},-9,-9],hi:[{i + 0.5},-8,-8]}}" for i in range(101)) + "]"],
     "obstacles: 101 of them; at most 100"),
    ("pipeline", ["--config-dir", "robots", "robot=square", "robot.cable_diameter=0.01"],
     "robot.cable_diameter=0.01: every two cables share an anchor or an attachment point"),
    # a ZeroDivisionError after the run folder existed; a sweep of 10^8 jobs hung while it was listed
    ("pipeline", ["--config-dir", "robots", "robot=square", "robot.search.step=5", "robot.search.spacing=centres"],
     "robot.search.step=5.0: no grid point in the search box"),
    ("pipeline", ["-m", "actuator=range(0,10000)", "load.mass=range(1,10001)"],
     "-m: 1e+08 jobs (actuator: 10000 x load.mass: 10000); at most 100000"),
    ("pipeline", ["drive.gear_ratio=1e308"], "drive.gear_ratio=1e+308: must be >= 0.001 and at most 100000"),
    ("pipeline", ["drive.gear_ratio=1e-300"], "drive.gear_ratio=1e-300: must be >= 0.001"),  # 1/0 in eq. 22
    ("pipeline", ["load.gravity=1e300"], "load.gravity=1e+300: must be in [0, 10000] m/s^2"),  # margins inf
    ("pipeline", ["load.com=[1e300,0,0]"], "load.com=[1e+300, 0.0, 0.0]: every value must be at most 10000"),
    ("pipeline", ["grid.n_vel=1"], "grid.n_vel=1: must be >= 2"),  # no velocity inside the sphere of eq. 26
    ("pipeline.study", ["no_such_study"], "study 'no_such_study' not found"),
    ("pipeline.study", ["actuator_choice", "catalogue=text.csv"], "row 2, column voltage_V: '48 V'"),
    ("pipeline.study", ["actuator_choice", "catalogue=dup.csv"], "row 3, column id: duplicate id 1"),
    ("pipeline.study", ["actuator_choice", "catalogue=missing.csv"], "missing column(s) gear_ratio"),
    ("pipeline.study", ["design_mass", "--figures-only"], "not a readable Parquet file"),
    ("pipeline.study", ["design_mass", "load.mass=-1"], "load.mass=-1.0: must be >= 0"),
    ("pipeline.study", ["actuator_choice", "drive.gear_ratio=0"], "drive.gear_ratio=0"),
    ("pipeline.study", [], "no study given"),
    ("pipeline.study", ["design_mass", "irpm_fig13_end_ratio", "motion.v_max=0.5"], "no such key for robot=irpm6"),
    ("pipeline.report", [], "no results for studies"),
]


def listing(root: Path) -> set[str]:
    return {str(p.relative_to(root)) for p in (root / "outputs").rglob("*")}


# Run end to end (a process, its exit status, its stderr, the files): the report case, one job
# case of each kind (a bad value, a sweep, a bad catalogue file, a grammar error) and of each way
# a study command fails (no study, redrawing damaged results, several studies at once).
END_TO_END = {"actuator=9", "-m actuator=1,2,9", "catalogue=truncated.parquet", "actuator=[1,2",
              "-m actuator=1,2 hydra.launcher.n_jobs=0", "grid.n=1000000", "no_such_study",
              "design_mass --figures-only", "design_mass irpm_fig13_end_ratio motion.v_max=0.5"}
IN_PROCESS = [c for c in CASES if c[0] == "pipeline" and " ".join(c[1]) not in END_TO_END]
STUDIES_IN_PROCESS = [c for c in CASES if c[0] == "pipeline.study" and " ".join(c[1]) not in END_TO_END]
PROCESSES = [c for c in CASES if c not in IN_PROCESS and c not in STUDIES_IN_PROCESS]


@pytest.mark.parametrize("module, args, expected", IN_PROCESS, ids=[" ".join(c[1]) for c in IN_PROCESS])
def test_the_plan_names_the_bad_key_and_value(workdir, monkeypatch, module, args, expected):
    """What `python -m pipeline ARGS` prints after ``error: `` (pipeline.app.cli), in-process."""
    monkeypatch.chdir(workdir)
    before = listing(workdir)
    with pytest.raises(ConfigError) as raised:
        plan(args)
    assert expected in str(raised.value) and "\n" not in str(raised.value)
    assert listing(workdir) == before


@pytest.mark.parametrize("module, args, expected", STUDIES_IN_PROCESS, ids=[" ".join(c[1]) for c in STUDIES_IN_PROCESS])
def test_a_study_command_names_the_bad_input(workdir, monkeypatch, capsys, module, args, expected):
    """What `python -m pipeline.study ARGS` prints (one line, exit 2, nothing written), in-process."""
    from pipeline.study import main

    monkeypatch.chdir(workdir)
    before = listing(workdir)
    with pytest.raises(SystemExit) as raised:
        main(args)
    lines = capsys.readouterr().err.strip().splitlines()
    assert raised.value.code == 2
    assert len(lines) == 1 and lines[0].startswith("error: ") and expected in lines[0], lines
    assert listing(workdir) == before


@pytest.mark.parametrize("module, args, expected", PROCESSES, ids=[" ".join(c[1]) or c[0] for c in PROCESSES])
def test_one_line_error_nonzero_exit_and_no_new_output(workdir, module, args, expected):
    before = listing(workdir)
    proc = subprocess.run([sys.executable, "-m", module, *args], cwd=workdir,
                          capture_output=True, text=True, timeout=300)
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2, proc.stderr
    assert len(lines) == 1 and lines[0].startswith("error: ") and expected in lines[0], proc.stderr
    assert listing(workdir) == before


def test_every_declared_rule_is_applied(make_cfg):
    """Each field's value rule sits next to its declaration (pipeline/app/config.py, ``rule``) and
    ``check_values`` applies all of them: a default that breaks none passes, and each rule-bearing
    field set to a value its rule refuses is named in the error."""
    from dataclasses import fields, is_dataclass

    from pipeline.app.config import Config, check_values
    from pipeline.errors import ConfigError

    def ruled(schema, prefix=""):
        for f in fields(schema):
            default = f.default_factory() if callable(f.default_factory) else None
            if is_dataclass(default):
                yield from ruled(type(default), f"{prefix}{f.name}.")
            elif "check" in f.metadata:
                yield f"{prefix}{f.name}", f.metadata["check"]

    cfg = make_cfg()
    check_values(cfg, Config)
    rules = dict(ruled(Config))
    assert len(rules) >= 25
    tried = 0
    for key, check in rules.items():
        parent, _, leaf = key.rpartition(".")
        node = OmegaConf.select(cfg, parent) if parent else cfg
        if node is None or leaf not in node:
            continue  # a key of another analysis
        for bad in (float("nan"), -1, 0, 1e9, [float("inf")]):
            if not _refused(check, bad):
                continue
            node = make_cfg()
            try:
                OmegaConf.update(node, key, bad)
            except Exception:  # a value of the wrong type for this field
                continue
            with pytest.raises(ConfigError, match=re.escape(f"{key}=")):
                check_values(node, Config)
            tried += 1
            break
    assert tried >= 20


def _refused(check, value):
    try:
        return check(value) is not None
    except TypeError:
        return False


def test_files_users_share_cannot_set_hydra_and_run_code(tmp_path):
    """A robot file given through --config-dir set hydra.callbacks (a builtins.open(..., 'w')
    callback truncated a file, exit 0); so did +hydra.callbacks on the command line. Refused,
    one line, exit 2, nothing written; a robot file of its own keys still runs."""
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me\n")
    robots = tmp_path / "mine" / "robot"
    robots.mkdir(parents=True)
    good = ("defaults: [points, _self_]\n"  # IPAnema 1 (README), a coarse grid
            "anchors: [[-2, 1.5, 2], [2, 1.5, 2], [2, -1.5, 2], [-2, -1.5, 2], [-2, 1.5, 0], [2, 1.5, 0], "
            "[2, -1.5, 0], [-2, -1.5, 0]]\n"
            "attachments: [[-0.06, 0.06, 0], [0.06, 0.06, 0], [0.06, -0.06, 0], [-0.06, -0.06, 0], "
            "[-0.06, 0.06, 0], [0.06, 0.06, 0], [0.06, -0.06, 0], [-0.06, -0.06, 0]]\n"
            "search: {lo: [-1, -1, 0.5], hi: [1, 1, 1.5], step: 0.5}\n")
    (robots / "tri.yaml").write_text(good)
    callback = f"{{_target_: builtins.open, file: {victim}, mode: w}}"
    cases = {
        "global.yaml": f"# @package _global_\ndefaults: [points, _self_]\nhydra: {{callbacks: {{x: {callback}}}}}\n",
        "plugin.yaml": "defaults: [points, {override /hydra/launcher: basic}, _self_]\n",
    }
    for name, text in cases.items():
        bad = tmp_path / f"conf_{name}" / "robot"
        bad.mkdir(parents=True)
        (bad / "tri.yaml").write_text(good)
        (bad / name).write_text(text)
        done = subprocess.run([sys.executable, "-m", "pipeline", "--config-dir", str(bad.parent), "robot=tri",
                               "hydra.run.dir=out"], cwd=tmp_path, capture_output=True, text=True, timeout=120)
        assert done.returncode == 2, done.stderr
        assert done.stderr.count("\n") == 1 and f"robot/{name} sets Hydra's own settings" in done.stderr
    line = subprocess.run([sys.executable, "-m", "pipeline", f"+hydra.callbacks.x={callback}", "hydra.run.dir=out"],
                          cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert line.returncode == 2 and "a Hydra callback runs code" in line.stderr
    assert victim.read_text() == "keep me\n" and not (tmp_path / "out").exists()
    fine = subprocess.run([sys.executable, "-m", "pipeline", "--config-dir", str(robots.parent), "robot=tri",
                           "hydra.run.dir=out"], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert fine.returncode == 0, fine.stderr


BOMB = "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{chr(98 + i)}: &{chr(98 + i)} [*{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, "
    f"*{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}]\n" for i in range(9))


def test_a_yaml_alias_bomb_in_a_robot_or_study_file_is_one_line_at_once(tmp_path, monkeypatch):
    """Ten lines of anchors and aliases expand to 9^10 nodes (the "billion laughs"): read by
    the composition they would hang it. A robot file of ``--config-dir`` and a study file are
    refused at their first alias, before anything is composed."""
    import time

    from pipeline import study

    robots = tmp_path / "mine" / "robot"
    robots.mkdir(parents=True)
    (robots / "bomb.yaml").write_text("defaults: [points, _self_]\n" + BOMB)
    started = time.perf_counter()
    with pytest.raises(ConfigError, match=r"robot/bomb.yaml: line 3: a YAML alias \(\*a\)"):
        plan(["--config-dir", str(robots.parent), "robot=points"])
    studies = tmp_path / "studies"
    studies.mkdir()
    (studies / "bomb.yaml").write_text("title: t\nsource: s\n" + BOMB)
    monkeypatch.setattr(study, "STUDIES_DIR", studies)
    with pytest.raises(ConfigError, match=r"bomb.yaml: line 4: a YAML alias"):
        study.load_study("bomb", studies)
    assert time.perf_counter() - started < 30  # (expanded, either would take minutes and gigabytes)


def test_an_alias_bomb_left_in_a_results_folder_or_a_params_file_is_one_line_at_once(tmp_path):
    """Files read back from an output folder are outside data too: a ``study.yaml`` record
    holding the billion laughs hung a rerun for 9 minutes at 899 MB; a ``--params`` file too."""
    import time

    from pipeline.study import claim_study_dir, params_overrides

    out = tmp_path / "out"
    out.mkdir()
    (out / "study.yaml").write_text("study: x\n" + BOMB)
    started = time.perf_counter()
    with pytest.raises(ConfigError, match=r"out: holds an unreadable study record \(study.yaml: line 3: a YAML alias"):
        claim_study_dir(out, "actuator_choice", [], force=False)
    (tmp_path / "params.yaml").write_text(BOMB)
    with pytest.raises(ConfigError, match=r"--params .*params.yaml: line 2: a YAML alias"):
        params_overrides(tmp_path / "params.yaml")
    assert time.perf_counter() - started < 30
    (out / "study.yaml").write_bytes(b"study: x\n" + b"#" * (2 << 20))  # a record is a few lines
    with pytest.raises(ConfigError, match=r"unreadable study record \(\d+ bytes, a record is a few lines\)"):
        claim_study_dir(out, "actuator_choice", [], force=False)


def test_an_unreadable_study_record_is_one_line_and_force_replaces_it(tmp_path, monkeypatch):
    from pipeline.study import claim_study_dir

    monkeypatch.chdir(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    for garbage in ("garbage: [\n", "- a\n- b\n", "\xff\xfe"):
        (out / "study.yaml").write_text(garbage, errors="surrogateescape")
        with pytest.raises(ConfigError, match="holds an unreadable study record"):
            claim_study_dir(out, "actuator_choice", [], force=False)
        assert "actuator_choice" in claim_study_dir(out, "actuator_choice", [], force=True)


def test_every_bit_flip_in_a_jobs_summary_footer_is_recomputed_not_a_traceback(tmp_path, caplog):
    """A job's summary.parquet read back for reuse is outside data: of the single-bit flips of
    its footer (schema, types, metadata), some make pyarrow raise NotImplementedError ("Integers
    with less than 8 bits"), which the reuse check did not catch (a 43-line traceback). Every
    flip now means "recompute" (None), with a log line."""
    import numpy as np
    import pandas as pd

    from pipeline.app.job import finished_summary
    from pipeline.app.results import read_metadata, read_verified, write_parquet

    path = tmp_path / "summary.parquet"
    frame = pd.DataFrame({"n_feasible": [np.int64(3)], "feasible_pct": [1.5], "limiting": ["torque"],
                          "ok": [True], "rank": [np.int8(5)]})
    write_parquet(frame, path, "config: x\n", {"cdpr.digests": "{}"})
    good = path.read_bytes()
    assert finished_summary(tmp_path, "config: x\n") is not None  # the intact file is reused
    uncaught_before = 0
    for bit in range(8 * (len(good) - 512), 8 * len(good)):
        flipped = bytearray(good)
        flipped[bit // 8] ^= 1 << (bit % 8)
        path.write_bytes(bytes(flipped))
        try:
            read_metadata(path)
            read_verified(path)
        except NotImplementedError:
            uncaught_before += 1
        except (OSError, ValueError):
            pass
        summary = finished_summary(tmp_path, "config: x\n")
        assert summary is None or summary == frame.iloc[0].to_dict(), bit  # a flip in padding may change nothing
    assert uncaught_before > 10  # the flips that reached the user as a traceback are among them


def test_obstacles_and_a_fine_search_step_are_counted_before_any_work(make_cfg, catalogue, caplog, tmp_path):
    """Unbounded work with no output (issue 51): 100 obstacle boxes on a 40^3 grid are announced
    with their share of the time before the job starts; a study search of step 1e-12 is refused
    when the study is read."""
    import logging

    from pipeline.app.problem import build_problem
    from pipeline.study import load_study
    from pipeline.workspace.dispatch import announce_cost

    boxes = "[" + ",".join(f"{{lo:[{0.1 + 0.03 * i},0.1,-2.25],hi:[{0.11 + 0.03 * i},0.2,-2.21]}}" for i in range(100)) + "]"
    cfg = make_cfg("grid.n=40", f"obstacles={boxes}")
    problem, grid = build_problem(cfg, catalogue)
    with caplog.at_level(logging.WARNING):
        announce_cost(cfg, problem, grid.n_points, 1)
    assert "this job evaluates 64000 poses" in caplog.text and "its 100 obstacles take about" in caplog.text
    (tmp_path / "fine.yaml").write_text("title: t\nsource: s\noptimise: null\nsearch:\n  variables:\n"
                                        "    drive.gear_ratio: {low: 5, high: 60, step: 1e-12}\n")
    with pytest.raises(ConfigError, match=r"search.variables.drive.gear_ratio: step=1e-12 gives 5.5e\+13 values "
                                          r"from 5 to 60; at most 10000"):
        load_study("fine", tmp_path)


@pytest.mark.parametrize("name", ["boundary.stl", "points.parquet", "summary.parquet"])
def test_a_folder_where_a_job_writes_a_file_is_one_line_before_the_work(tmp_path, name):
    """A folder named boundary.stl in the job's folder failed the job after its computation."""
    from conftest import command

    (tmp_path / "run" / name).mkdir(parents=True)
    done = command(tmp_path, "pipeline", "output.mesh=true", f"hydra.run.dir={tmp_path / 'run'}")
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert lines[0] == (f"error: {tmp_path / 'run' / name}: not a file, where the job writes its {name}; move it "
                        "or choose another folder (hydra.run.dir=...)")
    assert "feasible" not in done.stdout  # refused before the verdicts


def test_listed_poses_need_no_search_box(workdir, monkeypatch):
    """poses=[...] checks those poses: a robot file without a search box runs (the summary's box
    is NaN); it demanded robot.search.lo, which it does not use (issue 51)."""
    from pipeline.api import workspace

    monkeypatch.chdir(workdir)
    done = workspace(["robot=nobox", "poses=[[0,0,1],[0.5,0,1],[0,0,3]]", "load.mass=1", "tension=feasible"],
                     workdir / "poses_run", config_dir=workdir / "robots")
    assert done.summary["n_points"] == 3 and np.isnan(done.summary["box.x_min"])
    assert done.points["feasible"].tolist()[:2] == [True, True]
