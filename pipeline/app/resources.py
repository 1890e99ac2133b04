"""Where the shipped configs and declared studies are: ``pipeline/conf`` and ``pipeline/studies``.

In the repository these are links to the top-level ``conf/`` and ``studies/`` folders; an
installed wheel carries copies of them (``pyproject.toml``, package data), so ``cdpr`` runs from
any folder, with or without a checkout.
"""

from __future__ import annotations

from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parents[1]  # pipeline/, above app/
CONF_DIR = PACKAGE_DIR / "conf"
STUDIES_DIR = PACKAGE_DIR / "studies"
