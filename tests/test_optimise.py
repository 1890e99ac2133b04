"""The optimise study kind (pipeline/analyses/optimise.py): declared design variables and objectives,
Optuna's seeded sampler, each trial an ordinary job; bad input refused before anything runs."""

import re
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from conftest import command

import pipeline.study
from pipeline.model.catalogue import load_catalogue
from pipeline.errors import ConfigError
from pipeline.analyses.optimise import OptimiseSpec, corner_overrides, pareto_front
from pipeline.study import load_study, run_study

STUDY = "title: t\nsource: s\noptimise:\n{body}\n"
GOOD = {"variables": "{actuator: catalogue, drive.winch_radius: {low: 0.03, high: 0.12}}"}


@pytest.mark.parametrize("body, message", [
    ("  variables: {drive.winch_radius: {low: 0.12, high: 0.03}}",
     "optimise.variables.drive.winch_radius: an empty range [0.12, 0.03]"),
    ("  variables: {drive.gear_ratio: {low: 5, high: 10, step: 20}}",
     "optimise.variables.drive.gear_ratio: an empty range [5, 10] by 20"),
    ("  variables: {drive.gear_ratio: {low: 5, high: .inf}}", "low, high and step must be finite numbers"),
    ("  variables: {actuator: []}", "optimise.variables.actuator: an empty list of values"),
    ("  variables: {drive.gear_ratio: [5, .nan, 20]}", "variables.drive.gear_ratio: nan: the values must be finite numbers"),
    ("  variables: {drive.gear_ratio: [5, true]}", "variables.drive.gear_ratio: True: the values must be finite"),
    ("  variables: {drive.gear_ratio: [5, x]}", "gear_ratio: the values must be finite numbers, or all names"),
    ("  variables: {drive.gear_ratio: catalogue}", "only 'actuator' takes the catalogue's ids"),
    (f"  variables: {GOOD['variables']}\n  objectives: [cheapest]",
     "optimise.objectives: unknown 'cheapest' (known: feasible_pct, motor_torque_demand_Nm"),
    (f"  variables: {GOOD['variables']}\n  budget: 0", "optimise.budget=0: must be in [1, 10000]"),
    (f"  variables: {GOOD['variables']}\n  budget: -5", "optimise.budget=-5: must be in [1, 10000]"),
    (f"  variables: {GOOD['variables']}\n  sampler: grid", "optimise.sampler='grid': must be one of nsga2, tpe"),
    (f"  variables: {GOOD['variables']}\n  seed: -1", "seed=-1: must be an integer in [0, 2"),  # Optuna's ValueError
])
def test_a_bad_optimise_block_is_refused_when_the_study_is_loaded(tmp_path, body, message):
    (tmp_path / "bad.yaml").write_text(STUDY.format(body=body))
    with pytest.raises(ConfigError, match=message.replace("[", r"\[").replace("(", r"\(")):
        load_study("bad", tmp_path)


def test_a_study_either_sweeps_or_optimises(tmp_path):
    (tmp_path / "both.yaml").write_text(STUDY.format(body=f"  variables: {GOOD['variables']}")
                                        + "sweep: {actuator: catalogue}\n")
    with pytest.raises(ConfigError, match="a study either sweeps or optimises"):
        load_study("both", tmp_path)


def test_an_actuator_id_outside_the_catalogue_is_refused():
    ids = load_catalogue().ids
    spec = OptimiseSpec(variables={"actuator": [1, 9], "drive.gear_ratio": {"low": 5, "high": 60}})
    with pytest.raises(ConfigError, match=r"optimise.variables.actuator: id 9 is not in the catalogue \(ids: 1, 2, 3, 4, 5\)"):
        corner_overrides(spec.variables, ids)
    spec = replace(spec, variables={"actuator": "catalogue", "drive.gear_ratio": {"low": 5, "high": 60}})
    assert corner_overrides(spec.variables, ids) == [["actuator=1", "drive.gear_ratio=5"], ["actuator=5", "drive.gear_ratio=60"]]
    spec = replace(spec, variables={"actuator": [4, 2], "load.mass": [3.0, 0.5, 1.0]})  # the extremes of a list
    assert corner_overrides(spec.variables, ids) == [["actuator=2", "load.mass=0.5"], ["actuator=4", "load.mass=3.0"]]


def test_bad_extra_overrides_stop_the_study_before_anything_is_written(tmp_path):
    proc = command(tmp_path, "pipeline.study", "drive_pareto", "catalogue=missing.csv")
    assert proc.returncode == 2 and proc.stderr.startswith("error: catalogue=missing.csv")
    assert list(tmp_path.iterdir()) == []


def test_the_pareto_front_is_the_set_no_trial_dominates():
    rng = np.random.default_rng(3)
    table = pd.DataFrame({"feasible_pct": rng.integers(0, 5, 60) * 25.0,
                          "motor_torque_demand_Nm": rng.integers(0, 6, 60) / 10, "meets": rng.random(60) < 0.8})
    front = pareto_front(table, ["feasible_pct", "motor_torque_demand_Nm"])
    for i, row in table.iterrows():  # brute force: maximise the share, minimise the torque
        others = table[table["meets"]]
        better = ((others["feasible_pct"] >= row["feasible_pct"])
                  & (others["motor_torque_demand_Nm"] <= row["motor_torque_demand_Nm"])
                  & ((others["feasible_pct"] > row["feasible_pct"])
                     | (others["motor_torque_demand_Nm"] < row["motor_torque_demand_Nm"])))
        assert front[i] == (row["meets"] and not better.any()), i


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    """The declared drive_pareto study with 16 trials on a 4^3 grid, run twice (the second
    reuses every trial's job)."""
    root = tmp_path_factory.mktemp("optimise")
    spec = load_study("drive_pareto")
    small = replace(spec, optimise=replace(spec.optimise, budget=16))
    patch = pytest.MonkeyPatch()
    patch.setattr(pipeline.study, "load_study", lambda name, directory=None, config_dir=None: small)
    try:
        run_study("drive_pareto", ["grid.n=4", "grid.n_vel=4"], root)
        out = root / "drive_pareto"
        first = pd.read_parquet(out / "summary.parquet")
        stamps = {p: p.stat().st_mtime_ns for p in (out / "jobs").glob("trial_*/summary.parquet")}
        run_study("drive_pareto", ["grid.n=4", "grid.n_vel=4"], root)
    finally:
        patch.undo()
    return out, first, stamps


def test_a_seeded_rerun_proposes_the_same_trials_and_reuses_their_jobs(small_run):
    out, first, stamps = small_run
    again = pd.read_parquet(out / "summary.parquet")
    pd.testing.assert_frame_equal(first, again)
    assert len(first) == 16 and first["trial"].tolist() == list(range(16))
    assert len(stamps) == 16
    assert all(path.stat().st_mtime_ns == stamp for path, stamp in stamps.items())
    assert (out / "figures" / "pareto_front.png").exists() and (out / "best_drive.csv").exists()


def test_each_trial_is_the_job_its_variables_name(small_run, make_cfg, catalogue):
    """The objectives from the trial's own job: the peak motor torque is the largest share of
    eq. (32)'s limit over the feasible poses times the rated torque."""
    from conftest import compute_workspace

    out, trials, _ = small_run
    meeting = trials[trials["feasible_pct"] > 0].iloc[0]
    points, summary = compute_workspace(make_cfg(
        "grid.n=4", "grid.n_vel=4", f"actuator={meeting['actuator']}",
        f"drive.winch_radius={meeting['drive.winch_radius']}", f"drive.gear_ratio={meeting['drive.gear_ratio']}"),
        catalogue)
    assert summary["feasible_pct"] == meeting["feasible_pct"]
    used = (1 - points.loc[points["feasible"], "margin_torque"]).max()
    rated = catalogue.row(meeting["actuator"])["torque_Nm"]
    assert meeting["motor_torque_demand_Nm"] == pytest.approx(used * rated)
    assert meeting["winch_radius_m"] == meeting["drive.winch_radius"]
    assert trials["meets"].tolist() == (trials["feasible_pct"] >= 90).tolist()
    assert trials.loc[trials["pareto"], "meets"].all()


def priced_catalogue(tmp_path, prices) -> str:
    """Table 1 with the user's own price column."""
    from pipeline.model.catalogue import TABLE1

    table = pd.read_csv(TABLE1, dtype=str)
    table["price_EUR"] = prices
    path = tmp_path / "priced.csv"
    table.to_csv(path, index=False)
    return str(path)


def priced_study(monkeypatch):
    """drive_pareto asked for the cheapest actuator and gear ratio (8 trials), its front drawn."""
    from pipeline.analyses.figures import FigureSpec

    spec = load_study("drive_pareto")
    study = replace(spec, search=None, analyses=["best_drive"], optimise=OptimiseSpec(
        variables={"actuator": "catalogue", "drive.gear_ratio": {"low": 15, "high": 35}},
        objectives=["feasible_pct", "catalogue.price_EUR"], budget=8),
        figures=[FigureSpec(kind="pareto", file="front.png", x="catalogue.price_EUR", y="feasible_pct", hue="actuator")])
    monkeypatch.setattr(pipeline.study, "load_study", lambda name, directory=None, config_dir=None: study)


def test_a_column_of_the_users_catalogue_is_an_objective(tmp_path, monkeypatch):
    """optimise.objectives: [feasible_pct, catalogue.price_EUR]: each trial carries its
    actuator's price, the front is the cheapest design for each share."""
    prices = ["900", "400", "250", "150", "90"]
    priced_study(monkeypatch)
    run_study("drive_pareto", [f"catalogue={priced_catalogue(tmp_path, prices)}", "grid.n=4", "grid.n_vel=3"],
              tmp_path / "out")
    trials = pd.read_parquet(tmp_path / "out" / "drive_pareto" / "summary.parquet")
    assert trials["catalogue.price_EUR"].tolist() == [float(prices[a - 1]) for a in trials["actuator"]]
    again = trials.assign(pareto=pareto_front(trials, ["feasible_pct", "catalogue.price_EUR"]) & trials["meets"])
    assert trials["pareto"].tolist() == again["pareto"].tolist()
    assert (tmp_path / "out" / "drive_pareto" / "figures" / "front.png").stat().st_size > 0


@pytest.mark.parametrize("prices, objective, message", [
    (["900", "400", "n/a", "150", "90"], "catalogue.price_EUR",
     "optimise.objectives: catalogue.price_EUR: actuator 3: 'n/a' is not a number"),
    (["900", "400", "250", "150", "90"], "catalogue.cost",
     "catalogue.cost: the catalogue has no column 'cost' (its extra columns: price_EUR)"),
])
def test_a_catalogue_objective_needs_a_number_for_every_actuator(tmp_path, monkeypatch, prices, objective, message):
    priced_study(monkeypatch)
    study = pipeline.study.load_study("drive_pareto")
    study.optimise.objectives = ["feasible_pct", objective]
    with pytest.raises(ConfigError, match=re.escape(message)):
        pipeline.study.checked_commands("drive_pareto", [f"catalogue={priced_catalogue(tmp_path, prices)}"],
                                        tmp_path / "out")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("damage", ["truncated", "missing"])
def test_figures_only_refuses_a_damaged_search_table_before_touching_the_figures(small_run, tmp_path, monkeypatch, damage):
    import shutil

    out, _, _ = small_run
    copy = tmp_path / "drive_pareto"
    shutil.copytree(out, copy)
    searched = copy / "search.parquet"
    if damage == "truncated":
        searched.write_bytes(searched.read_bytes()[:100])
    else:
        searched.unlink()
    figures = sorted(p.name for p in (copy / "figures").iterdir())
    small = pipeline.study.load_study("drive_pareto")
    monkeypatch.setattr(pipeline.study, "load_study", lambda name, directory=None, config_dir=None: small)
    message = "not a readable Parquet file" if damage == "truncated" else r"no results in .*\(search.parquet\)"
    with pytest.raises(ConfigError, match=message):
        run_study("drive_pareto", ["grid.n=4", "grid.n_vel=4"], tmp_path, figures_only=True)
    assert sorted(p.name for p in (copy / "figures").iterdir()) == figures
