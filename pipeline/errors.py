"""The one exception type for bad input: its message is the whole one-line error shown to users."""

from __future__ import annotations

import re

_NOISE = re.compile(r"^\s*(full_key|reference_type|object_type|object_type=).*$")


class ConfigError(ValueError):
    """A configuration or input file value that cannot be used; the message names key and value.
    It is one line whatever the value holds: a line break in a quoted value is shown as ``\\n``."""

    def __init__(self, message: str = "") -> None:
        super().__init__(str(message).replace("\r", "\\r").replace("\n", "\\n"))


def one_line(exc: BaseException) -> str:
    """Hydra/OmegaConf messages span several lines; keep the informative ones, joined, each once
    (a cause's text is often already part of the message that wraps it)."""
    parts = []
    while exc is not None:
        for line in str(exc).splitlines():
            line = line.strip()
            if line and not _NOISE.match(line) and not any(line in part for part in parts):
                parts.append(line)
        exc = exc.__cause__
    return ": ".join(parts)


def text_number(values) -> str:
    """'' or why a value that looks like a number is not one: YAML 1.1 (OmegaConf, PyYAML) reads
    ``-.5``, ``.5e3`` and ``1e3`` as text; the hint says how to write it."""
    for value in values if isinstance(values, (list, tuple)) else [values]:
        if isinstance(value, str):
            try:
                number = float(value)
            except ValueError:
                continue
            return f" ({value!r} is text to YAML: write {number!r})"
    return ""


def require(module: str, extra: str, what: str):
    """The module ``module``, or ConfigError naming the extra that installs it: ``what`` (the
    feature, e.g. "the report") needs ``pip install 'cdpr-studies[extra]'`` (pyproject.toml's
    optional dependencies, by use)."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError:
        raise ConfigError(f"{what} needs {module.split('.')[0]}, which the base install leaves out: "
                          f"pip install 'cdpr-studies[{extra}]'") from None
