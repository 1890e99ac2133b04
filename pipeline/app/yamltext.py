"""A config's YAML text as ``OmegaConf.to_yaml`` writes it, emitted by libyaml.

``OmegaConf.to_yaml`` emits with PyYAML's pure-Python emitter; every job writes its config as
text three times (``.hydra/config.yaml``, ``hydra.yaml``, the summary's metadata), a large part
of a study's CPU. The same representation emitted by libyaml (PyYAML's C emitter, when PyYAML
was built with it) takes a fraction of the time for the same text: ``tests/test_yamltext.py``
compares both on the configs of the papers' robots, Hydra's node, strings YAML could misread and
random Unicode text. Where libyaml escapes a character PyYAML writes as it is (beyond U+FFFF,
and U+0085), and without libyaml, the text is OmegaConf's own.
"""

from __future__ import annotations

import yaml
from omegaconf import DictConfig, ListConfig, OmegaConf

# Strings YAML 1.1 reads as booleans: OmegaConf quotes them, as numbers, so they stay strings
YAML_BOOLS = frozenset({"y", "Y", "yes", "Yes", "YES", "n", "N", "no", "No", "NO", "true", "True",
                        "TRUE", "false", "False", "FALSE", "on", "On", "ON", "off", "Off", "OFF"})


def _reads_as_number(text: str) -> bool:
    for kind in (int, float):
        try:
            kind(text)
            return True
        except ValueError:
            pass
    return False


def _string(dumper: yaml.Dumper, text: str) -> yaml.ScalarNode:
    """OmegaConf's rule for a string: single-quoted when YAML would read a boolean or a number."""
    quoted = text in YAML_BOOLS or _reads_as_number(text)
    return dumper.represent_scalar(yaml.resolver.BaseResolver.DEFAULT_SCALAR_TAG, text,
                                   style="'" if quoted else None)


if yaml.__with_libyaml__:
    class _Dumper(yaml.CDumper):
        """libyaml's emitter with PyYAML's representer (OmegaConf's dumper: yaml.Dumper's)."""

    _Dumper.add_representer(str, _string)


def to_yaml(cfg: DictConfig | ListConfig, *, resolve: bool = False) -> str:
    """``OmegaConf.to_yaml(cfg, resolve=resolve)``, the same text, faster."""
    if not yaml.__with_libyaml__:
        return OmegaConf.to_yaml(cfg, resolve=resolve)
    container = OmegaConf.to_container(cfg, resolve=resolve, enum_to_str=True)
    text = yaml.dump(container, Dumper=_Dumper, default_flow_style=False, allow_unicode=True,
                     sort_keys=False)
    if "\\U" in text or "\\N" in text:  # libyaml escapes characters PyYAML writes as they are
        return OmegaConf.to_yaml(cfg, resolve=resolve)  # (beyond U+FFFF, U+0085)
    return text
