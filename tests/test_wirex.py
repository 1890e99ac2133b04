"""Import of WireX robot files (``pipeline.wirex``, issue 54 item 3): a file written here in
WireLib's model-writer format (the layout of the IPAnema sample WireX ships) becomes a robot file
with its pulleys, platform, cable and winch data; its cable lengths are WireLib's own pulley
formula's (doInverseKinematicsPulleyEx, ported here) wherever that formula is the tangent one."""

import numpy as np
import pandas as pd
import pytest
import yaml

from conftest import command

ANCHORS = [(-2, 1.5, 2), (2, 1.5, 2), (2, -1.5, 2), (-2, -1.5, 2), (-2, 1.5, 0), (2, 1.5, 0), (2, -1.5, 0), (-2, -1.5, 0)]
PLATFORM = [(-0.06, 0.06, 0), (0.06, 0.06, 0), (0.06, -0.06, 0), (-0.06, -0.06, 0)] * 2
IDENTITY = np.eye(3)


def frame_attributes(frame):
    return " ".join(f'a{i + 1}{j + 1}="{frame[i, j]:.6f}"' for i in range(3) for j in range(3))


def wcrfx(frames=None, pattern="3R3T", radius=0.1, winch="IPAnema-Winde", cable_types=1, elasticity=110e9):
    """A robot file as WireLib's model writer lays it out."""
    frames = frames or [IDENTITY] * 8
    chains = "".join(
        f"""
            <chain id="{i + 1}" winchtype="{winch}">
                <base x="{a[0]:.6f}" y="{a[1]:.6f}" z="{a[2]:.6f}" {frame_attributes(f)} radius="{radius:.6f}" />
                <platform x="{b[0]:.6f}" y="{b[1]:.6f}" z="{b[2]:.6f}" {frame_attributes(IDENTITY)} />
            </chain>""" for i, (a, b, f) in enumerate(zip(ANCHORS, PLATFORM, frames)))
    cable = (f'    <cable name="defaultCable" elasticity="{elasticity:.6f}" radius="0.006000" breaking_load="40000.000000" '
             'damping="1.000000" weight="0.023000" minimum_load="0.000000" max_length="0.000000" meter_cost="0.000000" '
             'material="defaultMaterial" />\n') * cable_types
    return f"""<models version="0.31">
    <robot name="IPAnema" id="1.0" author="Fraunhofer IPA" generator="WireLib" description="model" motionpattern="{pattern}">
        <geometry>{chains}
        </geometry>
        <platform name="default_platform" description="default_desc" mass="25.000000" swing_angle="50.000000">
            <inertiatensor Ixx="14" />
            <centerofgravity x="0.000000" y="0.000000" z="0.050000" />
        </platform>
        <controller ipo_clock="4.000000" />
    </robot>
{cable}    <winch name="IPAnema-Winde" description="winch">
        <cable nr_cables="1" f_max="720.000000" f_hold_max="0.000000" string_orientation="0.000000"
               dl_max="0.000000" l_min="0.000000" max_velocity="2.000000" />
        <motor motor_type="servo" inertia="0.001527" mass="5.700000" angular_velocity="6000.000000" gear_ratio="3.000000" />
        <drum r_drum="0.100000" l_drum="0.300000" nr_groove="14.000000" />
    </winch>
</models>
"""


def wirelib_lengths(anchor, frame, radius, ends):
    """WireLib's doInverseKinematicsPulleyEx, per end point: b in the base frame, its distance
    from the axis bxy and height bz, BM, the free length, beta = acos(lf/BM) + acos(bz/BM)."""
    b = (ends - anchor) @ frame  # R_base^T (B - A), row by row
    bxy, bz = np.hypot(b[:, 0], b[:, 1]), b[:, 2]
    bm = np.sqrt((bxy - radius) ** 2 + bz ** 2)
    free = np.sqrt(bz ** 2 + (bxy - radius) ** 2 - radius ** 2)
    return np.arccos(free / bm) * radius + np.arccos(bz / bm) * radius + free, bxy


@pytest.fixture
def imported(tmp_path):
    (tmp_path / "IPAnema.wcrfx").write_text(wcrfx())
    done = command(tmp_path, "pipeline.wirex", "IPAnema.wcrfx", "--step", "0.25", "--out", "mine/robot/ipanema.yaml")
    assert done.returncode == 0, done.stderr
    assert "8 cables (8 over pulleys), platform 25 kg" in done.stdout and "robot=ipanema" in done.stdout
    return tmp_path


def test_the_sample_robot_imports_as_the_same_robot_typed_by_hand(imported):
    data = yaml.safe_load((imported / "mine" / "robot" / "ipanema.yaml").read_text())
    robot = data["robot"]
    np.testing.assert_array_equal(robot["anchors"], ANCHORS)  # the README's IPAnema 1, typed by hand
    np.testing.assert_array_equal(robot["attachments"], PLATFORM)
    assert robot["pulleys"] == [{"axis": [0.0, 0.0, 1.0], "radius": 0.1}] * 8
    assert robot["platform"] == {"mass": 25.0, "com": [0.0, 0.0, 0.05]}
    assert robot["cable_diameter"] == pytest.approx(0.012)
    assert robot["cable_ea"] == pytest.approx(110e9 * np.pi * 0.006 ** 2)
    assert data["tension"] == {"t_min": 0.0, "t_max": 720.0}
    assert robot["cable_mass"] == pytest.approx(0.023 / 9.81)  # WireLib's weight: N/m
    assert "l_max" not in robot and "dofs" not in robot  # max_length 0: none; 3R3T: all six freedoms


def test_the_imported_robots_lengths_are_wirelibs_own_where_its_formula_is_the_tangent(imported):
    done = command(imported, "pipeline", "--config-dir", "mine", "robot=ipanema", "output.cables=true",
                   "hydra.run.dir=out")
    assert done.returncode == 0, done.stderr
    points = pd.read_parquet(imported / "out" / "points.parquet")
    summary = pd.read_parquet(imported / "out" / "summary.parquet").iloc[0]
    assert 0 < summary["n_feasible"] < summary["n_points"] == 16 * 12 * 8
    centres = points[["x", "y", "z"]].to_numpy()
    compared = 0
    for i, name in enumerate(["1", "2", "3", "4", "5", "6", "7", "8"]):
        theirs, bxy = wirelib_lengths(np.array(ANCHORS[i], float), IDENTITY, 0.1, centres + PLATFORM[i])
        tangent = bxy >= 0.1  # WireLib's acos(bz/BM) is the tangent's angle only outside the pulley's radius
        np.testing.assert_allclose(points[f"length_{name}"].to_numpy()[tangent], theirs[tangent], rtol=1e-12)
        compared += tangent.sum()
    assert compared >= 0.99 * 8 * len(points)  # the rest: attachments within a radius of an axis


def test_a_turned_base_frame_gives_its_third_column_as_the_axis(tmp_path):
    """WireLib turns the pulley about the base frame's z axis: a frame turned -90 degrees about x
    (its z axis along +y) gives the axis [0, 1, 0]; a planar motion pattern its freedoms."""
    turned = np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])
    (tmp_path / "T.wcrfx").write_text(wcrfx(frames=[turned] * 8, pattern="1R2T"))
    done = command(tmp_path, "pipeline.wirex", "T.wcrfx", "--out", "mine/robot/t.yaml")
    assert done.returncode == 0, done.stderr
    robot = yaml.safe_load((tmp_path / "mine" / "robot" / "t.yaml").read_text())["robot"]
    assert robot["pulleys"][0]["axis"] == [0.0, 1.0, 0.0] and robot["dofs"] == ["x", "y", "rz"]


BAD = {
    "garbage": ("not xml", "not well-formed XML"),
    "truncated": (wcrfx()[: len(wcrfx()) // 2], "not well-formed XML"),
    "wrong_root": ("<robot/>", "root element <robot>, a WireX robot file has <models> with <robot>"),
    "pattern": (wcrfx(pattern="2R3T"), "motionpattern '2R3T': imported are 3R3T, 3T, 1R2T, 2T"),
    "not_a_rotation": (wcrfx(frames=[2 * IDENTITY] * 8), "chain 1 <base>: a11..a33 are not a rotation"),
    "unknown_winch": (wcrfx(winch="Other"), "chain 1: winchtype 'Other' is not a <winch> of the file"),
    "two_cable_types": (wcrfx(cable_types=2), "2 <cable> types: one is imported"),
    "negative_elasticity": (wcrfx(elasticity=-1.0), "elasticity -1 Pa"),
    "nan_radius": (wcrfx().replace('radius="0.100000"', 'radius="nan"', 1), "chain 1 <base>: radius='nan' is not finite"),
    "negative_weight": (wcrfx().replace('weight="0.023000"', 'weight="-1"'), "weight -1 N/m: need 0 <= weight"),
    "no_platform_point": (wcrfx().replace('<platform x="-0.060000"', '<other x="-0.060000"', 1),
                          "chain 1: needs a <base> and a <platform> point"),
    "missing_coordinate": (wcrfx().replace(' y="1.500000" z="2.000000"', ' z="2.000000"', 1),
                           "chain 1 <base>: y=None is not a number"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_a_file_it_cannot_import_is_one_line_exit_2_and_writes_nothing(tmp_path, case):
    text, message = BAD[case]
    (tmp_path / "bad.wcrfx").write_text(text)
    done = command(tmp_path, "pipeline.wirex", "bad.wcrfx", "--out", "mine/robot/bad.yaml")
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and message in lines[0], done.stderr
    assert not (tmp_path / "mine").exists()
