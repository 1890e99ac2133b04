"""The plan checks every job of a command before any folder is made, with Hydra's composition and
its basic sweeper's expansion."""

import pytest

from pipeline.errors import ConfigError
from pipeline.app.plan import parse, plan, sweep_jobs


def test_sweep_expands_like_hydra_basic_sweeper():
    assert [list(job.overrides) for job in plan(["-m", "actuator=1,2", "load.mass=1,3"]).jobs] == [
        ["actuator=1", "load.mass=1"], ["actuator=1", "load.mass=3"],
        ["actuator=2", "load.mass=1"], ["actuator=2", "load.mass=3"],
    ]
    assert plan(["--cfg", "job"]) is None  # Hydra answers it: no job


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["-m", "actuator=1,2,9"], "actuator=9"),
        (["-m", "robot.frame.d=3.2,0.3"], "robot.frame.d=0.3"),
        (["-m", "load.mass=abc", "load.mass=1,2"], "load.mass=abc"),  # Hydra merges it first
        (["-m", "orientation={psi:x}"], "orientation.psi=x"),  # Hydra merges a dict into the files
        (["-m", "hydra/sweeper=nope", "actuator=1,2"], "nope"),
    ],
)
def test_first_bad_job_is_named(argv, needle):
    with pytest.raises(ConfigError) as info:
        plan(argv)
    assert needle in str(info.value) and "\n" not in str(info.value)


def test_value_overrides_reuse_one_composition_and_stay_typed():
    masses = ",".join(str(1 + i / 10) for i in range(200))
    plan(["-m", f"load.mass={masses}"])
    with pytest.raises(ConfigError, match="grid.n=2.5"):
        plan(["-m", f"load.mass={masses}", "grid.n=3,2.5"])


def test_expansion_matches_hydra_basic_sweeper_with_ranges_and_repeated_keys():
    """Same jobs, in the same order, as the basic sweeper's own split (Hydra's internal code is
    used here only as the reference, never by the package)."""
    from hydra._internal.core_plugins.basic_sweeper import BasicSweeper

    argv = ["-m", "actuator=range(1,4)", "load.mass=1", "grid.n=2,3", "load.mass=4,5"]
    expected = BasicSweeper.split_arguments(parse(argv[1:]), max_batch_size=None)[0]
    assert sweep_jobs(parse(argv[1:])) == expected and len(expected) == 12


def test_sweeps_another_sweeper_chooses_are_checked_by_their_fixed_part():
    """Another sweeper (e.g. Optuna) chooses values at run time: the command is Hydra's, its
    fixed part checked; the basic sweeper cannot sample an interval: refused."""
    assert sweep_jobs(parse(["hydra/sweeper=optuna", "load.mass=1,2"])) == [["hydra/sweeper=optuna"]]
    with pytest.raises(ConfigError, match="interval sweeps need a sweeper"):
        plan(["-m", "load.mass=interval(1,3)", "actuator=2"])


def _leaves(cfg, prefix=""):
    """Every leaf of a config as (key, value, Python type), resolved."""
    from omegaconf import DictConfig, ListConfig, OmegaConf

    found = []
    items = cfg.items() if isinstance(cfg, DictConfig) else enumerate(cfg)
    for key, value in items:
        if isinstance(value, (DictConfig, ListConfig)):
            found += _leaves(value, f"{prefix}{key}.")
        else:
            found.append((f"{prefix}{key}", value, type(value)))
    return found + [(prefix, OmegaConf.is_struct(cfg), "struct")] if isinstance(cfg, DictConfig) else found


POINTS = ["robot=points", "robot.anchors=[[2,0,3],[1,2,3],[-1,2,3],[-2,0,3],[-1,-2,3],[1,-2,3]]",
          "robot.attachments=[[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0]]",
          "robot.search.lo=[0,0,0]", "robot.search.hi=[0.5,0.5,1]", "robot.search.step=0.25"]


@pytest.mark.parametrize("argv", [
    ["-m", "actuator=1,3", "load.mass=2,7.5", "compute.kernel=numpy,fused", "model.rank_rtol=1e-6"],
    ["-m", "tension=feasible", "orientation.psi=0,0.1", "load.com=[0,0,0.1],[0.01,0,0]", "poses=[[0.1,0.2,0.3]]"],
    ["-m", "robot=irpm6", "robot.gamma_deg=0,15", "wrench.fx=0,50000", "robot.r_end=4.8", "tension.t_max=null,1e5"],
    ["-m", *POINTS, "robot.l_max=null,3", "load.mass=1,2"],
    ["-m", "--config-dir", "{user}", "robot=hexa", "robot.l_max=null,3", "robot.search.step=0.25,0.5",
     "robot.up=[0,0,1],[0,0.1,1]"],
    ["-m", "--config-dir", "{user}", "robot=tied", "load.mass=3,5"],
])
def test_jobs_derived_from_one_composition_equal_each_job_typed_on_its_own(argv, tmp_path):
    """Each job's typed config, derived from its composition by the overrides' typed values
    (``Composition.job``), equals the job's own composition typed from scratch
    (``typed_config``, the reference): same keys, values, Python types and struct flag."""
    from hydra import compose, initialize_config_dir
    from omegaconf import OmegaConf

    from pipeline.app.problem import typed_config
    from pipeline.app.resources import CONF_DIR

    folder = tmp_path / "robot"  # the user's own robot, every value in its file
    folder.mkdir()
    (folder / "hexa.yaml").write_text(
        "# @package _global_\ndefaults: [points, _self_]\nrobot:\n"
        "  anchors: [[2,0,3],[1,2,3],[-1,2,3],[-2,0,3],[-1,-2,3],[1,-2,3]]\n"
        "  attachments: [[0.2,0,0],[0.1,0.2,0],[-0.1,0.2,0],[-0.2,0,0],[-0.1,-0.2,0],[0.1,-0.2,0]]\n"
        "  search: {lo: [-0.5,-0.5,0], hi: [0.5,0.5,1], step: 0.25}\n")
    (folder / "tied.yaml").write_text(  # a value that follows another key: resolved per job
        "# @package _global_\ndefaults: [hexa, _self_]\nrobot:\n  l_max: ${load.mass}\n")
    argv = [a.replace("{user}", str(tmp_path)) for a in argv]
    user = [f"hydra.searchpath=[file://{tmp_path}]"] if "--config-dir" in argv else []
    planned = plan(argv).jobs
    jobs = [list(job.overrides) for job in planned]
    assert jobs == sweep_jobs(parse([a for a in argv if "=" in a])) and len(jobs) > 1
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3", job_name="reference"):
        for job, overrides in zip(planned, jobs):
            plain = compose(config_name="config", overrides=[*user, *overrides])
            assert OmegaConf.to_yaml(job.config) == OmegaConf.to_yaml(plain)
            assert _leaves(job.cfg) == _leaves(typed_config(plain))


def test_a_bad_value_is_refused_in_any_job_of_a_derived_sweep():
    """Typed values are remembered per override text: a good value first does not let a bad one
    of the same key through, in the sweep's last job too."""
    for argv, needle in [(["-m", "load.mass=1,2,abc"], "load.mass=abc"),
                         (["-m", "actuator=1,2", "compute.kernel=auto,gpu"], "compute.kernel=gpu"),
                         (["-m", "load.com=[0,0,0],[0,0,x]"], "load.com=[0,0,x]")]:
        with pytest.raises(ConfigError, match=needle.replace("[", r"\[").replace("]", r"\]")):
            plan(argv)


def test_copies_equal_deep_copies_also_of_a_config_pickle_cannot_write():
    """``Copies`` unpickles; a structured config whose class pickle cannot find by name (defined
    in a function) is deep-copied instead: equal, independent, still typed copies either way."""
    import copy
    import pickle
    from dataclasses import dataclass, field

    from omegaconf import OmegaConf
    from omegaconf.errors import ValidationError

    from pipeline.app.plan import Copies

    @dataclass
    class Local:
        mass: float = 2.0
        com: list = field(default_factory=lambda: [0.0, 0.0, 0.1])

    plain = OmegaConf.create({"load": {"mass": 2.0, "com": [0, 0, 0.1]}})
    typed = OmegaConf.create({"load": OmegaConf.structured(Local)})
    with pytest.raises((pickle.PicklingError, AttributeError)):
        pickle.dumps(typed)
    for cfg in (plain, typed):
        copies = Copies(cfg)
        first, second = copies(), copies()
        first.load.mass = 5.0
        assert second.load.mass == 2.0 and cfg.load.mass == 2.0
        assert OmegaConf.to_yaml(second) == OmegaConf.to_yaml(copy.deepcopy(cfg))
        cfg.load.mass = 3.0  # copies are of the config as it was when Copies took it
        assert copies().load.mass == 2.0
        cfg.load.mass = 2.0
    with pytest.raises(ValidationError):
        second.load.mass = "heavy"


ROBOT = ("defaults: [points, _self_]\n"
         "anchors: [[-2, 1.5, 2], [2, 1.5, 2], [2, -1.5, 2], [-2, -1.5, 2], [-2, 1.5, 0], [2, 1.5, 0], [2, -1.5, 0], "
         "[-2, -1.5, 0]]\n"
         "attachments: [[0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0]]\n"
         "search: {lo: [-1, -1, 0.5], hi: [1, 1, 1.5], step: 0.5}\n"
         "platform: {mass: 3.0}\n")


def test_a_process_composes_a_set_of_files_once_while_they_and_its_folder_stay_the_same(tmp_path, monkeypatch):
    """Plans over the same config files share Hydra's composition (a notebook's or a study's
    commands); a robot file edited in place, even to the same size and modification time, a
    new file of the folder, or another working folder (Hydra's node records it) compose again."""
    import os

    from hydra import compose

    import pipeline.app.plan as planning

    calls = []
    monkeypatch.setattr(planning, "compose", lambda **kw: calls.append(kw) or compose(**kw))
    robots = tmp_path / "mine" / "robot"
    robots.mkdir(parents=True)
    robot = robots / "box.yaml"
    robot.write_text(ROBOT)
    monkeypatch.chdir(tmp_path)
    argv = ["--config-dir", "mine", "robot=box", "hydra.run.dir=out"]

    def mass(*extra):
        (job,) = plan([*argv, *extra]).jobs
        return job.cfg.robot.platform.mass

    assert (mass(), mass("load.mass=2"), len(calls)) == (3.0, 3.0, 1)
    stat = robot.stat()
    robot.write_text(ROBOT.replace("mass: 3.0", "mass: 5.0"))  # the same size
    os.utime(robot, ns=(stat.st_atime_ns, stat.st_mtime_ns))  # and time
    assert (mass(), len(calls)) == (5.0, 2)
    (robots / "other.yaml").write_text(ROBOT)
    assert (mass(), len(calls)) == (5.0, 3)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    argv[1] = str(tmp_path / "mine")
    planned = plan(argv)
    assert len(calls) == 4 and planned.record(planned.jobs[0]).hydra.runtime.cwd == str(elsewhere)


def test_a_sweep_of_robot_files_says_why_their_shared_keys_meet_the_default_robot(tmp_path):
    """'-m robot=a,b robot.search.step=0.5' named robot=cpr8, which the user never chose: Hydra
    checks a sweep's shared overrides against its own config (the default robot); the line says
    so and what to do."""
    import shutil
    from pathlib import Path

    from pipeline.app.plan import plan
    from pipeline.errors import ConfigError

    example = Path(__file__).resolve().parents[1] / "examples" / "my_robot" / "robot" / "myrobot.yaml"
    (tmp_path / "robot").mkdir()
    shutil.copy(example, tmp_path / "robot" / "a.yaml")
    shutil.copy(example, tmp_path / "robot" / "b.yaml")
    with pytest.raises(ConfigError, match=r"^robot.search.step=0.5: no such key for robot=cpr8 .*; the sweep of robot "
                                          r"shares these keys, .* set them in each robot file, or run one sweep per robot$"):
        plan(["--config-dir", str(tmp_path), "-m", "robot=a,b", "robot.search.step=0.5"])
    assert len(plan(["--config-dir", str(tmp_path), "-m", "robot=a,b", "tension.t_max=300",
                     f"hydra.sweep.dir={tmp_path / 'out'}"]).jobs) == 2  # keys every robot has are accepted
