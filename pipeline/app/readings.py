"""The readings of a job: the ``model.*`` switches (docs/evidence.md, sections 1-2) by name and in
words, for its log line, the report and the evidence studies."""

from __future__ import annotations

import functools

from omegaconf import OmegaConf

from pipeline.app.resources import CONF_DIR

SETTINGS = ("rank_rtol", "margin_atol")  # model.* keys that are tolerances, not readings


def reading_name(switches: dict) -> str:
    """``default``, or the switches that differ from the defaults (``pinv_columns=full``)."""
    defaults = default_readings()
    differ = [f"{key[6:]}={_text(value)}" for key, value in switches.items()
              if _text(value) != defaults.get(key)]
    return ", ".join(differ) or "default"


@functools.cache
def default_readings() -> dict[str, str]:
    """``model.<switch>`` -> its default, as text, from the analysis files of ``conf/`` (the one
    place defaults live: CPR-WWA's readings in cpr_wwa.yaml, the IRPM's in statics.yaml)."""
    readings = {}
    for path in sorted((CONF_DIR / "analysis").glob("*.yaml")):
        for key, value in (OmegaConf.load(path).get("model") or {}).items():
            readings[f"model.{key}"] = _text(value)
    return readings


def describe_reading(model) -> str:
    """A job's readings in one line: ``default`` or the switches that differ, then every switch
    it has (``default: pinv_columns=full, ..., xi_in_torque_limit=true``)."""
    switches = {f"model.{key}": value for key, value in model.items() if key not in SETTINGS}
    return f"{reading_name(switches)}: " + ", ".join(f"{key[6:]}={_text(v)}" for key, v in switches.items())


def _text(value) -> str:
    return str(getattr(value, "value", value)).lower()
