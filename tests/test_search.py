"""The exact search over the drive train (pipeline/analyses/search.py): its two premises checked on the
kernel (only N_V / R_i counts; each pose's least margin is quasiconcave in it), its branch and
bound against evaluating every ratio (random interval data and the kernel), the paper robot's
answers pinned, and the optimiser's agreement on the single-variable questions."""

import re
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from pipeline.errors import ConfigError
from pipeline.analyses.optimise import OBJECTIVES, optimise
from pipeline.analyses.search import Evaluation, SearchSpec, branch_and_bound, candidates, exact_drive, search
from pipeline.study import checked_commands, load_study
from conftest import compute_workspace

STUDY = "title: t\nsource: s\nsearch:\n{body}\n"


def margins(points: pd.DataFrame) -> np.ndarray:
    return points[[c for c in points.columns if c.startswith("margin_")]].to_numpy()


def kernel_runner(make_cfg, catalogue, *fixed):
    """run_job for :func:`pipeline.analyses.search.search` on the kernel itself, no files."""
    def run_job(actuator, overrides):
        points, summary = compute_workspace(make_cfg(f"actuator={actuator}", *fixed, *overrides), catalogue)
        return {"job": "-", **summary}, points
    return run_job


# --- the premises, on the kernel -------------------------------------------------------------

@pytest.mark.parametrize("extra", [[], ["model.pinv_columns=translational", "model.jdot=true"],
                                   ["orientation.psi=0.5", "model.xi_in_torque_limit=false"]])
def test_only_the_ratio_of_gear_to_winch_radius_counts(make_cfg, catalogue, extra):
    """Eqs. (18)-(22), (30)-(34): (R_i, N_V) and (c R_i, c N_V) give every pose the same
    margins, hence the same verdicts and motor torque demand."""
    for actuator in (1, 3):
        base = compute_workspace(make_cfg(f"actuator={actuator}", "drive.winch_radius=0.035",
                                          "drive.gear_ratio=12", *extra), catalogue)[0]
        for factor in (2, 3.5):
            scaled = compute_workspace(make_cfg(f"actuator={actuator}", f"drive.winch_radius={0.035 * factor}",
                                                f"drive.gear_ratio={12 * factor}", *extra), catalogue)[0]
            np.testing.assert_allclose(margins(scaled), margins(base), rtol=0, atol=1e-12)
            assert (scaled["feasible"] == base["feasible"]).all()


@pytest.mark.parametrize("actuator, extra", [(3, []), (2, ["model.pinv_columns=translational", "model.jdot=true"]),
                                             (1, ["orientation.psi=0.5"])])
def test_each_poses_least_margin_is_quasiconcave_in_the_winch_radius(make_cfg, catalogue, actuator, extra):
    """The search's premise: along the winch radius no pose's least margin dips and rises
    again, so each pose is feasible on one interval. The share itself is not monotone (actuator
    2 without moments: 85.2, 83.3, 85.2 %), which is why a bisection on the share would fail."""
    radii = np.round(np.linspace(0.01, 0.3, 30), 4)
    least = np.array([margins(compute_workspace(make_cfg(f"actuator={actuator}", f"drive.winch_radius={r}", *extra),
                                                catalogue)[0]).min(axis=1) for r in radii])
    before = np.maximum.accumulate(least, axis=0)
    after = np.maximum.accumulate(least[::-1], axis=0)[::-1]
    assert (least >= np.minimum(before, after) - 1e-12).all()
    assert np.ptp(least, axis=0).min() > 0.1  # every pose's margin does move with R_i
    if actuator == 2:
        share = (least >= 0).mean(axis=1)
        assert (np.diff(share) < 0).any() and (np.diff(share[np.argmax(share < share.max()):]) > 0).any()


# --- the branch and bound against every ratio ------------------------------------------------

def interval_instance(rng, n, count):
    """Random poses whose margins have the model's form 1 - |a rho + b / rho| / c (four limits
    each), and torque demands W / rho."""
    rho = np.sort(rng.choice(np.linspace(20, 2000, 5 * count), count, replace=False))
    a = rng.normal(size=(n, 4)) * rng.uniform(0, 2e-3, size=(n, 1))
    b = rng.normal(size=(n, 4)) * rng.uniform(0, 300, size=(n, 1))
    c = rng.uniform(0.2, 1.5, size=(n, 4))
    margin = (1 - np.abs(a * rho[:, None, None] + b / rho[:, None, None]) / c).min(axis=2)
    return rho, margin, rng.uniform(10, 200, size=n)


def test_the_branch_and_bound_finds_what_evaluating_every_ratio_finds():
    rng = np.random.default_rng(7)
    evaluated, total, found = 0, 0, 0
    for _ in range(300):
        rho, margin, work = interval_instance(rng, int(rng.integers(1, 60)), int(rng.integers(1, 120)))
        every = []
        for g in range(len(rho)):
            feasible = margin[g] >= 0
            demand = work / rho[g]
            every.append(Evaluation(feasible, margin[g], demand, 100.0 * feasible.mean(),
                                    float(demand[feasible].max()) if feasible.any() else 1e9))
        shares = np.array([e.share for e in every])
        required = float(rng.choice([shares.max(), np.quantile(shares, 0.8), 50.0, 90.0]))
        for values in (None, 1 / rho, rho):  # the demand; the winch radius; the gear ratio
            objective = np.array([e.value for e in every]) if values is None else values
            meets = shares >= required
            done, excluded = branch_and_bound(rho, values, lambda g: every[g], required)
            got = min((objective[g] for g in done if meets[g]), default=None)
            assert got == (objective[meets].min() if meets.any() else None)
            for g, (upper, lower) in excluded.items():  # every exclusion is a true bound
                assert g not in done
                assert shares[g] <= upper + 1e-9 and (not meets[g] or objective[g] >= lower - 1e-9)
            evaluated, total, found = evaluated + len(done), total + len(rho), found + meets.any()
    assert found > 500 and evaluated < 0.35 * total  # most instances have an answer; a third of the work


@pytest.mark.parametrize("objective", ["gear_ratio", "motor_torque_demand_Nm"])
def test_on_the_kernel_the_search_equals_evaluating_every_ratio(make_cfg, catalogue, objective):
    spec = SearchSpec(variables={"drive.gear_ratio": {"low": 4, "high": 64, "step": 6}}, objective=objective)
    run_job = kernel_runner(make_cfg, catalogue, "grid.n=4", "grid.n_vel=3")
    table = search(spec, catalogue, 90.0, run_job, atol=1e-9)
    for actuator, part in table.groupby("actuator"):
        every = pd.DataFrame([run_job(actuator, [f"drive.gear_ratio={n:g}"])[0] for n in part["gear_ratio"]])
        value = every.apply(lambda row: OBJECTIVES[objective][2](row, catalogue.row(actuator)), axis=1)
        meets = every["feasible_pct"].to_numpy() >= 90.0
        found = part[part["meets"]]
        best = value[meets].min() if meets.any() else None
        assert (found["objective"].min() if len(found) else None) == best, actuator
        evaluated = part["evaluated"].to_numpy()
        np.testing.assert_array_equal(part["feasible_pct"].to_numpy()[evaluated], every["feasible_pct"].to_numpy()[evaluated])
        left_out = ~evaluated
        assert (every["feasible_pct"].to_numpy()[left_out] <= part["bound_pct"].to_numpy()[left_out] + 1e-9).all()
    assert table["evaluated"].sum() < len(table)


def test_candidates_are_the_distinct_ratios_each_with_its_smallest_design(catalogue):
    spec = SearchSpec(variables={"drive.winch_radius": [0.035, 0.07], "drive.gear_ratio": [12, 24]})
    table = candidates(spec, catalogue.row(1))
    assert table["rho"].tolist() == pytest.approx([12 / 0.07, 12 / 0.035, 24 / 0.035])  # 24/0.07 == 12/0.035
    assert table.loc[1, "winch_radius_m"] == 0.035 and table.loc[1, "overrides"] == [
        "drive.winch_radius=0.035", "drive.gear_ratio=12"]
    gears = candidates(replace(spec, objective="gear_ratio"), catalogue.row(1))
    assert gears.loc[1, "gear_ratio"] == 12
    only_gear = candidates(SearchSpec(variables={"drive.gear_ratio": [10, 20]}), catalogue.row(3))
    assert only_gear["winch_radius_m"].tolist() == [0.08, 0.08] and only_gear.loc[0, "overrides"] == ["drive.gear_ratio=10"]


# --- the paper robot's answers and the optimiser --------------------------------------------

def declared(name: str, make_cfg, catalogue):
    """A declared study's search and optimiser on the kernel (no files): the search table and
    the optimiser's trials."""
    study = load_study(name)
    run_job = kernel_runner(make_cfg, catalogue)
    table = search(study.search, catalogue, 90.0, run_job, atol=1e-9)
    trials = None
    if study.optimise is not None:
        trials = optimise(study.optimise, lambda number, overrides: {"job": "-", **compute_workspace(
            make_cfg(*overrides), catalogue)[1]}, catalogue, 90.0)
    return table, trials


@pytest.mark.parametrize("name, column, answers", [
    ("smallest_winch_radius", "winch_radius_m", {1: 0.075, 2: 0.08}),
    ("smallest_gear_ratio", "gear_ratio", {1: 16, 2: 25}),
])
def test_the_single_variable_answers_and_the_optimiser_agrees_within_one_grid_step(
        make_cfg, catalogue, name, column, answers):
    """Table 1 at x = 90 % on the paper's robot: the smallest winch radius (own gear ratio) and
    the smallest gear ratio (R_i = 0.08 m) per actuator, or the proof that none in the range
    reaches 90 % (every left-out ratio's share bound below 90 %); NSGA-II (200 trials, seed 0)
    lands on the same grid value or the next."""
    table, trials = declared(name, make_cfg, catalogue)
    verdict = exact_drive(table, trials.assign(meets=trials["feasible_pct"] >= 90.0)).set_index("actuator")
    for actuator, value in answers.items():
        assert verdict.loc[actuator, "found"] and verdict.loc[actuator, column] == pytest.approx(value)
    for actuator in (3, 4, 5):  # every ratio evaluated below 90 % or bounded below it
        part = table[table["actuator"] == actuator]
        assert not verdict.loc[actuator, "found"]
        assert (part["evaluated"] | (part["bound_pct"] < 90)).all() and (part["feasible_pct"].fillna(0) < 90).all()
    assert verdict["agree"].all() and not verdict["optimiser_better"].fillna(False).any()
    assert verdict["evaluated"].sum() < 0.5 * verdict["candidates"].sum()


def test_the_least_motor_torque_that_reaches_90_percent(make_cfg, catalogue):
    """drive_pareto's question answered exactly: R_i in [0.03, 0.12] by 0.005 m and N_V in
    [5, 60] (719 distinct ratios per actuator). Checked against every ratio once (3 595 jobs,
    outside the suite): actuator 1 at R_i = 0.03 m, N_V = 12 needs 0.390 N m at the motor, 14 %
    less than the best of NSGA-II's 200 trials (0.455 N m); none of actuators 3-5 reaches 90 %."""
    study = load_study("drive_pareto")
    table = search(study.search, catalogue, 90.0, kernel_runner(make_cfg, catalogue), atol=1e-9)
    verdict = exact_drive(table, None).set_index("actuator")
    assert verdict.loc[1, ["winch_radius_m", "gear_ratio"]].tolist() == [0.03, 12]
    assert verdict.loc[1, "motor_torque_demand_Nm"] == pytest.approx(0.38993, abs=5e-6)
    assert verdict.loc[2, ["winch_radius_m", "gear_ratio"]].tolist() == [0.115, 38]
    assert verdict.loc[2, "motor_torque_demand_Nm"] == pytest.approx(0.29629, abs=5e-6)
    assert not verdict.loc[[3, 4, 5], "found"].any()
    assert (verdict["candidates"] == 719).all() and verdict["evaluated"].max() <= 30


# --- bad input ---------------------------------------------------------------------------------

@pytest.mark.parametrize("body, message", [
    ("  variables: {}", "search.variables: none given"),
    ("  variables: {load.mass: {low: 1, high: 2, step: 1}}", "search.variables.load.mass: not a drive variable"),
    ("  variables: {drive.gear_ratio: {low: 5, high: 60}}", "give a step (the search is exact to a grid)"),
    ("  variables: {drive.gear_ratio: {low: 60, high: 5, step: 1}}", "an empty range [60, 5] by 1"),
    ("  variables: {drive.winch_radius: [0.05, -0.01]}", "search.variables.drive.winch_radius: -0.01: must be positive"),
    ("  variables: {drive.winch_radius: [0.05, .nan]}", "search.variables.drive.winch_radius: nan: the values must be finite"),
    ("  variables: {drive.winch_radius: [0.05, x]}", "search.variables.drive.winch_radius: the values must be finite"),
    ("  variables: {drive.winch_radius: [0.05]}\n  objective: motor_power_W", "search.objective='motor_power_W': unknown"),
])
def test_a_bad_search_block_is_refused_when_the_study_is_loaded(tmp_path, body, message):
    (tmp_path / "bad.yaml").write_text(STUDY.format(body=body))
    with pytest.raises(ConfigError, match=re.escape(message)):
        load_study("bad", tmp_path)


def test_a_search_and_an_optimiser_must_ask_the_same_question(tmp_path):
    (tmp_path / "two.yaml").write_text(STUDY.format(body="  variables: {drive.gear_ratio: [10, 20]}")
                                       + "optimise:\n  variables: {actuator: catalogue, drive.gear_ratio: [10, 30]}\n")
    with pytest.raises(ConfigError, match="search.variables: must be the optimise block's drive variables"):
        load_study("two", tmp_path)


@pytest.mark.parametrize("extra, message", [
    (["tension=feasible"], "tension.model=feasible: study smallest_gear_ratio's search is exact for minimum-norm"),
    (["output.points=false"], "output.points=false: study smallest_gear_ratio's search reads every job's margins"),
    (["catalogue=missing.csv"], "missing.csv"),
    (["analysis=payload"], "actuator=1: analysis=payload finds the largest payload the cables hold"),
    (["robot=irpm6", "analysis=certified", "tension=feasible"], "analysis=certified: study smallest_gear_ratio reads"),
    (["analysis=lines"], "analysis=lines: study smallest_gear_ratio searches the drive train; analysis=cpr_wwa has one"),
])
def test_a_search_the_model_cannot_make_exact_is_refused_before_anything_runs(tmp_path, extra, message):
    with pytest.raises(ConfigError, match=message):
        checked_commands("smallest_gear_ratio", extra, tmp_path)
    assert not any(tmp_path.iterdir())


def test_search_actuators_must_be_catalogue_ids(catalogue):
    with pytest.raises(ConfigError, match=r"search.actuators: id 9 is not in the catalogue \(ids: 1, 2, 3, 4, 5\)"):
        SearchSpec(variables={"drive.gear_ratio": [10]}, actuators=[2, 9]).ids(catalogue)
    with pytest.raises(ConfigError, match="search.actuators='all': catalogue or a list of ids"):
        SearchSpec(variables={"drive.gear_ratio": [10]}, actuators="all").ids(catalogue)


def test_a_users_catalogue_without_actuator_1_is_searched(tmp_path):
    """The design studies' preflight takes an id of the user's catalogue, not the default 1."""
    from pipeline.model.catalogue import TABLE1

    table = pd.read_csv(TABLE1, dtype=str).iloc[[0, 2]].assign(id=["7", "9"])
    table.to_csv(tmp_path / "mine.csv", index=False)
    corners = checked_commands("smallest_gear_ratio", [f"catalogue={tmp_path / 'mine.csv'}"], tmp_path / "out")
    actuators = [job.cfg.actuator for _, planned in corners for job in planned.jobs]
    assert actuators == [7, 9]
