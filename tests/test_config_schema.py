"""One source of each default: the schemas of pipeline/app/config.py declare types and value
rules, the YAML files of conf/ every value (a default written twice had drifted: wrench.fz was
100 000 N in the schema, 0 in conf/config.yaml)."""

import dataclasses
import itertools

import pytest
from omegaconf import MISSING, OmegaConf

from pipeline.app import config
from pipeline.app.config import Config
from pipeline.app.problem import ROBOTS, typed_config


def schemas(root):
    """``root`` and every dataclass nested in it."""
    found = [root]
    for item in dataclasses.fields(root):
        if item.default_factory is not dataclasses.MISSING and dataclasses.is_dataclass(item.default_factory):
            found += schemas(item.default_factory)
    return found


@pytest.mark.parametrize("root", [Config, *(kind.schema for kind in ROBOTS.values())], ids=lambda s: s.__name__)
def test_no_schema_field_declares_a_value(root):
    for schema in schemas(root):
        for item in dataclasses.fields(schema):
            nested = item.default_factory is not dataclasses.MISSING and dataclasses.is_dataclass(item.default_factory)
            assert nested or (item.default is MISSING and item.default_factory is dataclasses.MISSING), (
                f"{schema.__name__}.{item.name}")


COMBINATIONS = list(itertools.product(["cpr8", "irpm6", "points"], ["cpr_wwa", "statics", "lines"],
                                      ["pinv", "feasible"]))
POINTS_INPUT = {"robot.anchors", "robot.attachments"}  # the search box is null: not needed with poses=[...]


@pytest.mark.parametrize("robot, analysis, tension", COMBINATIONS)
def test_every_key_of_every_combination_gets_its_value_from_the_yaml(robot, analysis, tension):
    """Composed and typed, a job's config has a value at every key it keeps; the only keys left
    to the user are the points of ``robot=points`` (``???`` in conf/robot/points.yaml)."""
    from hydra import compose, initialize_config_dir

    from pipeline.app.resources import CONF_DIR

    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        composed = compose(config_name="config", overrides=[f"robot={robot}", f"analysis={analysis}",
                                                            f"tension={tension}"])
    missing = OmegaConf.missing_keys(composed)
    assert missing == (POINTS_INPUT if robot == "points" else set())
    if robot != "points":
        typed = typed_config(composed)
        assert not OmegaConf.missing_keys(typed)
        assert typed.keys() == composed.keys()


def test_the_rule_helper_declares_no_default():
    assert config.rule(config.positive).default is MISSING


@pytest.mark.parametrize("robot, model", [("cpr8", "pinv"), ("irpm6", "pinv"), ("points", "feasible")])
def test_a_users_robot_checks_cables_that_only_pull_by_default(robot, model):
    """The papers' robots keep their papers' minimum-norm forces; a robot given by its points
    (and every file built on it: your own, an imported CASPR model) checks pulling cables: with
    more cables than freedoms the minimum-norm forces are rarely all positive (0 % feasible)."""
    from hydra import compose, initialize_config_dir

    from pipeline.app.resources import CONF_DIR

    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        assert compose(config_name="config", overrides=[f"robot={robot}"]).tension.model == model
        assert compose(config_name="config", overrides=[f"robot={robot}", "tension=pinv"]).tension.model == "pinv"


def test_every_robot_kind_extends_the_one_base_schema_and_its_file_does_not_repeat_it():
    """What every robot has is declared once: RobotConfig (platform, cable diameter, longest
    cable, pulleys, elastic cables), with its values in conf/config.yaml's robot node; the robot kinds' schemas extend it
    and their files set only what differs (the CPR-8's 2 kg carrier, the IRPM's 15 m cables)."""
    import yaml

    from pipeline.app.resources import CONF_DIR

    base = {item.name for item in dataclasses.fields(config.RobotConfig)}
    assert base == {"name", "platform", "cable_diameter", "l_max", "pulleys", "cable_ea", "winch_length", "cable_mass",
                    "catenary"}
    root = yaml.safe_load((CONF_DIR / "config.yaml").read_text())["robot"]
    assert set(root) == base - {"name"}
    for name, kind in ROBOTS.items():
        assert issubclass(kind.schema, config.RobotConfig), name
        own = yaml.safe_load((CONF_DIR / "robot" / f"{name}.yaml").read_text())["robot"]
        repeated = {key for key in own if key in root and own[key] == root[key]}
        assert not repeated, (name, repeated)


def test_the_base_keys_reach_a_robot_that_had_none_the_cpr8s_longest_cable(make_cfg, catalogue):
    """``robot.l_max`` was the IRPM's and the points robot's; as a base key the CPR-8 takes it:
    its length criterion removes exactly the poses whose longest cable exceeds it."""
    import numpy as np

    from conftest import compute_workspace
    from pipeline.app.problem import build_problem

    cfg = make_cfg("robot.l_max=2.4")
    problem, grid = build_problem(cfg, catalogue)
    assert "length" in problem.criteria and "length" not in build_problem(make_cfg(), catalogue)[0].criteria
    points, summary = compute_workspace(cfg, catalogue)
    longest = np.linalg.norm(grid[:][:, None, :] + problem.robot.attachments - problem.robot.anchors, axis=2).max(axis=1)
    assert 0 < (longest > 2.4).sum() < len(longest) and not points.loc[longest > 2.4 + 1e-9, "feasible"].any()
    np.testing.assert_allclose(points["margin_length"], 1 - longest / 2.4, atol=1e-12)
