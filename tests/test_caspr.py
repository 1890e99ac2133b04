"""Import of CASPR model files (``pipeline.caspr``): the XML pair written here in CASPR's format
becomes a robot file, whose static workspace is computed with the body's mass (issue 15)."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from conftest import command
import yaml
from scipy.optimize import linprog

pytestmark = pytest.mark.slow

DATA = Path(__file__).parent / "data" / "caspr"
CABLES = (DATA / "Octo_cables.xml").read_text()  # written in CASPR's format: DOCTYPE, comments, two sets
BODIES = (DATA / "Octo_bodies.xml").read_text()  # <bodies_system>, a SPATIAL_EULER_XYZ joint with limits
ANCHORS = [(-3.0, 2.0, 3.0), (3.0, 2.0, 3.0), (3.0, -2.0, 3.0), (-3.0, -2.0, 3.0),
           (-3.0, 2.0, 0.0), (3.0, 2.0, 0.0), (3.0, -2.0, 0.0), (-3.0, -2.0, 0.0)]
PLATFORM = [(-0.1, 0.08, 0.05), (0.1, 0.08, 0.05), (0.1, -0.08, 0.05), (-0.1, -0.08, 0.05),
            (-0.1, 0.08, -0.05), (0.1, 0.08, -0.05), (0.1, -0.08, -0.05), (-0.1, -0.08, -0.05)]
COM = [0.01, -0.02, 0.03]


def cable(i, anchor, point, force_max, extra=""):
    """One <cable_ideal> as CASPR's files write it (for the bad-file cases)."""
    return f"""
    <cable_ideal name="cable {i}" attachment_reference="joint">
      <properties>
        <force_min>5</force_min>
        <force_max>{force_max}</force_max>
      </properties>
      <attachments>
        <attachment>
          <link>0</link>
          <location>{' '.join(map(str, anchor))}</location>
        </attachment>
        <attachment>
          <link>1</link>
          <location>{' '.join(map(str, point))}</location>
        </attachment>{extra}
      </attachments>
    </cable_ideal>"""


def cables_xml(cables):
    return ('<?xml version="1.0" encoding="utf-8"?>\n<!DOCTYPE cables SYSTEM "../../../../templates/cables.dtd">\n\n'
            f'<cables default_cable_set="original">\n  <cable_set id="original">{"".join(cables)}\n  </cable_set>\n'
            '</cables>\n')


GOOD = CABLES


def run(cwd, module, *args):
    """``python -m MODULE ARGS`` in ``cwd``, in this process (tests/conftest.py)."""
    return command(cwd, module, *args)


@pytest.fixture(scope="module")
def imported(tmp_path_factory):
    root = tmp_path_factory.mktemp("caspr")
    (root / "Octo_cables.xml").write_text(CABLES)
    (root / "Octo_bodies.xml").write_text(BODIES)
    done = run(root, "pipeline.caspr", "Octo_cables.xml", "--bodies", "Octo_bodies.xml", "--step", "0.5",
               "--out", "mine/robot/octo.yaml")
    assert done.returncode == 0, done.stderr
    assert "mine/robot/octo.yaml: 8 cables, platform 12.5 kg (bodies file)" in done.stdout
    assert "search box x [-2.5, 2.5], y [-1.5, 1.5], z [0.2, 2.8] m from the joint's q_min/q_max" in done.stdout
    assert "orientation.convention=xyz" in done.stdout and "robot=octo" in done.stdout
    return root


def test_a_file_of_casprs_library_format_keeps_points_limits_mass_and_the_joint_limits(imported):
    """The <bodies_system> wrapper, DOCTYPE references and comments before the root are read;
    the search box is the joint's position limits, not the display range (a plot extent)."""
    text = (imported / "mine" / "robot" / "octo.yaml").read_text()
    data = yaml.safe_load(text)
    assert text.startswith("# @package _global_")
    assert "(cable set 'original') with Octo_bodies.xml (link 'Octo platform', joint SPATIAL_EULER_XYZ)" in text
    assert data["robot"]["anchors"] == [list(a) for a in ANCHORS]
    assert data["robot"]["attachments"] == [list(p) for p in PLATFORM]
    assert data["robot"]["cable_names"] == [f"cable {i}" for i in range(1, 9)]
    assert data["robot"]["platform"] == {"mass": 12.5, "com": COM, "inertia": [0.8, 0.9, 1.1, 0.0, 0.0, 0.0]}
    assert data["robot"]["search"] == {"lo": [-2.5, -1.5, 0.2], "hi": [2.5, 1.5, 2.8], "step": 0.5,
                                       "spacing": "centres"}
    assert data["tension"] == {"t_min": 10.0, "t_max": [600.0] * 4 + [400.0] * 4}
    assert set(data) == {"defaults", "robot", "tension", "orientation"}  # no payload, no other robot's numbers
    assert data["orientation"] == {"convention": "xyz"}  # CASPR's angles mean CASPR's pose


def test_attachments_given_relative_to_the_centre_of_mass_are_the_same_points(imported):
    """CASPR's attachment_reference="com": link-1 locations relative to com_location; the set
    written so gives the joint-referenced set's points (to the file's 4 decimals)."""
    done = run(imported, "pipeline.caspr", "Octo_cables.xml", "--bodies", "Octo_bodies.xml", "--cable-set",
               "com_reference", "--out", "mine/robot/octo_com.yaml")
    assert done.returncode == 0, done.stderr
    data = yaml.safe_load((imported / "mine" / "robot" / "octo_com.yaml").read_text())
    np.testing.assert_allclose(data["robot"]["attachments"], PLATFORM, atol=1e-12)
    without = run(imported, "pipeline.caspr", "Octo_cables.xml", "--cable-set", "com_reference",
                  "--out", "mine/robot/octo_nobody.yaml")
    assert without.returncode == 2 and "relative to the centre of mass need --bodies" in without.stderr


@pytest.mark.parametrize("overrides", [[], ["load.mass=20", "load.com=[0.05,0,-0.1]"]])
def test_the_imported_robot_runs_with_the_files_mass_and_agrees_with_an_independent_lp(imported, overrides):
    """No other override than the tension model: the platform's 12.5 kg and centre of mass come
    from the bodies file, the tension limits from the cables file, the box from the joint; on a
    tilted platform (and with a payload off centre), a plain LP per pose on the weight and its
    moment about the reference point, worked out here, gives the same verdict at every pose."""
    out = f"out_{len(overrides)}"
    tilt = ["orientation.psi=0.1", "orientation.theta=-0.15"]
    done = run(imported, "pipeline", "--config-dir", "mine", "robot=octo", "tension.model=feasible", *tilt,
               *overrides, f"hydra.run.dir={out}")
    assert done.returncode == 0, done.stderr
    summary = pd.read_parquet(imported / out / "summary.parquet").iloc[0]
    assert summary["n_points"] == 10 * 6 * 5 and summary["robot.platform.mass"] == 12.5
    assert 0 < summary["n_feasible"] < summary["n_points"]
    points = pd.read_parquet(imported / out / "points.parquet")
    payload, at = (20.0, np.array([0.05, 0.0, -0.1])) if overrides else (0.0, np.zeros(3))
    mass = 12.5 + payload
    com = (12.5 * np.array(COM) + payload * at) / mass
    psi, theta = 0.1, -0.15  # the file's convention, CASPR's: R = Rx(a) Ry(b) Rz(c), c = 0
    rx = np.array([[1, 0, 0], [0, np.cos(psi), -np.sin(psi)], [0, np.sin(psi), np.cos(psi)]])
    ry = np.array([[np.cos(theta), 0, np.sin(theta)], [0, 1, 0], [-np.sin(theta), 0, np.cos(theta)]])
    rotation = rx @ ry
    weight = np.array([0.0, 0.0, -mass * 9.81])
    wrench = -np.concatenate([weight, np.cross(rotation @ com, weight)])  # what the cables must supply
    arms = np.array(PLATFORM) @ rotation.T
    vectors = points[["x", "y", "z"]].to_numpy()[:, None, :] + arms - np.array(ANCHORS)
    pulls = -vectors / np.linalg.norm(vectors, axis=2, keepdims=True)  # a cable pulls towards its anchor
    bounds = [(10, 600)] * 4 + [(10, 400)] * 4
    found = [linprog(np.zeros(8), A_eq=np.vstack([u.T, np.cross(arms, u).T]), b_eq=wrench, bounds=bounds,
                     method="highs").status == 0 for u in pulls]
    assert found == points["feasible"].tolist()


def _write(tmp_path, cables=CABLES, bodies=BODIES):
    (tmp_path / "x_cables.xml").write_text(cables)
    (tmp_path / "x_bodies.xml").write_text(bodies)
    return run(tmp_path, "pipeline.caspr", "x_cables.xml", "--bodies", "x_bodies.xml", "--out", "mine/robot/x.yaml")


JOINT = 'type="SPATIAL_EULER_XYZ"'
LIMITS = ' q_min="-2.5 -1.5 0.2 -3.1416 -3.1416 -3.1416" q_max="2.5 1.5 2.8 3.1416 3.1416 3.1416"'
BAD_BODIES = {
    "quaternion": (BODIES.replace(JOINT, 'type="S_QUATERNION"'),
                   "joint S_QUATERNION moves the platform in rx, ry, rz by a quaternion (four coordinates; "
                   "S_EULER_XYZ or S_FIXED_XYZ give angles); imported are the joints SPATIAL_EULER_XYZ, "
                   "SPATIAL_QUATERNION, T_XYZ, PLANAR_XY"),
    "universal": (BODIES.replace(JOINT, 'type="U_XY"'), "joint U_XY moves the platform in rx, ry (a universal joint)"),
    "unknown_joint": (BODIES.replace(JOINT, 'type="HINGE"'), "joint HINGE, not a CASPR joint type"),
    "two_links": (BODIES.replace("    </links>", '      <link_rigid num="2" name="arm">\n      </link_rigid>\n'
                                                  "    </links>"), "2 <link_rigid> links: only single-body models"),
    "limits_reversed": (BODIES.replace('q_min="-2.5', 'q_min="2.6'), "need q_min < q_max in x, y, z"),
    "limits_short": (BODIES.replace(LIMITS, ' q_min="0 0" q_max="1 1 1"'), "joint q_min '0 0': needs 3 finite numbers"),
    "negative_mass": (BODIES.replace("<mass>12.5</mass>", "<mass>-1</mass>"), "mass -1 must be in [0, 1e+08] kg"),
    "wrong_root": (BODIES.replace("bodies_system>", "robot>"), "root element <robot>, a CASPR bodies file"),
}


@pytest.mark.parametrize("case", sorted(BAD_BODIES))
def test_a_body_this_version_cannot_model_is_refused_with_the_reason(tmp_path, case):
    text, message = BAD_BODIES[case]
    done = _write(tmp_path, bodies=text)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and message in lines[0], done.stderr
    assert not (tmp_path / "mine").exists()


def test_a_platform_that_only_translates_keeps_its_three_freedoms(tmp_path):
    """CASPR's T_XYZ: the joint holds the orientation, the cables balance forces only."""
    assert _write(tmp_path, bodies=BODIES.replace(JOINT, 'type="T_XYZ"')).returncode == 0
    data = yaml.safe_load((tmp_path / "mine" / "robot" / "x.yaml").read_text())
    assert data["robot"]["dofs"] == ["x", "y", "z"] and data["robot"]["search"]["spacing"] == "centres"
    assert "convention" not in (tmp_path / "mine" / "robot" / "x.yaml").read_text()


def test_without_joint_limits_the_box_is_the_anchors_or_must_be_given(tmp_path):
    """Older library files give only q_initial (CoGiRo's); the anchors' bounding box is the
    box when it has a volume, and a suspended robot's flat one is refused, naming --lo/--hi."""
    legacy = BODIES.replace(LIMITS, "").replace("<bodies_system>\n", "").replace("</bodies_system>\n", "")
    done = _write(tmp_path, bodies=legacy)
    assert done.returncode == 0, done.stderr
    assert "search box x [-3, 3], y [-2, 2], z [0, 3] m from the anchors' bounding box" in done.stdout
    suspended = CABLES.replace(" 0</location>", " 3</location>")  # every anchor at the top
    (tmp_path / "flat").mkdir()
    done = _write(tmp_path / "flat", cables=suspended, bodies=legacy)
    assert done.returncode == 2 and "anchors span nothing along z (a suspended robot); give --lo x y z --hi x y z" \
        in done.stderr
    given = run(tmp_path / "flat", "pipeline.caspr", "x_cables.xml", "--bodies", "x_bodies.xml", "--lo", "-2", "-1",
                "0.5", "--hi", "2", "1", "2.5", "--out", "mine/robot/x.yaml")
    assert given.returncode == 0 and "z [0.5, 2.5] m from --lo/--hi" in given.stdout


def test_a_joint_away_from_the_frame_origin_keeps_casprs_joint_coordinates(tmp_path):
    """<parent><location>: the joint's origin in the frame; the anchors are written relative to
    it, so the searched positions are CASPR's q (a cable's length at q is the same)."""
    moved = BODIES.replace("<location>0.0 0.0 0.0</location>", "<location>0.5 -0.25 1.0</location>")
    assert _write(tmp_path, bodies=moved).returncode == 0
    data = yaml.safe_load((tmp_path / "mine" / "robot" / "x.yaml").read_text())
    np.testing.assert_allclose(data["robot"]["anchors"], np.array(ANCHORS) - [0.5, -0.25, 1.0])


BAD = {
    "garbage": ("not xml at all", "not well-formed XML"),
    "truncated": (GOOD[: len(GOOD) // 2], "not well-formed XML"),
    "no_force_max": (GOOD.replace("<force_max>600</force_max>", "", 1), "cable 1: missing <properties/force_max>"),
    "short_location": (GOOD.replace("-3 2 3<", "-3 2<", 1), "is not 3 finite numbers"),
    "three_links": (cables_xml([cable(1, ANCHORS[0], PLATFORM[0], 300,
                                      "<attachment><link>2</link><location>0 0 0</location></attachment>")]),
                    "attached to links ['0', '1', '2']: multi-link models are not supported"),
    "wrong_root": ("<links/>", "root element <links>"),
    "nan_force": (GOOD.replace("<force_max>400</force_max>", "<force_max>nan</force_max>", 1), "is not finite"),
    "min_above_max": (GOOD.replace("<force_max>600</force_max>", "<force_max>3</force_max>", 1),
                      "cable 1: force_min 10 and force_max 3 N: need 0 <= force_min < force_max"),
    "negative_min": (GOOD.replace("<force_min>10.0</force_min>", "<force_min>-5</force_min>", 1), "force_min -5"),
    "huge_max": (GOOD.replace("<force_max>600</force_max>", "<force_max>1e300</force_max>", 1), "force_max 1e+300"),
    "duplicate_name": (GOOD.replace('name="cable 3"', 'name="cable 1"', 1),
                       "cables 1 and 3 are both named 'cable 1'"),
    "routed": (cables_xml([cable(1, ANCHORS[0], PLATFORM[0], 300,
                                 "<attachment><link>0</link><location>9 9 9</location></attachment>")]),
               "3 attachments on links ['0', '0', '1']: only straight cables"),
    "pulley": (GOOD.replace("<attachment>", "<attachment_base_pulley>", 1).replace(
        "</attachment>", "</attachment_base_pulley>", 1), "<attachment_base_pulley>: only straight cables"),
    "screw_pulley": (cables_xml([cable(1, ANCHORS[0], PLATFORM[0], 300).replace(
        "<attachment>", "<screw_base_rotating_pulley><pulley_radius>0.05</pulley_radius></screw_base_rotating_pulley>"
        "<attachment>", 1)]), "<screw_base_rotating_pulley>: only straight cables"),
    "pulley_zero_axis": (cables_xml([cable(1, ANCHORS[0], PLATFORM[0], 300).replace(
        """<attachment>
          <link>0</link>
          <location>-3.0 2.0 3.0</location>
        </attachment>""", "<base_rotating_pulley><fixed_location>-3 2 3</fixed_location><pulley_radius>0.05</pulley_radius>"
        "<cable_entry_vector>0 0 0</cable_entry_vector></base_rotating_pulley>", 1)]),
        "cable_entry_vector [0.0, 0.0, 0.0]: need a radius >= 0 and a direction that is not zero"),
    "variable_stiffness": (GOOD.replace("cable_ideal", "cable_vsd_flexure_linear", 2),
                           "<cable_vsd_flexure_linear> is not an ideal or a linear-spring cable"),
    "mixed_springs": (GOOD.replace("cable_ideal", "cable_linear_spring", 2).replace(
        "<force_min>", "<K>2e4</K><force_min>", 1), "cable 2 is ideal and cable 1 a linear spring"),
    "spring_without_k": (GOOD.replace("cable_ideal", "cable_linear_spring", 2), "cable 1: missing <properties/K>"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_caspr_file_is_one_line_exit_2_and_writes_nothing(tmp_path, case):
    text, message = BAD[case]
    (tmp_path / "bad_cables.xml").write_text(text)
    done = run(tmp_path, "pipeline.caspr", "bad_cables.xml")
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and message in lines[0], done.stderr
    assert not (tmp_path / "conf").exists()


def test_an_unknown_cable_set_is_named_with_the_files_sets(tmp_path):
    (tmp_path / "a_cables.xml").write_text(GOOD)
    done = run(tmp_path, "pipeline.caspr", "a_cables.xml", "--cable-set", "IROS")
    assert done.returncode == 2 and "no cable_set 'IROS' (cable sets: original, com_reference)" in done.stderr
    assert not (tmp_path / "conf").exists()


def test_the_importer_writes_only_a_new_file_of_the_users(tmp_path):
    """It replaced any robot file without asking: run from a checkout, a model named cpr8
    replaced the shipped conf/robot/cpr8.yaml and the main job computed the imported robot."""
    from pipeline.app.resources import CONF_DIR

    (tmp_path / "demo_cables.xml").write_text(GOOD)
    (tmp_path / "cpr8_cables.xml").write_text(GOOD)
    target = tmp_path / "mine" / "robot" / "demo.yaml"
    assert run(tmp_path, "pipeline.caspr", "demo_cables.xml", "--out", str(target)).returncode == 0
    target.write_text("# edited by hand\n")
    again = run(tmp_path, "pipeline.caspr", "demo_cables.xml", "--out", str(target))
    assert again.returncode == 2 and again.stderr.strip().endswith("exists; give --force to replace it")
    assert target.read_text() == "# edited by hand\n"
    assert run(tmp_path, "pipeline.caspr", "demo_cables.xml", "--out", str(target), "--force").returncode == 0
    assert "anchors" in target.read_text()
    shipped = run(tmp_path, "pipeline.caspr", "cpr8_cables.xml", "--out", str(tmp_path / "mine" / "robot" / "cpr8.yaml"))
    assert shipped.returncode == 2 and "robot=cpr8 is a shipped robot" in shipped.stderr
    assert not (tmp_path / "mine" / "robot" / "cpr8.yaml").exists()
    inside = CONF_DIR / "robot" / "caspr_test_never_written.yaml"
    package = run(tmp_path, "pipeline.caspr", "demo_cables.xml", "--out", str(inside))
    assert package.returncode == 2 and "inside the package's own configs" in package.stderr
    assert not inside.exists()
    outside = [run(tmp_path, "pipeline.caspr", "demo_cables.xml", "--out", str(tmp_path / where))
               for where in ("etc/demo.yaml", "mine/robot/demo.yml", "mine/robot/de mo.yaml")]  # unrunnable names
    assert all(done.returncode == 2 and "a robot file DIR/robot/NAME.yaml" in done.stderr for done in outside)
    assert not (tmp_path / "etc").exists() and not (tmp_path / "mine" / "robot" / "demo.yml").exists()
    for done in (again, shipped, package, *outside):
        assert len(done.stderr.strip().splitlines()) == 1


def test_names_from_the_files_cannot_become_yaml_keys(tmp_path):
    """A source file or cable name holding line breaks was written as is into a comment or a
    scalar: the next line became a key of the robot file (a hydra.callbacks entry ran code)."""
    evil = "x\nhydra:\n  callbacks: {a: {_target_: builtins.print}}\n#"
    source = tmp_path / f"{evil}_cables.xml"
    source.write_text(GOOD.replace('name="cable 1"', 'name="one&#10;hydra: 1"'))
    target = tmp_path / "mine" / "robot" / "odd.yaml"
    done = run(tmp_path, "pipeline.caspr", str(source), "--out", str(target))
    assert done.returncode == 0, done.stderr
    text = target.read_text()
    assert set(yaml.safe_load(text)) == {"defaults", "robot", "tension"}  # no bodies file: no orientation convention
    assert yaml.safe_load(text)["robot"]["cable_names"][0] == "one?hydra: 1"
    assert text.splitlines()[1].startswith("# Imported from CASPR: x?hydra:?  callbacks:")


@pytest.mark.parametrize("joint, convention", [("S_EULER_XYZ", "xyz"), ("S_FIXED_XYZ", "zyx")])
def test_a_spherical_joint_imports_as_an_orientation_grid_that_runs(tmp_path, joint, convention):
    """The joint holds the platform at its origin: the freedoms are rx, ry, rz, the box is the
    joint's angle limits (rad), CASPR's Euler angles keep their convention; the run checks one
    orientation per row, at the origin, and agrees with the same robot typed by hand."""
    bodies = BODIES.replace(JOINT, f'type="{joint}"').replace(LIMITS, ' q_min="-0.4 -0.3 -0.2" q_max="0.4 0.3 0.2"')
    done = _write(tmp_path, bodies=bodies)
    assert done.returncode == 0, done.stderr
    assert "psi [-0.4, 0.4], theta [-0.3, 0.3], phi [-0.2, 0.2] rad" in done.stdout
    data = yaml.safe_load((tmp_path / "mine" / "robot" / "x.yaml").read_text())
    assert data["robot"]["dofs"] == ["rx", "ry", "rz"]
    assert data["robot"]["search"]["lo"] == [-0.4, -0.3, -0.2] and data["robot"]["search"]["hi"] == [0.4, 0.3, 0.2]
    assert data.get("orientation", {}).get("convention", "zyx") == convention
    run_ = run(tmp_path, "pipeline", "--config-dir", "mine", "robot=x", "robot.search.step=0.1", "tension.t_max=1000",
               "hydra.run.dir=out")
    assert run_.returncode == 0, run_.stderr
    points = pd.read_parquet(tmp_path / "out" / "points.parquet")
    assert (points[["x", "y", "z"]] == 0).all().all() and points["psi"].nunique() == 8
    robot = data["robot"]
    typed = run(tmp_path, "pipeline", "robot=points", f"robot.anchors={robot['anchors']}",
                f"robot.attachments={robot['attachments']}", "robot.dofs=[rx,ry,rz]",
                f"robot.platform.mass={robot['platform']['mass']}", f"robot.platform.com={robot['platform']['com']}",
                f"robot.search.lo={robot['search']['lo']}", f"robot.search.hi={robot['search']['hi']}",
                "robot.search.step=0.1", f"robot.search.spacing={robot['search']['spacing']}", "robot.cable_names=null",
                f"tension.t_min={data['tension']['t_min']}", "tension.t_max=1000",
                f"orientation.convention={convention}", "hydra.run.dir=typed")
    assert typed.returncode == 0, typed.stderr
    by_hand = pd.read_parquet(tmp_path / "typed" / "points.parquet")
    assert by_hand["feasible"].tolist() == points["feasible"].tolist() and 0 < points["feasible"].mean() <= 1


def test_a_file_that_names_two_cables_alike_imports_with_numbered_cables(tmp_path):
    """CASPR's own MACARM file names two cables "1": refused with the option that imports it,
    --number-cables, which names them 1, 2, ... in the file's order; the robot is otherwise the
    same (its anchors and attachments in the same order)."""
    (tmp_path / "twice_cables.xml").write_text(GOOD.replace('name="cable 3"', 'name="cable 1"', 1))
    (tmp_path / "good_cables.xml").write_text(GOOD)
    refused = run(tmp_path, "pipeline.caspr", "twice_cables.xml")
    assert refused.returncode == 2 and "--number-cables names them 1, 2, ... in the file's order" in refused.stderr
    done = run(tmp_path, "pipeline.caspr", "twice_cables.xml", "--number-cables", "--out", "mine/robot/twice.yaml")
    assert done.returncode == 0, done.stderr
    good = run(tmp_path, "pipeline.caspr", "good_cables.xml", "--out", "mine/robot/good.yaml")
    assert good.returncode == 0, good.stderr
    twice, plain = (yaml.safe_load((tmp_path / "mine" / "robot" / f"{n}.yaml").read_text())["robot"]
                    for n in ("twice", "good"))
    assert twice["cable_names"] == [str(i) for i in range(1, len(plain["anchors"]) + 1)]
    assert twice["anchors"] == plain["anchors"] and twice["attachments"] == plain["attachments"]


def caspr_pulley(fixed, entry, end, radius):
    """CASPR's closed form (BaseRotatingPulleyAttachment.ComputePulleyLeavingLocation), written
    here from its published steps: the centre in the plane of the entry vector and the cable's
    end, the leaving point r_C + rho^2 (r_B - r_C) - rho sqrt(1 - rho^2) n x (r_B - r_C), the arc
    by arccos. (n, 3) ends; the leaving points and the cable lengths from the fixed point."""
    normal = np.cross(entry, end - fixed)
    unit = normal / np.linalg.norm(normal, axis=1, keepdims=True)
    inward = np.cross(normal, entry)
    centre = fixed + radius * inward / np.linalg.norm(inward, axis=1, keepdims=True)
    rho = radius / np.linalg.norm(end - centre, axis=1, keepdims=True)
    leave = centre + rho**2 * (end - centre) - rho * np.sqrt(1 - rho**2) * np.cross(unit, end - centre)
    first, second = fixed - centre, leave - centre
    arc = radius * np.arccos(np.clip(np.einsum("nk,nk->n", first, second) / radius**2, -1, 1))
    return leave, np.linalg.norm(end - leave, axis=1) + arc


ENTRIES = [(0.0, 0.0, -1.0)] * 4 + [(0.0, 0.0, 1.0)] * 4  # the upper pulleys fed from above, the lower from below


def pulley_cables(radius):
    """The Octo set with every cable from a <base_rotating_pulley> at its anchor."""
    return cables_xml([cable(i + 1, ANCHORS[i], PLATFORM[i], 600).replace(
        f"""<attachment>
          <link>0</link>
          <location>{' '.join(map(str, ANCHORS[i]))}</location>
        </attachment>""", f"<base_rotating_pulley><fixed_location>{' '.join(map(str, ANCHORS[i]))}</fixed_location>"
        f"<pulley_radius>{radius}</pulley_radius><cable_entry_vector>{' '.join(map(str, ENTRIES[i]))}"
        "</cable_entry_vector></base_rotating_pulley>", 1) for i in range(8)])


def test_casprs_swivelling_pulleys_import_and_give_its_cable_lengths(tmp_path):
    """The robot file carries the pulleys, and the job's cable lengths (output.cables) are CASPR's
    own closed form's at every pose of the grid."""
    entries = ENTRIES
    (tmp_path / "p_cables.xml").write_text(pulley_cables(0.08))
    done = run(tmp_path, "pipeline.caspr", "p_cables.xml", "--step", "0.5", "--lo", "-2", "-1", "0.5", "--hi", "2", "1",
               "2.5", "--out", "mine/robot/p.yaml")
    assert done.returncode == 0, done.stderr
    data = yaml.safe_load((tmp_path / "mine" / "robot" / "p.yaml").read_text())
    assert data["robot"]["pulleys"] == [{"axis": list(e), "radius": 0.08} for e in entries]
    job = run(tmp_path, "pipeline", "--config-dir", "mine", "robot=p", "output.cables=true", "hydra.run.dir=out")
    assert job.returncode == 0, job.stderr
    points = pd.read_parquet(tmp_path / "out" / "points.parquet")
    centres = points[["x", "y", "z"]].to_numpy()
    assert len(centres) == 8 * 4 * 4  # the cells' centres
    for i in range(8):
        _, lengths = caspr_pulley(np.array(ANCHORS[i]), np.array(entries[i]), centres + PLATFORM[i], 0.08)
        np.testing.assert_allclose(points[f"length_cable {i + 1}"], lengths, rtol=1e-12)


def test_an_imported_pulley_robot_agrees_pose_by_pose_with_an_lp_on_casprs_geometry(tmp_path):
    """With its bodies file (12.5 kg), tilted, cables in [5, 600] N (the file's): the job's verdicts are a plain
    LP's on the directions from CASPR's own leaving points, and differ from the LP's on the
    directions from the anchors (the pulleys matter to the verdict, the test can tell)."""
    (tmp_path / "q_cables.xml").write_text(pulley_cables(0.25))
    (tmp_path / "Octo_bodies.xml").write_text(BODIES)
    done = run(tmp_path, "pipeline.caspr", "q_cables.xml", "--bodies", "Octo_bodies.xml", "--step", "0.25",
               "--out", "mine/robot/q.yaml")
    assert done.returncode == 0, done.stderr
    tilt = ["orientation.psi=0.2", "orientation.theta=-0.3"]
    job = run(tmp_path, "pipeline", "--config-dir", "mine", "robot=q", "tension.model=feasible",
              *tilt, "hydra.run.dir=out")
    assert job.returncode == 0, job.stderr
    points = pd.read_parquet(tmp_path / "out" / "points.parquet")
    psi, theta = 0.2, -0.3
    rx = np.array([[1, 0, 0], [0, np.cos(psi), -np.sin(psi)], [0, np.sin(psi), np.cos(psi)]])
    ry = np.array([[np.cos(theta), 0, np.sin(theta)], [0, 1, 0], [-np.sin(theta), 0, np.cos(theta)]])
    rotation = rx @ ry
    weight = np.array([0.0, 0.0, -12.5 * 9.81])
    wrench = -np.concatenate([weight, np.cross(rotation @ np.array(COM), weight)])
    arms = np.array(PLATFORM) @ rotation.T
    ends = points[["x", "y", "z"]].to_numpy()[:, None, :] + arms
    starts = np.stack([caspr_pulley(np.array(ANCHORS[i]), np.array(ENTRIES[i]), ends[:, i], 0.25)[0]
                       for i in range(8)], axis=1)
    verdicts = []
    for begin in (starts, np.broadcast_to(np.array(ANCHORS, float), ends.shape)):
        pulls = (begin - ends) / np.linalg.norm(begin - ends, axis=2, keepdims=True)
        verdicts.append([linprog(np.zeros(8), A_eq=np.vstack([u.T, np.cross(arms, u).T]), b_eq=wrench,
                                 bounds=[(5, 600)] * 8, method="highs").status == 0 for u in pulls])
    assert verdicts[0] == points["feasible"].tolist()
    assert 0 < sum(verdicts[0]) < len(points) and verdicts[1] != verdicts[0]


def test_casprs_linear_spring_cables_import_with_their_stiffness(tmp_path):
    """<cable_linear_spring> with <K> (CASPR: k = K / length) becomes robot.cable_ea, and the
    imported robot's stiffness criterion runs on it."""
    springs = GOOD.replace("cable_ideal", "cable_linear_spring").replace("<force_min>", "<K>30000</K><force_min>")
    (tmp_path / "s_cables.xml").write_text(springs)
    (tmp_path / "Octo_bodies.xml").write_text(BODIES)
    done = run(tmp_path, "pipeline.caspr", "s_cables.xml", "--bodies", "Octo_bodies.xml", "--step", "0.5",
               "--out", "mine/robot/s.yaml")
    assert done.returncode == 0, done.stderr
    assert yaml.safe_load((tmp_path / "mine" / "robot" / "s.yaml").read_text())["robot"]["cable_ea"] == 30000.0
    job = run(tmp_path, "pipeline", "--config-dir", "mine", "robot=s", "tension.model=feasible", "hydra.run.dir=out",
              "+criteria.stiffness={translational: 1000, rotational: 0, frequency: 1}")  # the file's inertia
    assert job.returncode == 0, job.stderr
    points = pd.read_parquet(tmp_path / "out" / "points.parquet")
    assert "margin_stiffness" in points and points["stiffness_translational_N_per_m"].notna().any()
    assert (points["stiffness_frequency_Hz"] > 0).any()


def test_an_inertia_about_the_joint_moves_to_the_centre_of_mass(tmp_path):
    """ref="joint": I_G = I_O - m (|c|^2 I - c c') (parallel axes, as CASPR reads it); one with a
    negative principal moment about the centre is refused in one line (a planar model's Izz
    alone is not: tests/test_freedoms.py)."""
    about_joint = BODIES.replace('<inertia ref="com">', '<inertia ref="joint">')
    assert _write(tmp_path, bodies=about_joint).returncode == 0
    written = yaml.safe_load((tmp_path / "mine" / "robot" / "x.yaml").read_text())["robot"]["platform"]["inertia"]
    com = np.array(COM)
    expected = np.diag([0.8, 0.9, 1.1]) - 12.5 * (com @ com * np.eye(3) - np.outer(com, com))
    np.testing.assert_allclose(written, [*np.diag(expected), expected[0, 1], expected[0, 2], expected[1, 2]], rtol=1e-12)
    flat = BODIES.replace("<Izz>1.1</Izz>", "<Izz>-1.1</Izz>")
    done = _write(tmp_path / "bad", bodies=flat) if (tmp_path / "bad").mkdir() is None else None
    assert done.returncode == 2 and "has a negative principal moment (-1.1 kg m^2)" in done.stderr
