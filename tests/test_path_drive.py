"""A catalogue actuator driving every cable of any robot along its path (issue 56 item 4:
``analysis=trajectory actuator=ID``).

Oracles: the platform's energy (its kinetic and potential energy, differentiated along the path
here) against the power the cables deliver, sum -t l_dot; the drive's armature and drum equations
written here from the catalogue row (eq. 22's constants) against the samples' voltage and
current, so that electrical power minus the copper, gearbox, friction and rotor-inertia terms is
the power into the cables; the actuator's limits in the catalogue's units; under pulling cables
an LP per sample with the torque and voltage intervals written here."""

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import linprog
from scipy.spatial.transform import Rotation

from conftest import CROSSED_PLATFORM, CROSSED_ROBOT, SPREAD_ANCHORS, command
from pipeline.app.resources import PACKAGE_DIR

ROBOT = CROSSED_ROBOT
TABLE1 = pd.read_csv(PACKAGE_DIR / "data" / "actuators_table1.csv").set_index("id")
G = 9.81
CABLES = [str(i) for i in range(1, 9)]


def drive_constants(actuator: int) -> dict:
    """Eq. (22)'s drive behind the gearbox, from the catalogue row in its own units."""
    row = TABLE1.loc[actuator]
    n_v = row["gear_ratio"]
    n_m = n_v * row["efficiency"]
    return {"C_E": row["back_emf_V_per_rad_s"] * n_v, "C_M": row["torque_constant_Nm_per_A"] * n_m,
            "B_C": row["viscous_friction_Nm_per_rad_s"] * n_v * n_m, "J_r": row["inertia_g_cm2"] * 1e-7 * n_v * n_m,
            "R_r": row["resistance_ohm"], "R": row["winch_radius_m"], "U": row["voltage_V"],
            "speed": row["speed_rpm"] * np.pi / 30 / n_v, "torque": row["torque_Nm"] * n_m}


@pytest.fixture(scope="module")
def moving(tmp_path_factory):
    """The crossed robot carrying a 3 kg body with its inertia along a turning spline, actuator 1
    on every cable, minimum-norm tensions (any sign: the energy balance is exact)."""
    root = tmp_path_factory.mktemp("drive")
    done = command(root, "pipeline", *ROBOT, "analysis=trajectory", "tension=pinv", "actuator=1", "robot.platform.mass=3",
                   "robot.platform.com=[0.02,-0.01,0.03]", "robot.platform.inertia=[0.05,0.06,0.08,0.01,0,0]",
                   "trajectory.law=spline", "trajectory.times=[0.7,0.6]", "trajectory.dt=0.002",
                   "trajectory.points=[[0,-0.4,0.7,0,0,0],[0,0.3,1.1,0.2,-0.1,0.3],[0,0.5,0.8,0,0.1,-0.2]]",
                   f"hydra.run.dir={root / 'run'}")
    assert done.returncode == 0, done.stderr[-2000:]
    return pd.read_parquet(root / "run" / "samples.parquet"), pd.read_parquet(root / "run" / "summary.parquet").iloc[0]


def test_the_cables_deliver_the_platforms_rate_of_kinetic_and_potential_energy(moving):
    """sum_i -t_i l_dot_i (the tensions and cable speeds of samples.parquet) against
    d/dt (m |v_c|^2 / 2 + omega . I omega / 2 + m g z_c) by differences along the path (rtol
    1e-3 of the largest power; the spline's knots left out)."""
    samples, _ = moving
    mass, com = 3.0, np.array([0.02, -0.01, 0.03])
    inertia = np.array([[0.05, 0.01, 0], [0.01, 0.06, 0], [0, 0, 0.08]])
    rotation = Rotation.from_euler("ZYX", samples[["phi", "theta", "psi"]].to_numpy()).as_matrix()  # eq. (9)
    omega = samples[["omega_x", "omega_y", "omega_z"]].to_numpy()
    arm = rotation @ com
    v_c = samples[["x_dot", "y_dot", "z_dot"]].to_numpy() + np.cross(omega, arm)
    turned = rotation @ inertia @ np.swapaxes(rotation, 1, 2)
    energy = (0.5 * mass * np.einsum("ni,ni->n", v_c, v_c) + 0.5 * np.einsum("ni,nij,nj->n", omega, turned, omega)
              + mass * G * (samples["z"].to_numpy() + arm[:, 2]))
    tensions, speeds = (samples[[f"{quantity}_{c}" for c in CABLES]].to_numpy() for quantity in ("tension", "speed"))
    delivered = -(tensions * speeds).sum(axis=1)
    scale = np.abs(delivered).max()
    for segment in (1, 2):
        rows = np.flatnonzero(samples["segment"].to_numpy() == segment)[3:-3]
        rate = np.gradient(energy[rows], samples["t"].to_numpy()[rows])
        np.testing.assert_allclose(rate[2:-2], delivered[rows][2:-2], atol=1e-3 * scale)
    assert scale > 5  # the test moves the platform for real


def test_the_drive_is_the_armature_and_drum_equations_and_its_power_balances(moving):
    """Per cable and sample: theta = l / R; M = R t; the armature u = R_r i + C_E theta_dot and the
    drum J_r theta_ddot = C_M i - B_C theta_dot + M (eq. 22, the physical sign chain), so
    u i - R_r i^2 - (C_E - C_M) theta_dot i - B_C theta_dot^2 - J_r theta_ddot theta_dot = -M theta_dot,
    the power into the cable; and the margins are the limits' in the catalogue's units."""
    samples, summary = moving
    c = drive_constants(1)
    for cable in CABLES:
        speed, accel = samples[f"theta_dot_{cable}"], samples[f"theta_ddot_{cable}"]
        u, i, torque = samples[f"voltage_{cable}"], samples[f"current_{cable}"], samples[f"torque_{cable}"]
        np.testing.assert_allclose(speed, samples[f"speed_{cable}"] / c["R"], rtol=1e-12)
        np.testing.assert_allclose(accel, samples[f"accel_{cable}"] / c["R"], rtol=1e-12)
        np.testing.assert_allclose(torque, c["R"] * samples[f"tension_{cable}"], rtol=1e-12)
        np.testing.assert_allclose(u, c["R_r"] * i + c["C_E"] * speed, atol=1e-9)
        np.testing.assert_allclose(c["J_r"] * accel, c["C_M"] * i - c["B_C"] * speed + torque, atol=1e-9)
        losses = c["R_r"] * i**2 + (c["C_E"] - c["C_M"]) * speed * i + c["B_C"] * speed**2 + c["J_r"] * accel * speed
        np.testing.assert_allclose(samples[f"power_{cable}"] - losses, -torque * speed, atol=1e-9)
    speeds = samples[[f"theta_dot_{c_}" for c_ in CABLES]].abs().to_numpy().max(axis=1)
    np.testing.assert_allclose(samples["margin_speed"], 1 - speeds / c["speed"], atol=1e-12)
    torques = samples[[f"torque_{c_}" for c_ in CABLES]].abs().to_numpy().max(axis=1)
    np.testing.assert_allclose(samples["margin_torque"], 1 - torques / c["torque"], atol=1e-12)
    volts = samples[[f"voltage_{c_}" for c_ in CABLES]].abs().to_numpy().max(axis=1)
    np.testing.assert_allclose(samples["margin_voltage"], 1 - volts / c["U"], atol=1e-12)
    power = samples[[f"power_{c_}" for c_ in CABLES]].to_numpy().sum(axis=1)
    if samples["feasible"].all():
        assert summary["energy_J"] == pytest.approx(np.trapezoid(power, samples["t"]), rel=1e-12)
    else:
        assert np.isnan(summary["energy_J"])
    held = samples["feasible"].to_numpy()
    assert summary["actuator_name"] == "Table 1 actuator 1"
    assert summary["voltage_peak_V"] == pytest.approx(volts[held].max()) if held.any() else np.isnan(summary["voltage_peak_V"])


def test_pulling_cables_with_the_drives_limits_against_an_lp_per_sample(tmp_path):
    """Under tension=feasible the torque and voltage limits bound each cable's tension: a sample
    is feasible when an LP finds tensions in [t_min, t_max], within R t <= M_lim and
    |G_v theta_ddot + L_v theta_dot - S_v R t| <= U (written here), that balance its wrench, and its
    shaft speeds and accelerations are within their limits; the samples agree with it."""
    done = command(tmp_path, "pipeline", *ROBOT, "analysis=trajectory", "actuator=4", "tension=feasible",
                   "tension.t_min=2", "robot.platform.mass=2", "trajectory.points=[[0,-0.5,0.6],[0,0.6,1.3]]",
                   "trajectory.times=0.45", "trajectory.dt=0.01", f"hydra.run.dir={tmp_path / 'run'}")
    assert done.returncode == 0, done.stderr[-2000:]
    samples = pd.read_parquet(tmp_path / "run" / "samples.parquet")
    row = TABLE1.loc[4]
    c = drive_constants(4)
    g_v, s_v = c["J_r"] * c["R_r"] / c["C_M"], c["R_r"] / c["C_M"]
    l_v = c["B_C"] * c["R_r"] / c["C_M"] + c["C_E"]
    anchors, platform = np.array(SPREAD_ANCHORS, float), np.array(CROSSED_PLATFORM, float)
    verdicts = []
    for _, sample in samples.iterrows():
        vectors = sample[["x", "y", "z"]].to_numpy(float) + platform - anchors  # level platform
        unit = vectors / np.linalg.norm(vectors, axis=1, keepdims=True)
        structure = np.vstack([unit.T, np.cross(platform, unit).T])
        wrench = sample[["wrench_fx", "wrench_fy", "wrench_fz", "wrench_mx", "wrench_my", "wrench_mz"]].to_numpy(float)
        theta_dot = sample[[f"speed_{k}" for k in CABLES]].to_numpy(float) / c["R"]
        theta_ddot = sample[[f"accel_{k}" for k in CABLES]].to_numpy(float) / c["R"]
        other = g_v * theta_ddot + l_v * theta_dot
        upper = np.minimum(c["torque"], (other + c["U"]) / s_v) / c["R"]
        lower = np.maximum(np.maximum(-c["torque"], (other - c["U"]) / s_v) / c["R"], 2.0)
        if (lower > upper).any():
            verdicts.append(False)
            continue
        lp = linprog(np.zeros(8), A_eq=structure, b_eq=wrench, bounds=list(zip(lower, upper)), method="highs")
        moving_ok = (np.abs(theta_dot).max() <= c["speed"] * (1 + 1e-9)
                     and np.abs(theta_ddot).max() <= row["torque_Nm"] * row["gear_ratio"] * row["efficiency"] / c["J_r"])
        verdicts.append(lp.status == 0 and moving_ok)
    np.testing.assert_array_equal(samples["feasible"].to_numpy(), np.array(verdicts))
    assert 0 < samples["feasible"].mean() < 1
    assert {"margin_torque", "margin_voltage", "margin_speed", "margin_acceleration"} <= set(samples.columns)


def test_every_catalogue_actuator_along_one_path_in_a_sweep(tmp_path):
    """`-m actuator=1,2,3,4,5` on a path: one job per actuator, its name in the summary, the
    weaker motors failing where the stronger hold."""
    done = command(tmp_path, "pipeline", "-m", "actuator=1,2,3,4,5", *ROBOT, "analysis=trajectory",
                   "tension=feasible", "tension.t_min=2", "robot.platform.mass=2",
                   "trajectory.points=[[0,-0.5,0.6],[0,0.6,1.3]]", "trajectory.times=1.2",
                   f"hydra.sweep.dir={tmp_path / 'sweep'}", "hydra.sweep.subdir='actuator=${actuator}'")
    assert done.returncode == 0, done.stderr[-2000:]
    summary = pd.read_parquet(tmp_path / "sweep" / "summary.parquet").set_index("actuator").sort_index()
    assert list(summary.index) == [1, 2, 3, 4, 5]
    assert list(summary["actuator_name"]) == [f"Table 1 actuator {i}" for i in range(1, 6)]
    assert summary.loc[1, "feasible_pct"] == 100 and summary.loc[5, "feasible_pct"] == 0  # actuator 5: torque
    assert summary.loc[5, "lost_torque"] == summary.loc[5, "n_samples"]
    assert (summary["n_samples"] == summary["n_points"]).all()


def test_the_actuator_to_buy_for_a_users_path(tmp_path):
    """CPR-ACM along a path (``api.actuator_choice``): every sample must hold (choice.required_pct
    = 100 for a path); the cheapest actuators that hold the whole path are accepted, ranked."""
    from pipeline import api

    choice = api.actuator_choice([*ROBOT, "analysis=trajectory", "tension=feasible", "tension.t_min=2",
                                  "robot.platform.mass=2", "trajectory.points=[[0,-0.5,0.6],[0,0.6,1.3]]",
                                  "trajectory.times=1.2"], folder=tmp_path / "choice")
    table = choice.table.set_index("actuator")
    assert (table["required_pct"] == 100).all()
    assert table.loc[1, "accepted"] and not table.loc[5, "accepted"]
    assert choice.verdict.startswith("actuator choice at x >= 100 %: accept 1")
    assert set(choice.workspaces) == {1, 2, 3, 4, 5} and choice.workspaces[1].samples is not None
    failing = choice.workspaces[3]  # a path that fails: its figure against time marks the first failure
    (png,) = failing.figure("path", out=tmp_path / "figures", title="actuator 3: {first_failure_criterion}")
    assert png.name == "path.png" and png.stat().st_size > 20_000
    (view,) = failing.figure("path_view", out=tmp_path / "figures", title="actuator 3 along the path")
    assert view.name == "path_view.png" and view.stat().st_size > 20_000
    with pytest.raises(api.ConfigError, match="no samples.parquet"):
        api.workspace([*ROBOT, "analysis=statics", "robot.search.step=0.5"], folder=tmp_path / "grid").figure("path")


@pytest.mark.parametrize("overrides, key", [
    (["actuator=9"], "actuator=9"),
    (["drive.winch_radius=0.05"], "drive.winch_radius"),
    (["drive.gear_ratio=-2", "actuator=1"], "drive.gear_ratio"),
    (["actuator=1", "catalogue=missing.csv"], "missing.csv"),
])
def test_a_drive_it_cannot_mean_is_refused_in_one_line(tmp_path, overrides, key):
    done = command(tmp_path, "pipeline", *ROBOT, "analysis=trajectory", "trajectory.points=[[0,0,1],[0,0.2,1]]",
                   "trajectory.times=1", *overrides, f"hydra.run.dir={tmp_path / 'run'}")
    assert done.returncode == 2, done.stderr[-2000:]
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and key in lines[0], lines
    assert not (tmp_path / "run").exists()


def test_cpr_wwa_without_an_actuator_is_refused(tmp_path):
    done = command(tmp_path, "pipeline", "actuator=null", "grid.n=4", f"hydra.run.dir={tmp_path / 'run'}")
    assert done.returncode == 2 and "actuator=null" in done.stderr and not (tmp_path / "run").exists()


PATH = ["robot=irpm6", "analysis=trajectory", "wrench.fz=0", "robot.platform.mass=30",
        "trajectory.points=[[0,0,4],[1,0.5,5],[-0.5,1,4.5]]", "trajectory.times=2"]
DYNAMIC = ["robot=irpm6", "analysis=statics", "tension=pinv", "wrench.fz=0", "robot.platform.mass=30",
           "robot.search.step=0.8", "platform_motion.acceleration={min:[-1,-1,-1,0,0,0],max:[1,1,1,0,0,0]}",
           "platform_motion.velocity=[[0.5,0,0],[0,0.5,0.3]]", "choice.required_pct=5"]


@pytest.mark.parametrize("overrides, low, high, step", [(PATH, 10, 40, 3), (DYNAMIC, 10, 100, 3)],
                         ids=["a path", "a dynamic workspace"])
def test_the_smallest_gear_ratio_is_found_exactly(tmp_path, overrides, low, high, step):
    """The search of the drive train (``pipeline.analyses.search``) on a path and on a static
    grid in its required motions: under minimum-norm tensions each sample's (each pose's, in
    each motion) speed and acceleration scale with the ratio N_V / R_i and its torque with the
    inverse, so each holds on one interval of it. The IRPM carrying 30 kg with actuator 1, along a
    path (every sample held at 25 and 28, 62 % at 40) and over 3 328 poses each accelerating by
    +-1 m/s^2 at two velocities (5 % required: the share rises to 5.8 % at 64, then falls to 0
    from 88 on, speed and voltage): the search's smallest gear ratio is brute force's, with
    fewer jobs."""
    import yaml

    from pipeline import api

    folder = tmp_path / "mine"
    (folder / "studies").mkdir(parents=True)
    (folder / "studies" / "gear.yaml").write_text(yaml.safe_dump({
        "title": "The smallest gear ratio", "source": "test", "overrides": overrides,
        "search": {"variables": {"drive.gear_ratio": {"low": low, "high": high, "step": step}}, "actuators": [1],
                   "objective": "gear_ratio"}}))
    done = command(tmp_path, "pipeline.study", "--config-dir", str(folder), "gear")
    assert done.returncode == 0, done.stderr[-3000:]
    table = pd.read_parquet(tmp_path / "outputs" / "studies" / "gear" / "search.parquet")
    found = table[table["meets"]]["gear_ratio"].min()
    ratios = np.arange(low, high + 1, step)
    summaries = {g: api.workspace([*overrides, "actuator=1", f"drive.gear_ratio={g}"], folder=tmp_path / f"g{g}").summary
                 for g in ratios}
    shares = {g: summary["feasible_pct"] for g, summary in summaries.items()}
    required = summaries[low]["choice.required_pct"]
    assert found == min(g for g in ratios if shares[g] >= required)
    assert shares[ratios[0]] < required and table["evaluated"].sum() < len(ratios)
    assert shares[ratios[-1]] < max(shares.values())  # not monotone: the far end loses poses again
    for _, row in table[table["evaluated"]].iterrows():  # its jobs are the jobs run alone
        assert row["feasible_pct"] == pytest.approx(shares[round(row["gear_ratio"])])
