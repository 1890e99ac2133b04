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
