"""Shared fixtures: configs composed from the real conf/ directory, as the command line does."""

from __future__ import annotations

import pytest
from hydra import compose, initialize_config_dir

from pipeline.model.catalogue import load_catalogue
from pipeline.app.config import register, typed_config
from pipeline.app.resources import CONF_DIR

register()


@pytest.fixture(scope="session")
def catalogue():
    return load_catalogue()


@pytest.fixture(scope="session")
def make_cfg():
    """make_cfg(*overrides) -> the composed, typed config a job sees (serial compute for
    in-process tests)."""

    def _make(*overrides: str):
        with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
            return typed_config(compose(config_name="config", overrides=["compute.n_jobs=1", *overrides]))

    return _make
