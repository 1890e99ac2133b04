"""``cdpr --help [group=option ...]``: the choices of each config group and every key of that
composition with its value, under the meaning and units its schema declares (the docstrings
of the dataclasses in ``pipeline/app/config.py``), so the page cannot drift from what is checked.
Hydra's own page stays available as ``--hydra-help``.
"""

from __future__ import annotations

import re
import textwrap
from dataclasses import fields, is_dataclass

from omegaconf import DictConfig, OmegaConf

from pipeline.app.config import Config
from pipeline.app.problem import ROBOTS
from pipeline.app.resources import CONF_DIR

GROUPS = ("robot", "analysis", "tension")
WIDTH = 100


def page(overrides: list[str], typed: DictConfig, version: str) -> str:
    """The help text for the composition ``typed`` (a job's typed config) of ``overrides``."""
    chosen = " ".join(overrides) or "the defaults"
    lines = [
        f"cdpr (cdpr-studies {version}): the feasible workspace of a cable robot and the "
        "catalogue actuator to buy.",
        "",
        "usage: cdpr [-m] [key=value | group=option ...]   (also: python -m pipeline ...)",
        "       cdpr --help [group=option ...]              this page for that composition",
        "       cdpr --cfg job | --version | --hydra-help",
        "  -m runs a sweep: comma-separated values, e.g. cdpr -m actuator=1,2,3,4,5",
        "",
        "choices (group=option):",
    ]
    for group in GROUPS:
        options = sorted(p.stem for p in (CONF_DIR / group).glob("*.yaml"))
        extra = " (or your own robot/NAME.yaml with --config-dir DIR)" if group == "robot" else ""
        lines.append(f"  {group}: {', '.join(options)}{extra}")
    lines += ["", f"keys of this composition ({chosen}); key = value, under what they mean:"]
    plain = [name for name in typed if name != "robot" and _field_schema(Config, name) is None]
    lines += _section("job", OmegaConf.create({k: typed[k] for k in plain}), Config, prefix="")
    for name in typed:
        if name not in plain:
            schema = ROBOTS[typed.robot.name].schema if name == "robot" else _field_schema(Config, name)
            lines += _section(name, typed[name], schema)
    lines += ["", "docs: docs/config.md (every key with its type and value), docs/model.md (the model), "
              "docs/evidence.md (the readings), docs/api.md (Python)."]
    return "\n".join(lines) + "\n"


def _section(key: str, value, schema, prefix: str | None = None) -> list[str]:
    """The keys under ``key`` (one line each) below the schema's docstring."""
    lines = [""]
    doc = re.sub(r":\w+:|``", "", " ".join((schema.__doc__ or "").split()))  # reST markup
    if doc and not doc.startswith(schema.__name__ + "("):  # a dataclass without its own docstring
        lines += textwrap.wrap(f"{key}: {doc}", WIDTH, subsequent_indent="    ")
    for path, leaf in _leaves(key if prefix is None else prefix, value):
        lines.append(f"  {path} = {_shown(leaf)}")
    return lines


def _leaves(prefix: str, value):
    if isinstance(value, DictConfig):
        for key in value:
            yield from _leaves(f"{prefix}.{key}" if prefix else str(key), value[key])
    else:
        yield prefix, value


def _shown(value) -> str:
    if hasattr(value, "name") and hasattr(value, "value"):  # an enum option
        return value.name
    plain = OmegaConf.to_container(value) if OmegaConf.is_config(value) else value
    if isinstance(plain, bool):
        return str(plain).lower()
    return "null" if plain is None else str(plain).replace("'", "")


def _field_schema(schema, name: str):
    """The dataclass a field of ``schema`` holds, or None for a plain value."""
    for item in fields(schema):
        if item.name == name and callable(item.default_factory):
            default = item.default_factory()
            return type(default) if is_dataclass(default) else None
    return None
