"""Straight-line simulation experiments (section 3.1.3, Figs. 4b, 5b, 6): the trapezoidal
profile, line O''-F'', the power balance, and the agreement with the CPR-WWA grid."""

import re

import numpy as np
import pytest

from pipeline.app.problem import build_problem
from pipeline.workspace.lines import simulate_lines
from pipeline.model.path import trapezoid

ROT = ["orientation.psi=0.5", "orientation.theta=0.5", "orientation.phi=0.5"]


@pytest.fixture(scope="module")
def lines(make_cfg, catalogue):
    cache = {}

    def run(*overrides):
        if overrides not in cache:
            cfg = make_cfg("analysis=lines", *overrides)
            cache[overrides] = simulate_lines(cfg, *build_problem(cfg, catalogue))
        return cache[overrides]
    return run


@pytest.mark.parametrize("distance, peak", [(2.9, 1.3), (1.0, np.sqrt(1.0 * 1.3 / 1.82))])
def test_trapezoid_reaches_the_end_at_rest_with_the_paper_accelerations(distance, peak):
    p = trapezoid(distance, 1.3, 1.82, 1.82, 0.001)
    assert p.s[-1] == pytest.approx(distance, abs=1e-9) and p.v[0] == 0 and p.v[-1] == pytest.approx(0, abs=1e-9)
    assert p.v.max() == pytest.approx(peak, rel=1e-3)
    assert set(np.round(np.unique(p.a), 6)) <= {round(1.3 / 1.82, 6), 0.0, round(-1.3 / 1.82, 6)}
    np.testing.assert_allclose(np.gradient(p.s, p.t)[5:-5], p.v[5:-5], atol=2e-3)
    assert np.trapezoid(p.v, p.t) == pytest.approx(distance, rel=1e-4)


@pytest.mark.parametrize("overrides", [(), ("grid.n=5", "motion.t_acc=0.7", "motion.t_dec=2.9")])
def test_the_lines_samples_are_counted_exactly_before_any_is_made(lines, make_cfg, catalogue, monkeypatch, overrides):
    """``check_samples`` counts each line's samples from its profile without sampling it: a bound
    of exactly the samples the simulation makes passes, one fewer is refused (square and
    asymmetric accelerations, lines of equal and of different lengths)."""
    import pipeline.workspace.lines as module
    from pipeline.app.problem import build_grid
    from pipeline.errors import ConfigError

    cfg = make_cfg("analysis=lines", *overrides)
    made = len(lines(*overrides)[0])
    grid = build_grid(cfg, build_problem(cfg, catalogue)[0].robot)
    monkeypatch.setattr(module, "MAX_SAMPLES", made)
    module.check_samples(cfg.motion, grid)
    monkeypatch.setattr(module, "MAX_SAMPLES", made - 1)
    with pytest.raises(ConfigError, match=re.escape(f"take {made:.3g} samples")):
        module.check_samples(cfg.motion, grid)


def line_of(samples, number=0):
    return samples[samples["line"] == number]


def test_line_O_F_is_the_top_edge_at_the_smallest_y(lines):
    samples, points, _ = lines()
    first = line_of(samples)
    assert (first["axis"] == "x").all()
    assert first["y"].iloc[0] == pytest.approx(points["y"].min())
    assert first["z"].iloc[0] == pytest.approx(points["z"].max())
    assert first["x"].iloc[[0, -1]].tolist() == pytest.approx([points["x"].min(), points["x"].max()])


@pytest.mark.parametrize("reading", ["translational", "full"])
def test_actuator_1_zero_orientation_line_O_F_within_all_limits(lines, reading):
    samples, _, _ = lines("actuator=1", f"model.pinv_columns={reading}")
    assert (line_of(samples).filter(like="margin_") >= 0).all().all()


def test_actuator_1_at_half_a_radian_violates_torque_not_speed_fig_6b(lines):
    """Fig. 6b: torque violated on some cables, speed and voltage within limits. With the full
    pseudo-inverse (docs/evidence.md) torque fails on cables 1, 3 and 8 and speed and voltage hold
    (peak 0.976 x 48 V, cable 5): cable 1 pays out at cruise under 1.68 x its torque limit, the
    braking quadrant, where the load lowers the voltage below the back-EMF. The translational
    reading shows no violation at all."""
    samples, _, summary = lines("actuator=1", "model.pinv_columns=full", *ROT)
    first = line_of(samples)
    over = [c for c in range(1, 9) if (first[f"torque_{c}"].abs() > summary["limit_torque"]).any()]
    assert over == [1, 3, 8]
    assert first["margin_torque"].min() == pytest.approx(-0.683, abs=0.002)
    assert (first["margin_speed"] >= 0).all()
    assert first["margin_voltage"].min() == pytest.approx(0.024, abs=0.002)
    worst = first[[f"voltage_{c}" for c in range(1, 9)]].abs().max().idxmax()
    assert worst == "voltage_5"
    cruise = first[(first["theta_dot_1"] > 16) & (first["torque_1"] > summary["limit_torque"])]
    assert len(cruise) > 10 and (cruise["voltage_1"] < cruise["voltage_5"].abs()).all()
    translational, _, _ = lines("actuator=1", "model.pinv_columns=translational", *ROT)
    assert (line_of(translational).filter(like="margin_") >= 0).all().all()


def test_power_balance_where_the_wrench_is_reachable(lines):
    """sum_i M_i theta_dot_i = F . p_dot wherever J^T M = F; the samples where F is not in the
    range of J^T (rank 5 at zero orientation with all six columns) are counted, not hidden."""
    for reading, unreachable in (("translational", 0), ("full", None)):
        samples, _, _ = lines("actuator=1", f"model.pinv_columns={reading}")
        scale = samples["power_load"].abs().max()
        reachable = samples["wrench_residual"] < 1e-9 * samples["wrench_residual"].max() + 1e-9
        gap = (samples["power_cables"] - samples["power_load"]).abs()
        assert gap[reachable].max() < 1e-9 * scale
        if unreachable is not None:
            assert (~reachable).sum() == unreachable
        else:
            assert (~reachable).sum() > 0 and gap[~reachable].max() > 1e-6 * scale
    samples, _, _ = lines("actuator=1", "model.pinv_columns=full", *ROT)  # rank 6: all reachable
    assert (samples["power_cables"] - samples["power_load"]).abs().max() < 1e-9 * samples["power_load"].abs().max()


AGREEMENT = {  # (reading, orientation) -> % of the 216 grid points where lines and grid agree, acts 1-5
    ("translational", "zero"): [100.0, 98.15, 98.15, 100.0, 87.04],
    ("translational", "rot05"): [99.54, 100.0, 99.07, 98.61, 88.43],
    ("full", "zero"): [100.0, 94.44, 98.15, 99.07, 100.0],
    ("full", "rot05"): [97.22, 94.91, 95.37, 79.63, 100.0],
}


@pytest.mark.parametrize("reading, orientation", sorted(AGREEMENT))
@pytest.mark.parametrize("actuator", [1, 2, 3, 4, 5])
def test_agreement_with_the_grid_per_actuator_and_orientation(lines, reading, orientation, actuator):
    _, points, summary = lines(f"actuator={actuator}", f"model.pinv_columns={reading}",
                               *(ROT if orientation == "rot05" else []))
    expected = AGREEMENT[reading, orientation][actuator - 1]
    assert summary["agreement_pct"] == pytest.approx(expected, abs=0.01)
    assert summary["n_feasible_grid"] == points["feasible_grid"].sum()
    assert summary["n_lines"] == 72 and not points.isna().any().any()
    lost = {k: v for k, v in summary.items() if k.startswith("lost_") and not k.startswith("lost_grid_")}
    lost_grid = {k: v for k, v in summary.items() if k.startswith("lost_grid_")}
    assert summary["n_feasible"] + sum(lost.values()) == summary["n_points"]  # the lines' verdict
    assert summary["n_feasible_grid"] + sum(lost_grid.values()) == summary["n_points"]
    for name, count in lost.items():  # each rejected point counted under its worst criterion
        assert count == ((points["limiting"] == name[5:]) & ~points["feasible"]).sum()




def test_interference_criteria_are_evaluated_on_the_lines_as_on_the_grid(lines):
    """The lines evaluate the registry's pose-only criteria (cable_cable, cable_platform,
    cable_obstacle) at every sample: at each line's first sample, a grid point, the margins
    equal the grid's there (they ended in KeyError: 'cable_cable' before, issue 51)."""
    samples, points, summary = lines("grid.n=5", "robot.cable_diameter=0.02", "robot.platform.shape=hull",
                                     "obstacles=[{name: block, lo: [1, 0.5, -2.2], hi: [1.4, 0.9, -1.4]}]")
    starts = samples[samples["s"] == 0].round({c: 9 for c in "xyz"}).drop_duplicates(["x", "y", "z"])
    grid = points.round({c: 9 for c in "xyz"}).set_index(["x", "y", "z"])
    for name in ("cable_cable", "cable_platform", "cable_obstacle"):
        at = grid.loc[list(zip(starts["x"], starts["y"], starts["z"])), f"margin_{name}"].to_numpy()
        np.testing.assert_allclose(starts[f"margin_{name}"].to_numpy(), at, rtol=0, atol=1e-12, err_msg=name)
    assert (samples["margin_cable_obstacle"] < 0).any() and (samples["margin_cable_obstacle"] > 0).any()
    assert summary["lost_cable_obstacle"] > 0


@pytest.mark.parametrize("extra", [[], ["model.jdot=true", "model.pinv_columns=translational"]])
def test_the_samples_margins_are_the_literal_criteria_at_each_samples_own_motion(make_cfg, catalogue, extra):
    """The lines evaluate the registry's criteria on a state of samples (one velocity and one
    acceleration each); the literal reference of section 3 (``pipeline.workspace.reference``, no
    shared array code), given each sample's velocity and acceleration as a set of one, gives the
    same four margins, on a tilted carrier with an off-centre load moving asymmetrically."""
    from dataclasses import replace

    from pipeline.model.dynamics import SampleDynamics
    from pipeline.workspace.criteria import margins
    from pipeline.workspace.reference import literal_margins

    cfg = make_cfg("analysis=lines", "actuator=2", *ROT, "load.mass=1.5", "load.com=[0.04,-0.03,0.02]", *extra)
    problem, _ = build_problem(cfg, catalogue)
    rng = np.random.default_rng(52)
    positions = np.column_stack([rng.uniform(0.9, 1.6, 7), rng.uniform(0.8, 1.4, 7), rng.uniform(-1.4, -0.6, 7)])
    velocities, accelerations = rng.normal(0, 0.6, (7, 3)), rng.normal(0, 0.8, (7, 3))
    state = SampleDynamics(problem.robot, positions, problem.orientation, problem.spec, velocities, accelerations)
    found = margins(problem.criteria, state, problem.limits)
    for n in range(7):
        one = replace(problem.spec, velocities=velocities[n:n + 1], accelerations=accelerations[n:n + 1])
        literal = literal_margins(problem.robot, positions[n:n + 1], problem.orientation, one, problem.limits)
        for name, value in literal.items():
            assert found[name][n] == pytest.approx(value[0], abs=1e-9), (name, n)


def test_line_0_is_the_trajectory_analysis_along_the_same_segment(lines, make_cfg, catalogue):
    """One physics, two paths through the code: the paper's line O''-F'' (the CPR-WWA model,
    M = (J^T)^+ F and eqs. 19-21, read with J-dot) and ``analysis=trajectory`` along the same
    segment with the same trapezoid (the statics' minimum-norm tensions times R, the cables' rates
    differentiated from their lengths), the CPR-8 at 0.5 rad (its structure matrix of rank 6)
    with actuator 2. At t = 0 the shaft speeds, torques and voltages agree to 1e-9 of the largest;
    along the line, the trajectory's read between its samples (its grid takes both sides of each
    jump of the acceleration, so it parts from the lines' after the first), to 1e-4."""
    from pipeline.workspace.samples import follow

    samples = line_of(lines(*ROT, "model.jdot=true", "actuator=2")[0]).reset_index(drop=True)
    ends = samples[["x", "y", "z"]].to_numpy()[[0, -1]].tolist()
    cfg = make_cfg("robot=cpr8", "analysis=trajectory", "actuator=2", "tension=pinv", *ROT, f"trajectory.points={ends}",
                   "trajectory.law=trapezoid", "trajectory.v_max=1.3", "trajectory.t_acc=1.82", "trajectory.t_dec=1.82")
    problem = build_problem(cfg, catalogue)[0]
    path, names = follow(cfg, problem)[0], list(problem.robot.cable_names)
    times = samples["t"].to_numpy()
    assert path["t"].iloc[-1] == pytest.approx(times[-1], rel=1e-12)
    away = (np.abs(times - 1.82) > 0.02) & (np.abs(times - (times[-1] - 1.82)) > 0.02)  # not at a jump
    for quantity in ("theta_dot", "torque", "voltage"):
        paper = samples[[f"{quantity}_{i + 1}" for i in range(len(names))]].to_numpy()
        ours = path[[f"{quantity}_{name}" for name in names]].to_numpy()
        scale = np.abs(paper).max()
        assert np.abs(paper[0] - ours[0]).max() < 1e-9 * scale, quantity
        read = np.column_stack([np.interp(times[away], path["t"], ours[:, i]) for i in range(len(names))])
        assert np.abs(paper[away] - read).max() < 1e-4 * scale, quantity
