"""A catalogue actuator on any robot's static and dynamic workspace (issue 56, item 4):
``analysis=statics actuator=ID``. At rest its limits are one tension cap per cable (the torque
behind the gearbox, eq. 32, and the voltage its armature's resistance allows, eq. 34), so the
verdicts equal the statics with ``tension.t_max`` at that cap; in motion each required motion's
cable speeds and accelerations (finite differences of the lengths here) and its own wrench
(Newton-Euler written here) meet the drive's limits in an LP per pose and motion."""

import numpy as np
import pandas as pd
import pytest
from scipy.linalg import expm
from scipy.optimize import linprog

from conftest import command
from pipeline.app.problem import build_problem
from pipeline.model.actuators import actuator_model
from pipeline.model.geometry import rotation_matrices

ANCHORS = [[-2, 1.5, 2], [2, 1.5, 2], [2, -1.5, 2], [-2, -1.5, 2], [-2, 1.5, 0], [2, 1.5, 0], [2, -1.5, 0], [-2, -1.5, 0]]
ATTACHMENTS = [[-0.1, 0.1, -0.05], [0.1, 0.1, -0.05], [0.1, -0.1, -0.05], [-0.1, -0.1, -0.05], [-0.1, 0.1, 0.05],
               [0.1, 0.1, 0.05], [0.1, -0.1, 0.05], [-0.1, -0.1, 0.05]]  # the top cables to the platform's bottom
ROBOT = ["robot=points", f"robot.anchors={ANCHORS}", f"robot.attachments={ATTACHMENTS}",
         "robot.search.lo=[-1.6,-1.1,0.2]", "robot.search.hi=[1.6,1.1,1.8]", "robot.search.step=0.4",
         "robot.platform.mass=5", "robot.platform.com=[0.03,-0.02,0.01]", "robot.platform.inertia=[0.1,0.12,0.2]",
         "orientation.psi=0.1", "orientation.theta=-0.05", "tension=feasible", "tension.t_min=1"]


def rest_cap(row: dict, gear_ratio: float | None = None) -> float:
    """The largest tension (N) a catalogue row holds at rest, from its columns: the torque
    behind the gearbox tau N_V eta (eq. 32), and the torque the voltage drives through the
    armature, U k_t N_V eta / R (eq. 34 without speed terms), over the winch radius."""
    behind = (row["gear_ratio"] if gear_ratio is None else gear_ratio) * row["efficiency"]
    voltage = row["voltage_V"] * row["torque_constant_Nm_per_A"] * behind / row["resistance_ohm"]
    return min(row["torque_Nm"] * behind, voltage) / row["winch_radius_m"]


def verdicts(make_cfg, catalogue, *overrides):
    problem, grid = build_problem(make_cfg(*overrides), catalogue)
    from pipeline.workspace.kernel import evaluate_chunk
    from pipeline.workspace.verdict import classify

    raw = evaluate_chunk(problem, grid[0:len(grid)])
    margins, feasible, limiting = classify({name: raw[f"margin_{name}"] for name in problem.criteria},
                                           problem.margin_atol)
    return problem, grid, feasible, [problem.criteria[k] for k in limiting]


CRANE = ["robot=points", "robot.anchors=[[-2,1.5,2],[2,1.5,2],[2,-1.5,2],[-2,-1.5,2]]",
         "robot.attachments=[[0,0,0],[0,0,0],[0,0,0],[0,0,0]]", "robot.dofs=[x,y,z]", "robot.search.lo=[-1.6,-1.1,0]",
         "robot.search.hi=[1.6,1.1,1.6]", "robot.search.step=0.2", "tension=pinv", "tension.t_min=1",
         "robot.platform.mass=3", "wrench.fx=4"]


@pytest.mark.parametrize("base", [[*ROBOT, "robot.platform.mass=4"], CRANE], ids=["feasible, tilted", "pinv crane"])
def test_at_rest_the_drive_is_a_tension_cap_per_cable(make_cfg, catalogue, base):
    """Every Table 1 actuator (and one with another gear ratio) against the statics with
    tension.t_max at its cap written from its columns: the same verdict at every pose; where the
    cap loses poses, the drive's job names torque (actuator 3) or voltage (actuator 4, whose
    voltage binds first) as what limits them. Pulling cables on a tilted platform with an
    off-centre load (null-space test and LPs), and a crane pulled sideways under the minimum-norm
    tensions (the registry's margins)."""
    lost, held = {}, {}
    for actuator, gear in ((1, None), (2, None), (3, None), (4, None), (5, None), (3, 60.0)):
        extra = [f"actuator={actuator}"] + ([f"drive.gear_ratio={gear}"] if gear else [])
        _, grid, driven, limiting = verdicts(make_cfg, catalogue, *base, *extra)
        cap = rest_cap(catalogue.row(actuator), gear)
        _, _, capped, _ = verdicts(make_cfg, catalogue, *base, f"tension.t_max={cap}")
        assert (driven == capped).all(), (actuator, gear, int((driven != capped).sum()))
        lost[(actuator, gear)] = {name for name, kept in zip(limiting, driven) if not kept}
        held[(actuator, gear)] = int(driven.sum())
    _, _, free, _ = verdicts(make_cfg, catalogue, *base)
    assert 0 < held[(3, None)] < held[(4, None)] <= held[(1, None)] <= free.sum(), (held, free.sum())
    assert held[(3, 60.0)] > held[(3, None)]  # a higher gear ratio holds more at rest
    assert "voltage" in lost[(4, None)] and "torque" not in lost[(4, None)]
    assert "torque" in lost[(3, None)] and "voltage" not in lost[(3, None)]


def newton_euler(position, rotation, mass, com, inertia, acceleration, omega, gravity=9.81):
    """The wrench [f; M] gravity and D'Alembert's forces put on the platform (moments about its
    reference point): f = m (g - a_c), a_c = a + alpha x c + omega x (omega x c), M = c x f -
    I alpha - omega x (I omega), with c = R com and I = R I_c R^T (fixed axes)."""
    a, alpha = acceleration[:3], acceleration[3:]
    c = rotation @ com
    world = rotation @ inertia @ rotation.T
    a_c = a + np.cross(alpha, c) + np.cross(omega, np.cross(omega, c))
    force = mass * (np.array([0, 0, -gravity]) - a_c)
    return np.concatenate([force, np.cross(c, force) - world @ alpha - np.cross(omega, world @ omega)])


def length_rates(position, rotation, velocity, acceleration, omega, step=1e-4):
    """(m,) each cable's speed and acceleration by central differences of its length along the
    motion p(t) = p + v t + a t^2 / 2, R(t) = expm([omega t + alpha t^2 / 2]x) R."""
    anchors, arms = np.array(ANCHORS, float), np.array(ATTACHMENTS, float)

    def lengths(t):
        turn = omega * t + 0.5 * acceleration[3:] * t * t
        skew = np.array([[0, -turn[2], turn[1]], [turn[2], 0, -turn[0]], [-turn[1], turn[0], 0]])
        ends = position + velocity * t + 0.5 * acceleration[:3] * t * t + arms @ (expm(skew) @ rotation).T
        return np.linalg.norm(anchors - ends, axis=1)

    before, now, after = lengths(-step), lengths(0.0), lengths(step)
    return (after - before) / (2 * step), (after - 2 * now + before) / step**2


def lp_holds(position, rotation, wrench, speed, accel, act, radius, slack=0.0) -> bool:
    """Tensions t in [1, inf) with A t = -w, |R t| <= torque limit (eq. 32) and
    |G_v theta_ddot + L_v theta_dot - S_v R t| <= U (eq. 34), each limit widened by ``slack``
    of itself; the speed and acceleration limits (eqs. 30, 33) checked as they are."""
    anchors, arms = np.array(ANCHORS, float), np.array(ATTACHMENTS, float) @ rotation.T
    toward = anchors - (position + arms)
    unit = toward / np.linalg.norm(toward, axis=1, keepdims=True)
    structure = np.vstack([unit.T, np.cross(arms, unit).T])
    theta_dot, theta_ddot = speed / radius, accel / radius
    grow = 1 + slack
    if (np.abs(theta_dot) > act.speed_limit * grow).any() or (np.abs(theta_ddot) > act.accel_limit * grow).any():
        return False
    other = act.G_v * theta_ddot + act.L_v * theta_dot
    upper = np.minimum(act.torque_limit * grow, (other + act.voltage_limit * grow) / act.S_v) / radius
    lower = np.maximum(1.0 * (1 - slack), (other - act.voltage_limit * grow) / act.S_v / radius)
    if (lower > upper).any():
        return False
    found = linprog(np.zeros(8), A_eq=structure, b_eq=-wrench, bounds=list(zip(lower, upper)), method="highs")
    return found.status == 0


def test_in_motion_every_motion_meets_the_drive_with_its_own_wrench_and_cable_rates(make_cfg, catalogue):
    """platform_motion: three accelerations (linear and angular, none symmetric) at two angular
    velocities and two velocities of the reference point, actuator 4 (its voltage binds first): a
    pose holds iff every one of the twelve motions has tensions within the drive's limits for its
    own wrench (Newton-Euler here) and its own cable speeds and accelerations (finite differences
    of the lengths here), by an LP each; poses within 1e-6 of a limit are not counted."""
    accelerations = [[1.5, -0.5, 2.0, 0.0, 0.0, 0.0], [-1.0, 0.8, -1.2, 0.5, -0.3, 0.8], [0.2, 1.1, 0.4, -0.6, 0.4, 0.0]]
    omegas = [[0.0, 0.0, 6.0], [1.0, -0.8, 0.3]]
    velocities = [[0.0, 0.0, 0.0], [0.6, -0.4, 0.3]]
    problem, grid, driven, limiting = verdicts(
        make_cfg, catalogue, *ROBOT, "robot.platform.mass=3", "actuator=4",
        f"platform_motion.acceleration={accelerations}", f"platform_motion.angular_velocity={omegas}",
        f"platform_motion.velocity={velocities}")
    act = actuator_model(catalogue.row(4))
    rotation = rotation_matrices(np.array([[0.1, -0.05, 0.0]]))[0]
    com, inertia = np.array([0.03, -0.02, 0.01]), np.diag([0.1, 0.12, 0.2])
    positions = grid[0:len(grid)]
    checked = 0
    for position, held in zip(positions, driven):
        verdict = []
        for slack in (-1e-6, 1e-6):
            verdict.append(all(  # the first motion that fails decides
                lp_holds(position, rotation, newton_euler(position, rotation, 3.0, com, inertia, acceleration, omega),
                         *length_rates(position, rotation, velocity, acceleration, omega), act, 0.08, slack)
                for velocity in np.array(velocities, float) for omega in np.array(omegas, float)
                for acceleration in np.array(accelerations, float)))
        if verdict[0] == verdict[1]:
            assert held == verdict[0], position
            checked += 1
    assert checked >= 0.95 * len(positions) and 0 < driven.sum() < len(driven), (checked, driven.sum())
    assert {"torque", "voltage"} <= {name for name, h in zip(limiting, driven) if not h}


def test_a_drive_on_a_static_grid_from_the_command_line(tmp_path):
    """The job's summary names its actuator and what the drive loses. Refused in one line,
    nothing written: a drive under payload, a drive in motion under certified (a velocity, an
    acceleration or a moving path), drive.* or a velocity without an actuator, and a velocity
    that is not three finite numbers."""
    done = command(tmp_path, "pipeline", *ROBOT, "robot.platform.mass=12", "actuator=4", "hydra.run.dir=run")
    assert done.returncode == 0, done.stderr[-2000:]
    summary = pd.read_parquet(tmp_path / "run" / "summary.parquet").iloc[0]
    assert summary["actuator"] == 4 and summary["actuator_name"] == "Table 1 actuator 4"
    assert summary["lost_voltage"] > 0 and summary["lost_torque"] == 0
    for extra, message in ((["analysis=payload", "actuator=1"], "actuator=1: analysis=payload finds the largest payload"),
                           (["analysis=certified", "actuator=1", "platform_motion.acceleration=[[0.5,0,0,0,0,0]]"],
                            "actuator=1: analysis=certified: a drive in motion"),
                           (["analysis=certified", "actuator=1", "platform_motion.velocity=[0.5,0,0]"],
                            "actuator=1: analysis=certified: a drive in motion"),
                           (["analysis=certified", "actuator=1", "certified.path=[[0,0,1],[0.5,0,1]]", "certified.times=2"],
                            "actuator=1: analysis=certified: a drive in motion"),
                           (["drive.gear_ratio=10"], "drive.gear_ratio=10.0: the drive is a catalogue actuator's"),
                           (["platform_motion.velocity=[0.5,0,0]"],
                            "platform_motion.velocity: the reference point's velocity changes no wrench"),
                           (["actuator=1", "platform_motion.velocity=[0.5,0,nan]"], "platform_motion.velocity")):
        refused = command(tmp_path, "pipeline", *ROBOT, *extra, "hydra.run.dir=refused")
        assert refused.returncode == 2 and message in refused.stderr, refused.stderr[-1500:]
        assert len(refused.stderr.strip().splitlines()) == 1 and not (tmp_path / "refused").exists()


def test_the_actuator_choice_of_a_users_robot_at_rest(tmp_path, make_cfg, catalogue):
    """api.actuator_choice on the tilted robot at rest: one job per Table 1 actuator, each
    feasible share that of the statics with tension.t_max at the actuator's cap (written from its
    columns), the accepted ones those at >= 50 %, the rejected named with what removes their poses."""
    from pipeline import api

    base = [*ROBOT, "robot.platform.mass=4", "choice.required_pct=50"]
    choice = api.actuator_choice(base, folder=tmp_path / "choice")
    table = choice.table.set_index("actuator")
    for actuator in catalogue.ids:
        _, _, capped, _ = verdicts(make_cfg, catalogue, *base, f"tension.t_max={rest_cap(catalogue.row(actuator))}")
        assert table.loc[actuator, "feasible_pct"] == pytest.approx(100 * capped.mean(), abs=1e-9)
        assert table.loc[actuator, "accepted"] == (100 * capped.mean() >= 50)
    assert choice.verdict == ("actuator choice at x >= 50 %: accept 1, 2, 4; reject 3 21.85 % (lost to torque 211); "
                              "5 0.00 % (lost to torque 270)")
    assert table.loc[4, "lost_voltage"] == 132 and table.loc[4, "lost_torque"] == 0  # actuator 4: its voltage binds


def test_a_certified_job_with_a_drive_at_rest_is_the_paving_at_its_cap(tmp_path, catalogue):
    """``analysis=certified actuator=3`` from the command line: its boxes are, one for one, those of
    the same job with ``tension.t_max`` at actuator 3's rest cap written here from the catalogue's
    columns (29.80 N, below the 40 N rating), its summary names the actuator, and the cap binds
    (the 40 N job proves more inside)."""
    crane = [*CRANE[:-4], "tension=feasible", "tension.t_min=1", "robot.platform.mass=3", "wrench.fx=4",
             "analysis=certified", "certified.depth=9"]
    cap = rest_cap(catalogue.row(3))
    assert cap == pytest.approx(29.8025)
    found = {}
    for name, extra in (("driven", ["tension.t_max=40", "actuator=3"]), ("capped", [f"tension.t_max={cap!r}"]),
                        ("rated", ["tension.t_max=40"])):
        done = command(tmp_path, "pipeline", *crane, *extra, f"hydra.run.dir={name}")
        assert done.returncode == 0, done.stderr[-2000:]
        found[name] = (pd.read_parquet(tmp_path / name / "boxes.parquet"),
                       pd.read_parquet(tmp_path / name / "summary.parquet").iloc[0])
    pd.testing.assert_frame_equal(found["driven"][0], found["capped"][0])
    assert found["driven"][1]["actuator_name"] == "Table 1 actuator 3"
    assert found["rated"][1]["inside_m3"] > found["driven"][1]["inside_m3"] > 0
