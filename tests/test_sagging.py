"""Statics with sagging cables (``robot.catenary``, issue 55 item 3).

Oracles, none of them the model's own: the inextensible catenary written here from its cosh form
(its parameter from the textbook's closed form, its taut root by bracketing), whose end forces,
summed with the load's weight and moment, must balance at every pose called feasible; a second
method for the verdicts, a constrained nonlinear search (SLSQP from several starts) over the chord
tensions of a point robot; and the straight cables, which weightless cables must reproduce."""

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import brentq, minimize

from conftest import SPREAD_ANCHORS, SPREAD_PLATFORM, SPREAD_ROBOT, command, compute_workspace, eq9_rotation
from pipeline.model.catenary import solve

G = 9.81


def cosh_cable(span, rise, tau, w, samples=40001):
    """The inextensible catenary from A (0, 0) to B (span, rise) pulled with chord tension tau:
    H = tau span / l, c = H / w, z = c (cosh((x - x0)/c) - cosh(x0/c)) with x0 = span/2 - c
    asinh(rise / (2 c sinh(span / 2c))). Returns H, V at A (up), the top tension, the length and
    the largest distance below the chord (at ``samples`` points)."""
    chord = np.hypot(span, rise)
    h = tau * span / chord
    c = h / w
    x0 = span / 2 - c * np.arcsinh(rise / (2 * c * np.sinh(span / (2 * c))))
    x = np.linspace(0.0, span, samples)
    z = c * (np.cosh((x - x0) / c) - np.cosh(x0 / c))
    top = h * max(np.cosh(x0 / c), np.cosh((span - x0) / c))
    length = c * (np.sinh((span - x0) / c) + np.sinh(x0 / c))
    return h, h * np.sinh(-x0 / c), top, length, ((x * rise - z * span) / chord).max()


def taut_root(span, rise, top, w):
    """The chord tension of the taut branch (the largest root) whose top tension is ``top``."""
    grid = np.geomspace(1e-3 * w * np.hypot(span, rise), 10 * top, 600)
    values = np.array([cosh_cable(span, rise, t, w, 2)[2] for t in grid]) - top
    k = np.flatnonzero((values[:-1] < 0) & (values[1:] >= 0))[-1]
    return brentq(lambda t: cosh_cable(span, rise, t, w, 2)[2] - top, grid[k], grid[k + 1], xtol=1e-13, rtol=1e-14)


HEAVY = [*SPREAD_ROBOT, "robot.search.step=0.25", "tension=feasible", "tension.t_min=5", "tension.t_max=300",
         "load.mass=5", "load.com=[0.03,-0.02,0.01]", "orientation.psi=0.1", "orientation.theta=-0.05",
         "robot.cable_mass=0.2", "robot.catenary=0.05", "output.cables=true"]


@pytest.fixture(scope="module")
def heavy(catalogue):
    from conftest import make_cfg

    return compute_workspace(make_cfg(*HEAVY), catalogue)


def test_every_feasible_pose_is_an_equilibrium_of_catenaries(heavy):
    """At every pose called feasible, each cable's written top tension gives (by the cosh form
    here) the force it pulls its attachment with; with the load's weight they balance the
    platform's forces and moments (1e-6 of the weight), within [t_min, t_max] and a sag of 5 %;
    the written sags, lengths and angles are those catenaries'."""
    points, summary = heavy
    feasible = points[points.feasible]
    assert len(feasible) >= 30 and summary["undecided_pct"] < 1
    rotation, up, w = eq9_rotation(0.1, -0.05, 0.0), np.array([0.0, 0.0, 1.0]), 0.2 * G
    anchors, arms = np.array(SPREAD_ANCHORS, float), np.array(SPREAD_PLATFORM, float) @ rotation.T
    weight = np.array([0.0, 0.0, -5 * G])
    names = [str(i + 1) for i in range(8)]
    for _, pose in feasible.iterrows():
        total, moment = weight.copy(), np.cross(rotation @ [0.03, -0.02, 0.01], weight)
        for i, name in enumerate(names):
            to_anchor = anchors[i] - (pose[["x", "y", "z"]].to_numpy(float) + arms[i])
            rise = to_anchor @ up
            level = to_anchor - rise * up
            span = np.linalg.norm(level)
            top = pose[f"tension_{name}"]
            assert 5 - 1e-6 <= top <= 300 + 1e-6
            tau = taut_root(span, rise, top, w)
            h, v, _, length, sag = cosh_cable(span, rise, tau, w)
            force = h * level / span + v * up
            total += force
            moment += np.cross(arms[i], force)
            assert sag <= 0.05 * np.hypot(span, rise) * (1 + 1e-9)
            assert pose[f"sag_{name}"] == pytest.approx(sag, abs=1e-6 * np.hypot(span, rise))
            assert pose[f"unstrained_{name}"] == pytest.approx(length, rel=1e-8)
            assert pose[f"angle_platform_{name}"] == pytest.approx(np.arctan2(v, h), abs=1e-8)
        assert np.abs(total).max() <= 1e-6 * 5 * G and np.abs(moment).max() <= 1e-6 * 5 * G
    assert (points.sag_max_ratio[points.feasible] <= 0.05 * (1 + 1e-9)).all()
    assert points.sag_max_ratio[~points.feasible].isna().all() and summary["sag_max_ratio_max"] > 0.01


def test_sagging_cables_need_more_than_straight_ones_and_weightless_ones_are_the_straight(catalogue):
    """Cables of negligible weight give the straight cables' verdicts (away from their boundary:
    margins beyond 1e-6) and their least-norm tensions (rtol 1e-6); heavy cables hold fewer poses
    here, and every pose they hold the straight ones hold too (their weight only adds load)."""
    from conftest import make_cfg

    base = [*SPREAD_ROBOT, "robot.search.step=0.25", "tension=feasible", "tension.t_min=5", "tension.t_max=300",
            "load.mass=5", "orientation.psi=0.1", "tension.distribution=min_norm", "output.cables=true"]
    straight, _ = compute_workspace(make_cfg(*base), catalogue)
    light, _ = compute_workspace(make_cfg(*base, "robot.cable_mass=1e-9", "robot.catenary=0.05"), catalogue)
    clear = (straight.filter(like="margin_").abs() > 1e-6).all(axis=1)
    assert (straight.feasible[clear] == light.feasible[clear]).all() and clear.mean() > 0.9
    held = straight.feasible & light.feasible
    tensions = [c for c in straight.columns if c.startswith("tension_")]
    assert np.allclose(light.loc[held, tensions], straight.loc[held, tensions], rtol=1e-6, atol=1e-6)
    heavy, _ = compute_workspace(make_cfg(*base, "robot.cable_mass=0.3", "robot.catenary=0.05"), catalogue)
    assert heavy.feasible.sum() < straight.feasible.sum()
    assert not (heavy.feasible & ~straight.feasible).any()


CRANE_ANCHORS = [[-2.0, -1.5, 3.0], [2.5, -1.0, 3.2], [1.5, 2.0, 2.8], [-1.8, 1.7, 3.1]]
CRANE = ["robot=points", f"robot.anchors={CRANE_ANCHORS}", "robot.attachments=[[0,0,0],[0,0,0],[0,0,0],[0,0,0]]",
         "robot.dofs=[x,y,z]", "robot.search.lo=[-1.6,-1.2,0.6]", "robot.search.hi=[1.6,1.4,2.6]",
         "robot.search.step=0.4", "tension=feasible", "tension.t_min=10", "tension.t_max=80", "load.mass=6",
         "robot.cable_mass=0.1", "robot.catenary=0.05"]


PLANAR_ANCHORS = [[-2.0, 3.0, 0.0], [2.2, 3.3, 0.0], [0.6, -0.6, 0.0]]
PLANAR = ["robot=points", f"robot.anchors={PLANAR_ANCHORS}", "robot.attachments=[[0,0,0],[0,0,0],[0,0,0]]",
          "robot.dofs=[x,y]", "robot.up=[0,1,0]", "robot.search.lo=[-1.6,0.2,0]", "robot.search.hi=[1.6,2.6,0]",
          "robot.search.step=0.1", "tension=feasible", "tension.t_min=5", "tension.t_max=60", "load.mass=3",
          "robot.cable_mass=0.1", "robot.catenary=0.05"]


def searched(anchors, up, position, w, weight, t_min, t_max, ratio, starts):
    """Whether chord tensions exist whose catenaries (cosh form) balance a point load, each on its
    taut branch with its top tension in [t_min, t_max] and its sag within ``ratio``: SLSQP from
    ``starts`` random points (the second method)."""
    to_anchor = anchors - position
    rise = to_anchor @ up
    level = to_anchor - rise[:, None] * up
    span = np.linalg.norm(level, axis=1)
    chord = np.hypot(span, rise)
    axes = (np.abs(level).max(axis=0) > 0) | (up != 0)  # a planar robot's plane: no equation across it

    def cables(tau):
        return [cosh_cable(span[i], rise[i], tau[i], w, 2001) for i in range(len(tau))]

    def balance(tau):
        found = cables(tau)
        force = sum(h * level[i] / span[i] + v * up for i, (h, v, *_) in enumerate(found))
        return ((force - weight * up) / weight)[axes]

    def limits(tau):
        found = cables(tau)
        rising = [cosh_cable(span[i], rise[i], tau[i] * 1.001, w, 2)[2] - c[2] for i, c in enumerate(found)]
        return np.concatenate([[c[2] - t_min for c in found], [t_max - c[2] for c in found],
                               [ratio * chord[i] - c[4] for i, c in enumerate(found)], rising])

    rng = np.random.default_rng(0)
    for _ in range(starts):
        start = rng.uniform(t_min, t_max, len(anchors))
        found = minimize(lambda t: 0.0, start, method="SLSQP", bounds=[(1e-3, 10 * t_max)] * len(anchors),
                         constraints=[{"type": "eq", "fun": balance}, {"type": "ineq", "fun": limits}],
                         options={"maxiter": 200, "ftol": 1e-12})
        if np.abs(balance(found.x)).max() < 1e-7 and limits(found.x).min() > -1e-7:
            return True
    return False


@pytest.mark.parametrize("robot, anchors, up, limits", [
    (CRANE, CRANE_ANCHORS, [0.0, 0.0, 1.0], (6, 10, 80)),
    (PLANAR, PLANAR_ANCHORS, [0.0, 1.0, 0.0], (3, 5, 60)),
])
def test_a_second_method_agrees_with_every_proven_verdict(catalogue, robot, anchors, up, limits):
    """A heavy-cabled crane (4 cables hold a point load, one redundant) and a planar point robot
    whose third cable runs down to the floor: a nonlinear search finds an equilibrium at every
    pose proven feasible and none at the poses proven infeasible, away from the boundary (the
    search's own tolerance, 1e-7, is the boundary's width here); 30 feasible and 30 infeasible poses of each."""
    from conftest import make_cfg

    mass, t_min, t_max = limits
    points, summary = compute_workspace(make_cfg(*robot), catalogue)
    decided = points[~points.catenary_undecided]
    assert 0.1 < decided.feasible.mean() < 0.9 and summary["undecided_pct"] < 10
    near = decided.filter(like="margin_").drop(columns="margin_catenary").abs().min(axis=1) < 1e-3
    away = decided[~near]
    checked = pd.concat([away[away.feasible == verdict].sample(min(30, int((away.feasible == verdict).sum())), random_state=3)
                         for verdict in (True, False)])
    assert checked.feasible.sum() >= 20 and (~checked.feasible).sum() >= 20
    for _, pose in checked.iterrows():
        found = searched(np.array(anchors), np.array(up), pose[["x", "y", "z"]].to_numpy(float), 0.1 * G, mass * G,
                         t_min, t_max, 0.05, starts=2 if pose.feasible else 5)
        assert found == pose.feasible, pose


@pytest.mark.parametrize("seed", [0, 1])
def test_what_the_proofs_assume_of_the_catenary_holds(seed):
    """On the taut branch a cable pulled harder is shorter, its ends' angles nearer the chord's and
    its top tension higher; and over a box of +-1 % the share of its weight it leaves on the
    platform, g, lies within its ends' and centre's values widened by their second difference
    (the proof's bound), at 41 samples, for 2 000 random cables, elastic and not."""
    rng = np.random.default_rng(seed)
    n = 2000
    span, rise = rng.uniform(0.05, 20, n), rng.uniform(-15, 15, n)
    w = rng.uniform(0.01, 5, n)
    ea = np.where(rng.random(n) < 0.5, np.inf, rng.uniform(1e4, 1e7, n))
    floor = solve(span, rise, w, ea, "sag_ratio", rng.uniform(0.005, 0.1, n)).chord_tension
    tau = floor[None] * np.geomspace(1.0, 50.0, 40)[:, None]
    cables = solve(span, rise, w, ea, "chord_tension", tau)
    taut = (np.diff(cables.top_tension, axis=0) > 0).all(axis=0)
    assert taut.mean() > 0.95  # the rest are steep cables: the model's floor lifts them onto it
    first, last = cables.angles
    chord_angle = np.arctan2(rise, span)
    assert (np.diff(cables.length, axis=0)[:, taut] < 0).all()
    assert (np.diff(chord_angle - first, axis=0)[:, taut] <= 1e-12).all()
    assert (np.diff(last - chord_angle, axis=0)[:, taut] <= 1e-12).all()
    centre = tau[20]
    box = centre[None] * (1 + np.linspace(-0.01, 0.01, 41))[:, None]
    inside = solve(span, rise, w, ea, "chord_tension", box)
    g = inside.vertical - box * rise / np.hypot(span, rise)
    ends = g[[0, 20, 40]]
    pad = np.abs(ends[0] + ends[2] - 2 * ends[1])
    assert (g >= ends.min(axis=0) - pad - 1e-12).all() and (g <= ends.max(axis=0) + pad + 1e-12).all()


BAD = {
    "no weight": (["robot.catenary=0.05"], "robot.cable_mass"),
    "zero": (["robot.cable_mass=0.1", "robot.catenary=0"], "robot.catenary"),
    "too much sag": (["robot.cable_mass=0.1", "robot.catenary=0.2"], "robot.catenary"),
    "nan": (["robot.cable_mass=0.1", "robot.catenary=nan"], "robot.catenary"),
    "text": (["robot.cable_mass=0.1", "robot.catenary=taut"], "robot.catenary"),
    "pinv": (["robot.cable_mass=0.1", "robot.catenary=0.05", "tension=pinv"], "tension=feasible"),
    "cpr_wwa": (["robot.cable_mass=0.1", "robot.catenary=0.05", "analysis=cpr_wwa"], "analysis=statics"),
    "payload": (["robot.cable_mass=0.1", "robot.catenary=0.05", "analysis=payload"], "analysis=statics"),
    "pulleys": (["robot.cable_mass=0.1", "robot.catenary=0.05", "robot.pulleys={axis: [0, 0, 1], radius: 0.05}"],
                "robot.pulleys"),
    "metrics": (["robot.cable_mass=0.1", "robot.catenary=0.05", "output.metrics=true"], "output.metrics"),
    "stiffness": (["robot.cable_mass=0.1", "robot.catenary=0.05", "robot.cable_ea=1e5",
                   "+criteria.stiffness={translational: 1000, rotational: 0, frequency: 0}"], "criteria.stiffness"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_what_sagging_cables_cannot_mean_is_one_line(tmp_path, case):
    overrides, named = BAD[case]
    run = tmp_path / "run"
    done = command(tmp_path, "pipeline", *SPREAD_ROBOT, "robot.search.step=0.5", "tension=feasible", *overrides,
                   f"hydra.run.dir={run}")
    assert done.returncode == 2, done.stderr[-2000:]
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and named in lines[0], lines
    assert not run.exists()


def test_the_cogiro_study_gives_the_numbers_its_docs_state(catalogue):
    """docs/studies.md quotes this job of the study sagging_cogiro, run from its own overrides."""
    from conftest import make_cfg
    from pipeline.study import load_study

    overrides = [o.strip('"') for o in load_study("sagging_cogiro").overrides]
    summary = compute_workspace(make_cfg(*overrides, "robot.cable_mass=0.25", "robot.catenary=0.05"), catalogue)[1]
    assert (summary["n_feasible"], summary["n_points"], summary["lost_catenary"]) == (3871, 5040, 8)
    assert round(summary["undecided_pct"], 2) == 0.14 and round(summary["added_length_max_max"], 3) == 0.116


def shot(horizontal, vertical, length, w, ea, steps=400):
    """The far end of an elastic cable pulled at its start with (H, V), by fixed-step RK4 on its
    equilibrium (a second integrator, written here)."""
    def slope(s):
        force = np.array([horizontal, vertical + w * s])
        tension = np.hypot(*force)
        return force / tension * (1.0 + tension / ea)

    h, point = length / steps, np.zeros(2)
    for k in range(steps):
        s = k * h
        point = point + h / 6 * (slope(s) + 4 * slope(s + h / 2) + slope(s + h))
    return point


def test_elastic_sagging_cables_balance_the_load_too(catalogue):
    """The crane's cables elastic (EA = 20 kN, strains of a few per mille): at feasible poses each
    written top tension, shot by RK4 from its attachment (H, V, L0 by fsolve here), reaches its
    anchor and gives forces that hold the load (1e-6 of its weight), its unstrained length the
    written one."""
    from scipy.optimize import fsolve

    from conftest import make_cfg

    points, _ = compute_workspace(make_cfg(*CRANE, "robot.cable_ea=2e4", "output.cables=true"), catalogue)
    anchors, w = np.array(CRANE_ANCHORS), 0.1 * G
    feasible = points[points.feasible]
    assert len(feasible) > 50
    for _, pose in feasible.sample(6, random_state=2).iterrows():
        total = np.array([0.0, 0.0, -6 * G])
        for i in range(4):
            to_anchor = anchors[i] - pose[["x", "y", "z"]].to_numpy(float)
            rise, level = to_anchor[2], to_anchor[:2]
            span, chord, top = np.linalg.norm(level), np.linalg.norm(to_anchor), pose[f"tension_{i + 1}"]

            def missed(unknowns):
                h, v, length = unknowns
                end = shot(h, v, length, w, 2e4)
                return [(end[0] - span) / chord, (end[1] - rise) / chord,
                        (max(np.hypot(h, v), np.hypot(h, v + w * length)) - top) / top]

            start = [top * span / chord, top * rise / chord - w * chord / 2, chord / (1 + top / 2e4)]
            h, v, length = fsolve(missed, start, xtol=1e-13)
            assert np.abs(missed([h, v, length])).max() < 1e-9
            assert pose[f"unstrained_{i + 1}"] == pytest.approx(length, rel=1e-7)
            total += np.array([*(h * level / span), v])
        assert np.abs(total).max() <= 1e-6 * 6 * G
