"""Declared studies through their command line: `python -m pipeline.study NAME`."""

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from conftest import command
from pipeline.model.catalogue import load_catalogue
from pipeline.errors import ConfigError
from pipeline.app.results import read_metadata, write_parquet
from pipeline.study import StudySpec, available, checked_commands, load_study, run_study

pytestmark = pytest.mark.slow


def study(cwd, *args):
    """``python -m pipeline.study ARGS`` in ``cwd``, in this process (tests/conftest.py)."""
    return command(cwd, "pipeline.study", *args)


def study_process(cwd, *args):
    """The same in a process of its own: what only a process shows (studies run two at a time)."""
    return subprocess.run([sys.executable, "-m", "pipeline.study", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def choice_run(tmp_path_factory):
    cwd = tmp_path_factory.mktemp("choice")
    proc = study_process(cwd, "actuator_choice")  # the study command end to end, once
    assert proc.returncode == 0, proc.stderr
    return cwd / "outputs" / "studies" / "actuator_choice"


def test_choice_command_accepts_actuators_1_and_2_and_draws_every_figure(choice_run):
    choice = pd.read_parquet(choice_run / "choice.parquet")
    assert sorted(choice.loc[choice["accepted"], "actuator"]) == [1, 2]
    assert (choice[[c for c in choice if c.startswith("lost_") and not c.endswith("_pct")]]
            .sum(axis=1) == choice["n_points"] - choice["n_feasible"]).all()
    figures = sorted(p.name for p in (choice_run / "figures").iterdir())
    assert figures == sorted(
        ["fig9_feasible_share_by_actuator.png", "limiting_constraints_by_actuator.png"]
        + [f"fig8_workspace_actuator{a}.{kind}" for a in range(1, 6) for kind in ("png", "json")]
        + ["fig8_slices_actuator3.png", "fig8_slices_actuator4.png"]
    )  # each workspace picture with its interactive view (pipeline/analyses/views.py)
    from pipeline.analyses.figures import caption

    assert caption(choice_run / "figures" / "fig8_workspace_actuator5.png").endswith(
        "0 of 216 points are feasible.")  # the study's caption, filled from the job


def test_the_slices_show_each_layers_least_margin_and_where_the_workspace_ends(choice_run):
    """Actuator 4: four sections across z (both ends of the six levels and two between), each
    cell the least of the job's margins, clipped to +-1; the top layer holds its 32 lost poses."""
    series = pd.read_csv(choice_run / "series" / "fig8_slices_actuator4.csv")
    (job,) = [p for p in (choice_run / "jobs").iterdir() if p.name == "actuator=4"]
    points = pd.read_parquet(job / "points.parquet")
    levels = np.sort(points["z"].unique())
    assert np.allclose(np.sort(series["z"].unique()), levels[[0, 2, 3, 5]])
    merged = series.merge(points.round({"x": 9, "y": 9, "z": 9}).assign(
        least=points.filter(like="margin_").min(axis=1).clip(-1, 1)), on=["x", "y", "z"])
    assert len(merged) == len(series) == 4 * 36
    assert np.allclose(merged["least_margin"], merged["least"], atol=1e-9)
    top = merged[np.isclose(merged["z"], levels[-1])]
    assert ((top["least_margin"] < 0) == ~top["feasible"]).all() and (~top["feasible"]).sum() == 32


def test_figures_are_drawn_from_the_parquet_results(choice_run, monkeypatch):
    """Block the kernel, redraw from Parquet: identical bytes; the summary rewritten by the
    project's writer: the figure follows; edited by another tool (no digest of its new rows) or
    a job file changed: refused in one line, the figures kept."""
    import pipeline.workspace.compute

    def blocked(*args, **kwargs):
        raise AssertionError("figures must not recompute the workspace")

    # the name every workspace computation calls its kernel by (grid_workspace's own binding)
    monkeypatch.setattr(pipeline.workspace.compute, "evaluate_chunk", blocked)
    figures = choice_run / "figures"
    before = {p.name: p.read_bytes() for p in figures.iterdir()}
    out_root = choice_run.parent
    run_study("actuator_choice", [], out_root, figures_only=True)
    assert {p.name: p.read_bytes() for p in figures.iterdir()} == before

    summary_path = choice_run / "summary.parquet"
    summary, written = pd.read_parquet(summary_path), summary_path.read_bytes()
    edited = summary.copy()
    edited.loc[edited["actuator"] == 3, "feasible_pct"] = 42.0
    edited.to_parquet(summary_path)  # pandas' writer: its rows carry no digest
    with pytest.raises(ConfigError, match="summary.parquet: .*not a readable Parquet file of this study"):
        run_study("actuator_choice", [], out_root, figures_only=True)
    assert {p.name: p.read_bytes() for p in figures.iterdir()} == before
    write_parquet(edited, summary_path, read_metadata(choice_run / "choice.parquet")["cdpr.config"])
    points_path = choice_run / "jobs" / "actuator=4" / "points.parquet"
    points, finished = pd.read_parquet(points_path), points_path.read_bytes()
    try:
        run_study("actuator_choice", [], out_root, figures_only=True)
        after = {p.name: p.read_bytes() for p in figures.iterdir()}
        assert pd.read_parquet(choice_run / "choice.parquet").set_index("actuator").loc[
            3, "feasible_pct"] == 42.0
        changed = {name for name in before if after[name] != before[name]}
        assert changed == {"fig9_feasible_share_by_actuator.png", "limiting_constraints_by_actuator.png"}
        points.assign(feasible=True).to_parquet(points_path)  # a job file no longer as it finished
        with pytest.raises(ConfigError, match="actuator=4: points.parquet changed since the job finished"):
            run_study("actuator_choice", [], out_root, figures_only=True)
        assert {p.name: p.read_bytes() for p in figures.iterdir()} == after
    finally:
        summary_path.write_bytes(written)
        points_path.write_bytes(finished)


def test_user_catalogue_of_20_synthetic_actuators(choice_run):
    table1 = load_catalogue().table().reset_index()
    rng = np.random.default_rng(7)
    rows = table1.iloc[np.arange(20) % 5].copy()
    for column in ("torque_Nm", "speed_rpm", "resistance_ohm", "inertia_g_cm2", "gear_ratio"):
        rows[column] = rows[column].to_numpy() * rng.uniform(0.7, 1.3, 20)
    rows["id"] = np.arange(101, 121)
    rows["name"] = [f"synthetic {i}" for i in rows["id"]]
    cwd = choice_run.parents[2]  # beside the paper's reproduction, which must stay as it is
    before = {str(p.relative_to(choice_run)): p.read_bytes() for p in choice_run.rglob("*.parquet")}
    rows.to_csv(cwd / "motors.csv", index=False)
    proc = study(cwd, "actuator_choice", "catalogue=motors.csv")
    assert proc.returncode == 0, proc.stderr
    out = cwd / "outputs" / "studies" / "actuator_choice+catalogue=motors.csv"
    assert {str(p.relative_to(choice_run)): p.read_bytes() for p in choice_run.rglob("*.parquet")} == before
    assert "catalogue=motors.csv" in (out / "study.yaml").read_text()
    choice = pd.read_parquet(out / "choice.parquet")
    assert sorted(choice["actuator"]) == list(range(101, 121))
    assert (choice["accepted"] == (choice["feasible_pct"] >= 90.0)).all()
    assert choice["feasible_pct"].is_monotonic_decreasing
    assert len(list((out / "figures").glob("fig8_workspace_actuator*.png"))) == 20


@pytest.mark.parametrize(
    "edit, expected",
    [
        (lambda t: t.drop(columns="efficiency"), "missing column(s) efficiency"),
        (lambda t: t.assign(inertia_g_cm2=t["inertia_g_cm2"].where(t["id"] != 3, -181)),
         "row 4, column inertia_g_cm2: -181 must be >= 0.001 and at most 1e+12"),
        (lambda t: t.astype({"resistance_ohm": str}).assign(
            resistance_ohm=lambda d: d["resistance_ohm"].where(d["id"] != 2, "1.1 ohm")),
         "row 3, column resistance_ohm: '1.1 ohm' is not a number"),
        (lambda t: t.assign(id=[1, 2, 3, 3, 5]), "row 5, column id: duplicate id 3"),
    ],
)
def test_malformed_catalogue_fails_before_any_computation(tmp_path, edit, expected):
    edit(load_catalogue().table().reset_index()).to_csv(tmp_path / "bad.csv", index=False)
    proc = study(tmp_path, "actuator_choice", "catalogue=bad.csv")
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [f"error: catalogue=bad.csv: {expected}"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.csv"]


def test_unknown_study_and_unknown_key_in_a_study_file(tmp_path):
    proc = study(tmp_path, "no_such_study")
    assert proc.returncode == 2 and "study 'no_such_study' not found" in proc.stderr
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "typo.yaml").write_text("title: t\nsource: s\nfigures:\n  - {kind: curve, file: a.png, colour: red}\n")
    with pytest.raises(ConfigError, match="colour"):
        load_study("typo", tmp_path)
    (tmp_path / "kind.yaml").write_text("title: t\nsource: s\nfigures:\n  - {kind: pie, file: a.png}\n")
    with pytest.raises(ConfigError, match="unknown kind 'pie'"):
        load_study("kind", tmp_path)


def test_every_declared_study_parses():
    for name in available():
        assert isinstance(load_study(name), StudySpec)


def test_every_case_has_words_for_a_reader_and_a_label_names_a_case(tmp_path):
    """Case names are folder names (``rot05``); titles, captions and tables use the labels."""
    for name in available():
        spec = load_study(name)
        assert sorted(spec.case_labels) == sorted(spec.cases), name
    (tmp_path / "label.yaml").write_text(
        "title: t\nsource: s\ncases: {zero: []}\ncase_labels: {rot05: 'ψ = 0.5 rad'}\n")
    with pytest.raises(ConfigError, match="case_labels: 'rot05' is not a case \\(cases: zero\\)"):
        load_study("label", tmp_path)


def test_a_folder_holding_another_configuration_is_not_replaced_without_force(tmp_path):
    first = study(tmp_path, "design_mass", "--out", "mine", "choice.required_pct=80")
    assert first.returncode == 0, first.stderr
    summary = (tmp_path / "mine" / "design_mass" / "summary.parquet").read_bytes()
    refused = study(tmp_path, "design_mass", "--out", "mine")
    assert refused.returncode == 2 and refused.stderr.strip().splitlines() == [
        "error: mine/design_mass: holds study design_mass with overrides "
        "['choice.required_pct=80']; --force replaces them, --out DIR writes elsewhere"]
    assert (tmp_path / "mine" / "design_mass" / "summary.parquet").read_bytes() == summary
    forced = study(tmp_path, "design_mass", "--out", "mine", "--force")
    assert forced.returncode == 0, forced.stderr
    assert "extra_overrides: []" in (tmp_path / "mine" / "design_mass" / "study.yaml").read_text()


def test_a_study_is_a_declared_name_and_cannot_set_hydra_callbacks(tmp_path):
    """A path is not a study (it could point at any YAML file), and a study file may not set
    Hydra's own settings: a callback or plugin there would run code from a data file."""
    (tmp_path / "evil.yaml").write_text(
        "title: t\nsource: s\noverrides: ['+hydra.callbacks.x._target_=os.system']\n")
    proc = study(tmp_path, str(tmp_path / "evil"))
    assert proc.returncode == 2 and "not found (available: " in proc.stderr
    proc = study(tmp_path, "../" * 8 + str(tmp_path / "evil").lstrip("/"))
    assert proc.returncode == 2 and "not found (available: " in proc.stderr
    with pytest.raises(ConfigError, match="hydra.callbacks.x._target_: a study file may not set Hydra"):
        load_study("evil", tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["evil.yaml"]


def test_a_study_that_reads_points_refuses_a_summary_only_run():
    with pytest.raises(ConfigError, match=r"^output.points=false: study tension_comparison reads every "
                                          r"job's points.parquet \(cloud, survival\)$"):
        checked_commands("tension_comparison", ["output.points=false"])
    with pytest.raises(ConfigError, match=r"study actuator_choice reads every job's points.parquet \(cloud, slices\)"):
        checked_commands("actuator_choice", ["output.points=false"])
    assert len(checked_commands("design_mass", ["output.points=false"])) == 1


def test_a_second_run_of_a_study_at_once_stops_in_one_line(tmp_path):
    """Two runs into one study folder would share its jobs: the second stops (exit 2) while
    the first holds the folder, and writes nothing; --figures-only too."""
    from pipeline.app.job import folder_lock
    from pipeline.study import study_dir

    folder = study_dir("actuator_choice", [], tmp_path)
    folder.mkdir(parents=True)
    with folder_lock(folder):
        for flags in ([], ["--figures-only"]):
            done = subprocess.run([sys.executable, "-m", "pipeline.study", "actuator_choice", "--out", str(tmp_path), *flags],
                                  capture_output=True, text=True, cwd=tmp_path)
            assert done.returncode == 2
            assert done.stderr.strip().splitlines()[-1] == (
                f"error: {folder}: another run of study actuator_choice is writing this folder; wait for "
                "it or write elsewhere (--out DIR)")
    assert [p.name for p in folder.iterdir()] == [".lock"]


def test_several_studies_run_two_at_a_time_with_the_results_of_one_run_each(tmp_path):
    """Two studies in one command run concurrently (each its jobs on one core): the same tables
    as the study run alone with the default two-worker pool."""
    (tmp_path / "alone").mkdir()
    assert study(tmp_path / "alone", "actuator_choice").returncode == 0
    proc = study(tmp_path, "actuator_choice", "actuator_choice_pulling")
    assert proc.returncode == 0, proc.stderr
    both, alone = tmp_path / "outputs" / "studies", tmp_path / "alone" / "outputs" / "studies"
    for table in ("summary", "choice"):
        pd.testing.assert_frame_equal(pd.read_parquet(both / "actuator_choice" / f"{table}.parquet"),
                                      pd.read_parquet(alone / "actuator_choice" / f"{table}.parquet"))
    pulling = pd.read_parquet(both / "actuator_choice_pulling" / "choice.parquet")
    assert pulling["feasible_pct"].round(2).tolist() == [66.67, 62.96, 51.85, 51.85, 14.81]
    def n_jobs(root):
        return yaml.safe_load((root / "actuator_choice" / "jobs" / "multirun.yaml").read_text())["hydra"]["launcher"]["n_jobs"]

    assert n_jobs(both) == 1 and n_jobs(alone) == 2  # one level of parallelism: the studies, or the jobs


def test_a_bad_study_among_several_stops_them_all_before_any_runs(tmp_path):
    """The studies of one command are checked in the concurrent workers too, all before the
    first runs: the failing check is the one line, exit 2, and no study folder is written."""
    proc = study(tmp_path, "actuator_choice", "evidence_cpr8", "load.mass=3")
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        "error: load.mass=3: study evidence_cpr8 checks the papers' published facts on their own "
        "settings; it takes compute.* overrides only"]
    assert not (tmp_path / "outputs").exists()


@pytest.mark.parametrize("override", ["hydra.sweep.dir=/tmp/elsewhere", "hydra.run.dir=/tmp/elsewhere",
                                      "hydra/launcher=basic", "+hydra.job.env_set.X=1", "~hydra.callbacks.sweep_summary"])
def test_a_study_places_and_launches_its_own_jobs(tmp_path, override):
    """Hydra's settings on a study's command line were ignored (hydra.run.dir: the study wrote to
    a folder named after the override) or failed after its files (hydra.sweep.dir: a traceback
    from the sweep summary it then could not find). One line, exit 2, nothing written."""
    with pytest.raises(ConfigError, match=r"a study places and launches its own jobs \(--out, --launcher\)"):
        checked_commands("actuator_choice", [override])
    proc = study(tmp_path, "actuator_choice", override)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("value", ["None", "cpr9", "points"])
def test_a_robot_name_set_on_the_command_line_is_checked_like_a_robot_file(tmp_path, value):
    """robot.name=None gave a KeyError traceback (the override is applied after the robot file
    chose the schema); another kind's name keeps the file's keys, which that kind does not have."""
    from pipeline.app.plan import plan

    with pytest.raises(ConfigError, match=rf"^robot.name={value}: "):
        plan([f"robot.name={value}"])
    with pytest.raises(ConfigError, match=rf"^robot.name={value}: "):
        checked_commands("actuator_choice", [f"robot.name={value}"])
    done = command(tmp_path, "pipeline", f"robot.name={value}")
    assert done.returncode == 2 and done.stderr.startswith(f"error: robot.name={value}: ")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("expression, why", [
    ("volume_m3 **", "invalid syntax"),
    ("round(volume_m3)", '"round" is not a supported function'),
    ("np.log(volume_m3)", "has no attribute 'log'"),
])
def test_a_figure_expression_pandas_refuses_stops_the_study_before_its_jobs(tmp_path, expression, why):
    """It failed after every job had run and written its files."""
    (tmp_path / "mine.yaml").write_text(
        "title: t\nsource: s\nsweep: {load.mass: '1,2'}\n"
        f"figures:\n  - {{kind: curve, file: f.png, x: load.mass, y: '{expression}'}}\n")
    with pytest.raises(ConfigError, match=rf"mine.yaml: figures: f.png: y='{re.escape(expression)}': pandas cannot "
                                          rf"evaluate it \(.*{re.escape(why)}"):
        load_study("mine", tmp_path)
    (tmp_path / "fine.yaml").write_text(
        "title: t\nsource: s\nsweep: {load.mass: '1,2'}\n"
        "figures:\n  - {kind: curve, file: f.png, x: load.mass, y: 'volume_m3 / `load.mass` ** 2'}\n")
    assert load_study("fine", tmp_path).figures[0].y == "volume_m3 / `load.mass` ** 2"


@pytest.mark.parametrize("keys, shown", [("axis: w", "axis='w': slices cut across x, y or z"),
                                         ("layers: 0", "layers=0: slices cut at 1 or more layers")])
def test_slices_across_no_axis_or_no_layer_stop_the_study_at_load(tmp_path, keys, shown):
    (tmp_path / "mine.yaml").write_text(
        f"title: t\nsource: s\nsweep: {{load.mass: '1,2'}}\nfigures:\n  - {{kind: slices, file: s.png, {keys}}}\n")
    with pytest.raises(ConfigError, match=rf"^.*mine.yaml: figures: s.png: {re.escape(shown)}$"):
        load_study("mine", tmp_path)


def test_a_params_file_gives_overrides_in_hydras_grammar(tmp_path):
    """--params (the DVC stages' params.yaml): every leaf of its mappings is one override that
    Hydra's parser reads back as the same value, strings quoted, lists and nulls kept."""
    from pipeline.app.plan import parse
    from pipeline.study import params_overrides

    path = tmp_path / "params.yaml"
    path.write_text("robot:\n  platform: {mass: 0.5, com: [0, 0, -0.1]}\nchoice: {required_pct: 80}\n"
                    "catalogue: \"my cat's, list.csv\"\ntension: {t_max: null}\noutput: {cables: true}\n")
    overrides = params_overrides(path)
    assert overrides == ["robot.platform.mass=0.5", "robot.platform.com=[0,0,-0.1]", "choice.required_pct=80",
                         "catalogue='my cat\\'s, list.csv'", "tension.t_max=null", "output.cables=true"]
    values = {o.key_or_group: o.value() for o in parse(overrides)}
    assert values == {"robot.platform.mass": 0.5, "robot.platform.com": [0, 0, -0.1], "choice.required_pct": 80,
                      "catalogue": "my cat's, list.csv", "tension.t_max": None, "output.cables": True}
    for text in ("", "{}\n", "# nothing\n"):
        path.write_text(text)
        assert params_overrides(path) == []


@pytest.mark.parametrize("text, message", [
    ("[1, 2]\n", "needs a mapping of keys to values (found list)"),
    ("load: {mass: [1\n", "not YAML"),
    ("load: {1: 2}\n", "load.1: not a key name"),
    ("when: 2026-11-26\n", "when=2026-11-26: not a number, string, list or mapping"),
])
def test_a_bad_params_file_is_one_line_and_nothing_runs(tmp_path, text, message):
    (tmp_path / "params.yaml").write_text(text)
    proc = study(tmp_path, "design_mass", "--params", "params.yaml")
    assert proc.returncode == 2
    (line,) = proc.stderr.strip().splitlines()
    assert line.startswith("error: --params params.yaml: ") and message in line, line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["params.yaml"]
    missing = study(tmp_path, "design_mass", "--params", "nosuch.yaml")
    assert missing.returncode == 2 and missing.stderr.strip() == "error: --params nosuch.yaml: No such file or directory"


@pytest.mark.parametrize("file, why", [
    ("../../x.png", "a file name ending in .png"), ("/tmp/x.png", "a file name ending in .png"),
    ("sub/x.png", "a file name ending in .png"), ("fig.svg", "a file name ending in .png"),
    (".hidden.png", "a file name ending in .png"),
    ("{load_mass.__class__}.png", "fields are {column} or {column:format}"),
    ("{load_mass[0]}.png", "fields are {column} or {column:format}"),
])
def test_a_figure_file_is_a_png_name_in_the_figures_folder(tmp_path, file, why):
    """A figure's ``file`` wrote outside the study folder (``..``, absolute paths) and was a
    ``str.format`` template with attribute access: each is refused when the study is read,
    before any job runs."""
    (tmp_path / "mine.yaml").write_text(
        f"title: t\nsource: s\nsweep: {{load.mass: '1,2'}}\nfigures:\n  - {{kind: curve, file: '{file}', "
        "x: load.mass, y: volume_m3}\n")
    with pytest.raises(ConfigError, match=rf"mine.yaml: figures: file='{re.escape(file)}': {re.escape(why)}"):
        load_study("mine", tmp_path)
    (tmp_path / "mine.yaml").write_text(
        "title: t\nsource: s\nsweep: {load.mass: '1,2'}\nfigures:\n  - {kind: curve, file: f.png, x: load.mass, "
        "y: volume_m3, title: 'mass {load_mass.real}'}\n")
    with pytest.raises(ConfigError, match=r"figures: f.png: title='mass \{load_mass.real\}': fields are"):
        load_study("mine", tmp_path)


def test_figure_fields_are_filled_from_the_row_only():
    """``{column}`` and ``{column:format}`` from the row; a missing column is a ConfigError
    naming the columns; a value that would put a separator in the file name is refused."""
    from matplotlib.figure import Figure

    from pipeline.analyses.figures import FigureSpec, _fill, _save

    row = pd.Series({"load.mass": 2.5, "case_label": "a/b", "volume_m3": 1.2345})
    assert _fill("m {load_mass:g}, {{literal}}, {volume_m3:.2f}", row) == "m 2.5, {literal}, 1.23"
    with pytest.raises(ConfigError, match=r"figure field \{load_mas\}: no such column \(there are: load_mass, "):
        _fill("{load_mas}", row)
    with pytest.raises(ConfigError, match=r"fills to 'fig_a/b.png', not a file name"):
        _save(Figure(), FigureSpec(kind="curve", file="fig_{case_label}.png"), Path("/nonexistent"), row)


def test_a_study_file_whose_name_is_not_a_plain_name_is_no_study(tmp_path):
    """``...yaml`` is study ``..``, whose results would land above --out: not a study."""
    (tmp_path / "...yaml").write_text("title: t\nsource: s\n")
    (tmp_path / "ok-1.yaml").write_text("title: t\nsource: s\n")
    from pipeline.study import available
    assert available(tmp_path) == ["ok-1"]
    with pytest.raises(ConfigError, match=r"study '\.\.' not found \(available: ok-1\); a study's name is letters"):
        load_study("..", tmp_path)


@pytest.mark.parametrize("field_, value, message", [
    ("hue", "tension.t_mx", "hue='tension.t_mx': not a key of the study's jobs (did you mean tension.t_max?)"),
    ("per", "[load.mas]", "per='load.mas': not a key of the study's jobs (did you mean load.mass?)"),
    ("select", "{robot.gama_deg: 0}", "select='robot.gama_deg': not a key"),
    ("y", "robot.r_ed", "y='robot.r_ed': not a key of the study's jobs (did you mean robot.r_end?)"),
])
def test_a_figures_config_key_is_checked_before_any_job(tmp_path, field_, value, message):
    """hue was not checked before the jobs: a 40-line KeyError after them. Every config key a
    figure names is checked against the planned jobs, with the nearest key, and nothing runs."""
    (tmp_path / "studies").mkdir()
    (tmp_path / "studies" / "mine.yaml").write_text(
        "title: t\nsource: s\noverrides: [robot=irpm6, robot.search.step=2]\nsweep: {load.mass: '1,2'}\n"
        f"figures:\n  - {{kind: curve, file: f.png, x: load.mass, y: feasible_pct, {field_}: {value}}}\n".replace(
            f"y: feasible_pct, y: {value}", f"y: {value}"))
    out = tmp_path / "out"
    done = command(tmp_path, "pipeline.study", "--config-dir", str(tmp_path), "--out", str(out), "mine")
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and message in lines[0], lines
    assert not (out / "mine" / "jobs").exists()


def test_two_figures_of_one_file_are_refused_and_drawings_over_each_other_are_named(tmp_path, caplog):
    """A study whose figure file lacks the field that tells its drawings apart wrote one file
    four times over itself without a word: two figures of one file are refused at load, and one
    figure whose drawings land in one file warns, naming it."""
    import logging

    (tmp_path / "twice.yaml").write_text("title: t\nsource: s\nsweep: {load.mass: '1,2'}\nfigures:\n"
                                         "  - {kind: curve, file: f.png, x: load.mass, y: feasible_pct}\n"
                                         "  - {kind: curve, file: f.png, x: load.mass, y: volume_m3}\n")
    with pytest.raises(ConfigError, match=r"twice.yaml: figures: f.png: the file of 2 figures; each needs its own$"):
        load_study("twice", tmp_path)
    (tmp_path / "studies").mkdir()
    (tmp_path / "studies" / "clouds.yaml").write_text(
        "title: t\nsource: s\noverrides: [robot=irpm6, robot.search.step=2]\nsweep: {load.mass: '1,2'}\n"
        "figures:\n  - {kind: cloud, file: cloud.png}\n")
    with caplog.at_level(logging.WARNING, logger="pipeline.study"):
        done = command(tmp_path, "pipeline.study", "--config-dir", str(tmp_path), "--out", str(tmp_path / "out"), "clouds")
    assert done.returncode == 0, done.stderr[-2000:]
    assert "figures: cloud.png: 2 drawings were written to cloud.png, each over the one before" in done.stderr + caplog.text


def test_a_curves_long_legend_goes_beside_the_plot_not_over_its_data(tmp_path):
    """A hue of robot files' attachment lists (140 characters) covered the plot: a legend of long
    entries (or many) is drawn beside the axes, so the saved figure grows to the right of it."""
    import matplotlib.pyplot as plt
    from PIL import Image

    from pipeline.analyses.figures import FigureSpec, render

    class Results:  # a study's summary is all a curve reads
        def __init__(self, table):
            self.summary = table

    sizes = {}
    for name, hue in (("short", ["a", "b"]), ("long", ["[[-0.06, 0.06, 0.05], [0.06, 0.06, 0.02], [0.06, -0.06]]",
                                                      "[[-0.08, 0.08, 0.05], [0.08, 0.08, 0.02], [0.08, -0.08]]"])):
        table = pd.DataFrame({"load.mass": [0, 1, 0, 1], "feasible_pct": [50.0, 40.0, 45.0, 35.0],
                              "robot.attachments": [hue[0], hue[0], hue[1], hue[1]]})
        spec = FigureSpec(kind="curve", file=f"{name}.png", x="load.mass", y="feasible_pct", hue="robot.attachments")
        (png, _) = render(spec, Results(table), tmp_path / "figures")
        with Image.open(png) as image:
            sizes[name] = image.size
    plt.close("all")
    assert sizes["long"][0] > sizes["short"][0] + 200 and sizes["long"][1] == pytest.approx(sizes["short"][1], abs=40)
