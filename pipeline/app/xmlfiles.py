"""The user's XML files (CASPR's models and trajectories, WireX's robots): parsed, or refused in
one line. Outside data: only read, never run (no external entity or DTD is fetched)."""

from __future__ import annotations

import xml.etree.ElementTree as ElementTree
from pathlib import Path

from pipeline.errors import ConfigError


def parse_xml(path: Path) -> ElementTree.Element:
    """The root element of the XML file ``path``; ConfigError naming the file when it cannot be
    read or is not well-formed XML."""
    try:
        return ElementTree.parse(path).getroot()
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read ({exc.strerror or exc})") from None
    except ElementTree.ParseError as exc:
        raise ConfigError(f"{path}: not well-formed XML ({exc})") from None
