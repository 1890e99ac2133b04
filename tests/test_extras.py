"""The install by use (pyproject.toml's extras): the base install runs the jobs and the studies'
figures; the report, the optimise studies and the cluster launchers name the extra they need in
one line when it is missing (issue 53: the base install pulled optuna, sqlalchemy and plotly)."""

import sys
import tomllib
from pathlib import Path

import pytest

from conftest import command

ROOT = Path(__file__).resolve().parents[1]


def test_the_base_install_leaves_out_what_only_the_report_and_the_design_studies_use():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    base = " ".join(project["dependencies"])
    extras = project["optional-dependencies"]
    for name, extra in (("plotly", "report"), ("markdown-it-py", "report"), ("optuna", "design"),
                        ("hydra-submitit-launcher", "cluster")):
        assert name not in base and any(d.startswith(name) for d in extras[extra]), name
    assert "cdpr-studies[report,design]" in extras["test"]


def test_a_missing_extra_is_named_in_one_line(monkeypatch):
    from pipeline.errors import ConfigError, require

    monkeypatch.setitem(sys.modules, "optuna", None)  # import optuna raises ImportError
    with pytest.raises(ConfigError, match=r"^an optimise study needs optuna, which the base install leaves out: "
                                          r"pip install 'cdpr-studies\[design\]'$"):
        require("optuna", "design", "an optimise study")


def test_without_plotly_a_study_draws_its_figures_and_says_the_views_need_the_report_extra(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "plotly", None)
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "plotly" else real(name, *a))
    (tmp_path / "studies").mkdir()
    (tmp_path / "studies" / "c.yaml").write_text(
        "title: t\nsource: s\noverrides: [robot=irpm6, robot.search.step=2]\nsweep: {load.mass: '1'}\n"
        "figures:\n  - {kind: cloud, file: cloud.png}\n")
    done = command(tmp_path, "pipeline.study", "--config-dir", str(tmp_path), "--out", str(tmp_path / "out"), "c")
    assert done.returncode == 0, done.stderr[-2000:]
    figures = tmp_path / "out" / "c" / "figures"
    assert (figures / "cloud.png").is_file() and not (figures / "cloud.json").exists()
    assert "no interactive view beside cloud.png: plotly is not installed (pip install 'cdpr-studies[report]')" in done.stderr
    report = command(tmp_path, "pipeline.report", "--config-dir", str(tmp_path), "--studies", str(tmp_path / "out"),
                     "--out", str(tmp_path / "report"))
    lines = report.stderr.strip().splitlines()
    assert report.returncode == 2 and lines == ["error: the report needs plotly, which the base install leaves out: "
                                                "pip install 'cdpr-studies[report]'"], lines
    assert not (tmp_path / "report").exists()
