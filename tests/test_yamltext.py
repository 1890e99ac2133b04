"""pipeline.app.yamltext.to_yaml writes OmegaConf.to_yaml's text, byte for byte: emitted by
libyaml where PyYAML has it (its PyPI wheels do), by OmegaConf itself where it does not."""

import random

import pytest
from hydra import compose, initialize_config_dir
from omegaconf import OmegaConf

from pipeline.app.config import register
from pipeline.app.resources import CONF_DIR
from pipeline.app.yamltext import to_yaml

TRICKY = ["yes", "No", "on", "OFF", "y", "1e3", "1_000", "0x10", "inf", "-inf", "nan", ".nan", ".inf",
          "", "null", "~", "Null", "a: b", "#x", "x #y", " lead", "trail ", "multi\nline\n", "tab\there",
          "µ and é", "雪", "emoji 🙂", "-", "'", '"', "'quoted'", "{a: 1}", "[1, 2]", "*ref", "&anchor",
          "!tag", "%", "@", "`", "10:30", "2026-11-24", "1.5e-300", "+1", "007", "=", "a=b,c",
          "x" * 200, "word " * 40, "\\back\\slash", "\x07bell", "\u2028sep"]


@pytest.mark.parametrize("overrides", [
    [], ["robot=irpm6"], ["robot=points"], ["analysis=lines"], ["analysis=statics"],
    ["tension=feasible"], ["robot=irpm6", "tension=feasible", "wrench.fx=-1e-300"],
    ["catalogue='/tmp/my motors é.csv'", "load.com=[0,0,0.5]", "poses=[[0,0,1],[1,2,3]]"],
])
def test_composed_configs_and_hydra_s_node(overrides):
    register()
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        cfg = compose(config_name="config", overrides=overrides, return_hydra_config=True)
    for node in (cfg, cfg.hydra, cfg.hydra.help, cfg.hydra.overrides):
        assert to_yaml(node) == OmegaConf.to_yaml(node)
    task = OmegaConf.masked_copy(cfg, [key for key in cfg if key != "hydra"])
    assert to_yaml(task, resolve=True) == OmegaConf.to_yaml(task, resolve=True)


def test_strings_yaml_could_misread_and_other_scalars():
    cfg = OmegaConf.create({"strings": TRICKY, "by_key": {text or "empty": text for text in TRICKY[:30]},
                            "numbers": [0, -1, 2**63 - 1, 1.0, -0.0, 1e-300, 1.5e300, float("inf"),
                                        float("nan")],
                            "flags": [True, False, None], "nested": {"a": [{"b": [[]]}, {}], "c": {}}})
    assert to_yaml(cfg) == OmegaConf.to_yaml(cfg)
    assert to_yaml(cfg.strings) == OmegaConf.to_yaml(cfg.strings)
    interpolated = OmegaConf.create({"a": 1, "b": "${a}", "c": "x ${a} y"})
    assert to_yaml(interpolated) == OmegaConf.to_yaml(interpolated)
    assert to_yaml(interpolated, resolve=True) == OmegaConf.to_yaml(interpolated, resolve=True)


def test_random_unicode_text():
    """Characters from every plane: where libyaml would escape one that PyYAML writes as it is,
    OmegaConf writes the text."""
    rng = random.Random(11)
    planes = [(0x20, 0x7E), (0x00, 0x1F), (0x80, 0x2FF), (0x2000, 0x206F), (0xD7F0, 0xD7FF),
              (0xE000, 0xE0FF), (0xFFF0, 0xFFFF), (0x1F300, 0x1F64F), (0x10FFF0, 0x10FFFF)]
    for _ in range(300):
        text = "".join(chr(rng.randint(*rng.choice(planes))) for _ in range(rng.randint(1, 12)))
        if 0xD800 <= max(map(ord, text)) <= 0xDFFF:
            continue
        cfg = OmegaConf.create({"value": text, "list": [text, "x"], "nested": {"k": text}})
        assert to_yaml(cfg) == OmegaConf.to_yaml(cfg), repr(text)
