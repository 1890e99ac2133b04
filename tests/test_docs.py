"""The generated reference pages match what generates them, and the pages' examples run."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def test_docs_config_md_is_what_the_schemas_and_the_yaml_files_say():
    """docs/config.md is written by scripts/config_doc.py from pipeline/app/config.py and conf/:
    an edited schema, docstring or default without `python scripts/config_doc.py` fails here."""
    done = subprocess.run([sys.executable, str(ROOT / "scripts" / "config_doc.py"), "--check"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, "docs/config.md is stale: run python scripts/config_doc.py" + done.stderr[-2000:]
    text = (ROOT / "docs" / "config.md").read_text()
    for key in ("`wrench.fz` | float | `0.0` | default", "`tension.t_max=55000.0`", "`lines.samples` | first \\| all"):
        assert key in text


@pytest.mark.parametrize("page", ["README.md", "docs/api.md"])
def test_the_pages_python_examples_are_doctests_that_pass(tmp_path, monkeypatch, page):
    """The API examples of the README and docs/api.md run, in an empty folder, and print what the
    page says they print (an edited output, or a change of the numbers, fails here)."""
    import doctest

    monkeypatch.chdir(tmp_path)
    assert ">>> from pipeline import api" in (ROOT / page).read_text()
    failures, tried = doctest.testfile(str(ROOT / page), module_relative=False, report=True,
                                       optionflags=doctest.NORMALIZE_WHITESPACE)
    assert failures == 0 and tried >= 3, (failures, tried)
