"""The Python API (pipeline.api, docs/api.md): the command line's jobs in a notebook, the same
numbers, the same one-line errors as exceptions, no global side effects."""

import pathlib
import re
import subprocess
import sys

import pandas as pd
import pytest

from conftest import command

from pipeline import api
from pipeline.app.results import file_digest

def test_importing_the_api_keeps_the_notebook_backend_and_logging():
    """A notebook's pyplot backend and logging handlers are not touched by the import."""
    code = ("import logging, matplotlib; matplotlib.use('svg'); import pipeline.api, pipeline.analyses.figures; "
            "assert matplotlib.get_backend() == 'svg', matplotlib.get_backend(); "
            "assert not logging.getLogger().handlers, logging.getLogger().handlers")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr


def test_workspace_gives_table_2_and_the_command_line_points(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    ws = api.workspace(["actuator=3"], folder="a3")
    assert ws.folder == pathlib.Path("a3")
    assert (ws.summary["n_feasible"], ws.summary["n_points"]) == (184, 216)  # Table 2: 85.19 %
    assert ws.points["feasible"].sum() == 184 and len(ws.points) == 216
    assert "actuator: 3" in ws.config and ws.version.startswith("0.")
    cli = command(tmp_path, "pipeline", "actuator=3", "hydra.run.dir=cli")
    assert cli.returncode == 0, cli.stderr
    pd.testing.assert_frame_equal(pd.read_parquet("cli/points.parquet"), ws.points)
    before = file_digest(pathlib.Path("a3/points.parquet")), (tmp_path / "a3/points.parquet").stat().st_mtime_ns
    again = api.workspace(["actuator=3"], folder="a3")  # finished: reused, not rewritten
    assert again.summary == ws.summary
    assert (file_digest(pathlib.Path("a3/points.parquet")),
            (tmp_path / "a3/points.parquet").stat().st_mtime_ns) == before


def test_a_folder_name_may_hold_the_override_grammars_characters(tmp_path, monkeypatch):
    """The folder goes to Hydra quoted (pipeline.app.plan.quoted): =, commas, quotes, spaces."""
    monkeypatch.chdir(tmp_path)
    for name in ("grid=centred,n=6", "it's here", "trailing\\"):
        ws = api.workspace(["actuator=1"], folder=name)
        assert ws.folder == pathlib.Path(name) and (tmp_path / name / "points.parquet").exists()
    choice = api.actuator_choice(folder="a=b,c")
    assert sorted(p.name for p in (tmp_path / "a=b,c").iterdir())[:2] == ["actuator=1", "actuator=2"]
    assert choice.verdict.startswith("actuator choice at x >= 90 %: accept 1, 2")


def test_actuator_choice_on_the_users_catalogue(tmp_path, monkeypatch):
    """Table 1 plus a 6th, weaker motor (actuator 5 with half its torque): one job per id."""
    monkeypatch.chdir(tmp_path)
    table = pd.read_csv(pathlib.Path(api.__file__).parent / "data" / "actuators_table1.csv")
    weak = table[table["id"] == 5].copy()
    weak["id"], weak["name"], weak["torque_Nm"] = 6, "half actuator 5", weak["torque_Nm"] / 2
    pd.concat([table, weak]).to_csv("mine.csv", index=False)
    choice = api.actuator_choice(["catalogue=mine.csv", "choice.required_pct=85"], folder="choice")
    assert sorted(choice.workspaces) == [1, 2, 3, 4, 5, 6]
    accepted = choice.table.set_index("actuator")["accepted"]
    assert accepted.to_dict() == {1: True, 2: True, 3: True, 4: True, 5: False, 6: False}
    share = choice.table.set_index("actuator")["feasible_pct"]
    assert share[6] <= share[5]  # less torque never reaches more of the grid
    assert choice.verdict.startswith("actuator choice at x >= 85 %: accept 1, 2, 3, 4; reject 5 ")
    assert sorted(p.name for p in pathlib.Path("choice").iterdir() if p.is_dir()) == [f"actuator={i}" for i in range(1, 7)]
    assert (pathlib.Path("choice") / "multirun.yaml").is_file()  # run as the command line runs a sweep
    assert (pathlib.Path("choice") / "actuator=6" / ".hydra" / "overrides.yaml").is_file()
    assert pd.read_parquet(pathlib.Path("choice") / "summary.parquet")["actuator"].tolist() == [1, 2, 3, 4, 5, 6]


def test_actuator_choice_on_a_catalogue_without_id_1(tmp_path, monkeypatch):
    """A user's catalogue numbers its motors as it likes: the choice checks its first id, not
    Table 1's default actuator 1 (which refused such a catalogue)."""
    monkeypatch.chdir(tmp_path)
    table = pd.read_csv(pathlib.Path(api.__file__).parent / "data" / "actuators_table1.csv")
    table.iloc[[4, 0]].assign(id=[50, 10]).to_csv("mine.csv", index=False)
    choice = api.actuator_choice(["catalogue=mine.csv"], folder="choice")
    assert choice.table.set_index("actuator")["accepted"].to_dict() == {10: True, 50: False}
    assert sorted(choice.workspaces) == [10, 50]


@pytest.mark.parametrize("call, overrides, message", [
    ("workspace", ["actuator=9"], "actuator=9: no such id in the catalogue"),
    ("workspace", ["orientation.psi=nan"], "orientation.psi=nan: must be finite"),
    ("workspace", ["-m", "actuator=1,2"], "-m: the API takes key=value overrides only"),
    ("workspace", ["grid.nn=3"], "grid.nn"),
    ("workspace", ["robot=nosuch"], "robot=nosuch: no such option of the robot group"),
    ("actuator_choice", ["actuator=2"], "actuator=...: the choice runs every actuator"),
    ("actuator_choice", ["analysis=payload"], "actuator=1: analysis=payload finds the largest payload"),
    ("actuator_choice", ["catalogue=missing.csv"], "catalogue=missing.csv"),
])
def test_bad_input_raises_config_error_and_writes_nothing(tmp_path, monkeypatch, call, overrides, message):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(api.ConfigError, match=re.escape(message)):
        getattr(api, call)(overrides, folder="out")
    assert list(tmp_path.iterdir()) == []


def test_load_study_reads_a_finished_study_or_says_how_to_make_it(tmp_path):
    with pytest.raises(api.ConfigError, match="study actuator_choice: no results in .*cdpr-study actuator_choice"):
        api.load_study("actuator_choice", out_root=tmp_path)
    for name in ("../../etc", "/tmp", "actuator_choice/.."):  # a declared study, never a path
        with pytest.raises(api.ConfigError, match="not found"):
            api.load_study(name, out_root=tmp_path)
    from pipeline.study import main

    main(["actuator_choice", "--out", str(tmp_path), "--launcher", "serial"])
    results = api.load_study("actuator_choice", out_root=tmp_path)
    choice = results.table("choice")
    assert sorted(choice.loc[choice["accepted"], "actuator"]) == [1, 2]
    csv = pd.read_csv(tmp_path / "actuator_choice" / "choice.csv")  # the spreadsheet copy
    pd.testing.assert_frame_equal(csv[["actuator", "feasible_pct", "accepted"]],
                                  choice[["actuator", "feasible_pct", "accepted"]])
    assert len(results.points("actuator=5")) == 216


def test_two_threads_may_call_the_api_at_once(tmp_path, monkeypatch):
    """Hydra's compose API keeps one global state per process: two notebook threads checking
    their jobs at once used to fail with "GlobalHydra is already initialized"."""
    from concurrent.futures import ThreadPoolExecutor

    monkeypatch.chdir(tmp_path)
    with ThreadPoolExecutor(2) as pool:
        done = list(pool.map(lambda a: api.workspace([f"actuator={a}", "grid.n=3"], folder=f"a{a}"), [1, 2, 3, 4] * 2))
    assert [ws.summary["n_feasible"] for ws in done[:4]] == [27, 25, 22, 22]
    assert [ws.summary for ws in done[4:]] == [ws.summary for ws in done[:4]]


def test_a_workspace_draws_itself_with_the_studies_figure_code(tmp_path, monkeypatch):
    """Issue 53: the API had no picture. A job's cloud (with its 3-D view, whose feasible set is
    the job's), slices and map come from the studies' code; what cannot draw one job is one line."""
    import json

    monkeypatch.chdir(tmp_path)
    ws = api.workspace(["actuator=3"], folder="a3")
    (cloud,) = ws.figure()
    assert cloud == pathlib.Path("a3/figures/cloud.png") and cloud.stat().st_size > 10_000
    view = json.loads(cloud.with_suffix(".json").read_text())
    assert any(t["name"] == "feasible set (184)" for t in view["data"])  # Table 2: 184 of 216
    slices = ws.figure("slices", out=tmp_path / "mine", axis="x", layers=2)
    assert [p.name for p in slices if p.suffix == ".png"] == ["slices.png"]
    for kind, keys, message in [("curve", {}, "kind='curve': a job draws as a cloud, slices, map, path, path_view or paving"),
                                ("slices", {"axis": "w"}, "figure: axis='w': slices cut across x, y or z"),
                                ("map", {}, "a map colours the poses by a points column"),
                                ("slices", {"colour": "red"}, "unexpected keyword argument 'colour'")]:
        with pytest.raises(api.ConfigError, match=re.escape(message)):
            ws.figure(kind, **keys)
