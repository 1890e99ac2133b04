"""Import of CASPR model files (``pipeline.caspr``): the XML pair written here in CASPR's format
becomes a robot file, whose static workspace is computed with the body's mass (issue 15)."""

import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
import yaml
from scipy.optimize import linprog

from pipeline.model.geometry import structure_matrix

pytestmark = pytest.mark.slow

ANCHORS = [(-1.5, 1.5, 3.0), (1.5, 1.5, 3.0), (1.5, -1.5, 3.0), (-1.5, -1.5, 3.0),
           (-1.5, 1.5, 2.5), (1.5, 1.5, 2.5), (1.5, -1.5, 2.5), (-1.5, -1.5, 2.5)]
PLATFORM = [(0.1, -0.1, 0.1), (-0.1, -0.1, 0.1), (-0.1, 0.1, 0.1), (0.1, 0.1, 0.1),  # upper cables cross
            (-0.1, 0.1, -0.1), (0.1, 0.1, -0.1), (0.1, -0.1, -0.1), (-0.1, -0.1, -0.1)]


def cable(i, anchor, point, force_max, extra=""):
    return f"""
    <cable_ideal name="cable {i}" attachment_reference="joint">
      <properties><force_min>5</force_min><force_max>{force_max}</force_max></properties>
      <attachments>
        <attachment><link>0</link><location>{' '.join(map(str, anchor))}</location></attachment>
        <attachment><link>1</link><location>{' '.join(map(str, point))}</location></attachment>{extra}
      </attachments>
    </cable_ideal>"""


def cables_xml(cables):
    return ('<?xml version="1.0" encoding="utf-8"?>\n<cables default_cable_set="original">\n'
            f'  <cable_set id="original">{"".join(cables)}\n  </cable_set>\n</cables>\n')


GOOD = cables_xml([cable(i + 1, a, p, 300 if i < 4 else 150) for i, (a, p) in enumerate(zip(ANCHORS, PLATFORM))])
BODIES = """<?xml version="1.0" encoding="utf-8"?>
<links display_range="-1.5 1.5 -1.5 1.5 0 3">
  <link_rigid num="1" name="demo">
    <joint type="SPATIAL_EULER_XYZ" />
    <physical><mass>10.0</mass><com_location>0.0 0.0 -0.05</com_location></physical>
  </link_rigid>
</links>
"""


def run(cwd, module, *args):
    return subprocess.run([sys.executable, "-m", module, *args], cwd=cwd, capture_output=True,
                          text=True, timeout=300)


@pytest.fixture(scope="module")
def imported(tmp_path_factory):
    root = tmp_path_factory.mktemp("caspr")
    (root / "demo_cables.xml").write_text(GOOD)
    (root / "demo_bodies.xml").write_text(BODIES)
    done = run(root, "pipeline.caspr", "demo_cables.xml", "--bodies", "demo_bodies.xml", "--step", "0.2")
    assert done.returncode == 0, done.stderr
    assert "conf/robot/demo.yaml" in done.stdout
    return root


def test_the_robot_file_keeps_points_limits_mass_and_display_range(imported):
    text = (imported / "conf" / "robot" / "demo.yaml").read_text()
    data = yaml.safe_load(text)
    assert text.startswith("# @package _global_")
    assert data["robot"]["anchors"] == [list(a) for a in ANCHORS]
    assert data["robot"]["attachments"] == [list(p) for p in PLATFORM]
    assert data["robot"]["cable_names"] == [f"cable {i}" for i in range(1, 9)]
    assert data["robot"]["search"] == {"lo": [-1.5, -1.5, 0.0], "hi": [1.5, 1.5, 3.0], "step": 0.2,
                                       "spacing": "centres"}
    assert data["tension"] == {"t_min": 5.0, "t_max": [300.0] * 4 + [150.0] * 4}
    assert data["load"] == {"mass": 10.0, "com": [0.0, 0.0, -0.05]}


@pytest.mark.parametrize("overrides, feasible", [([], 1986), (["load.mass=0"], 169)])
def test_static_workspace_of_the_imported_robot_with_its_mass(imported, overrides, feasible):
    """Pulling tensions in [5, 300/150] N: the body's 10 kg (from the bodies file) hold the
    crossing cables taut over far more of the box than the massless platform can be braced.
    With the mass, a plain LP per pose on the weight and its moment, worked out here by hand,
    gives the same verdict at every pose."""
    out = f"out_{len(overrides)}"
    done = run(imported, "pipeline", "--config-dir", "conf", "robot=demo", "tension.model=feasible",
               *overrides, f"hydra.run.dir={out}")
    assert done.returncode == 0, done.stderr
    summary = pd.read_parquet(imported / out / "summary.parquet").iloc[0]
    assert summary["n_points"] == 15 ** 3 and summary["load.mass"] == (0.0 if overrides else 10.0)
    assert summary["n_feasible"] == feasible
    if not overrides:
        points = pd.read_parquet(imported / out / "points.parquet")
        weight = np.array([0.0, 0.0, -10.0 * 9.81])
        wrench = np.concatenate([weight, np.cross([0.0, 0.0, -0.05], weight)])
        anchors, platform = np.array(ANCHORS), np.array(PLATFORM)
        vectors = points[["x", "y", "z"]].to_numpy()[:, None, :] + platform - anchors
        unit = vectors / np.linalg.norm(vectors, axis=2, keepdims=True)
        bounds = [(5, 300)] * 4 + [(5, 150)] * 4
        found = [linprog(np.zeros(8), A_eq=a, b_eq=wrench, bounds=bounds, method="highs").status == 0
                 for a in structure_matrix(unit, np.broadcast_to(platform, unit.shape))]
        assert found == points["feasible"].tolist()


BAD = {
    "garbage": ("not xml at all", "not well-formed XML"),
    "truncated": (GOOD[: len(GOOD) // 2], "not well-formed XML"),
    "no_force_max": (GOOD.replace("<force_max>300</force_max>", "", 1), "cable 1: missing <properties/force_max>"),
    "short_location": (GOOD.replace("-1.5 1.5 3.0", "-1.5 1.5", 1), "is not 3 finite numbers"),
    "three_links": (cables_xml([cable(1, ANCHORS[0], PLATFORM[0], 300,
                                      "<attachment><link>2</link><location>0 0 0</location></attachment>")]),
                    "multi-link models are not supported"),
    "wrong_root": ("<links/>", "root element <links>"),
    "nan_force": (GOOD.replace("<force_max>150</force_max>", "<force_max>nan</force_max>", 1), "is not finite"),
    "min_above_max": (GOOD.replace("<force_max>300</force_max>", "<force_max>3</force_max>", 1),
                      "cable 1: force_min 5 and force_max 3 N: need 0 <= force_min < force_max"),
    "negative_min": (GOOD.replace("<force_min>5</force_min>", "<force_min>-5</force_min>", 1), "force_min -5"),
    "huge_max": (GOOD.replace("<force_max>300</force_max>", "<force_max>1e300</force_max>", 1), "force_max 1e+300"),
    "duplicate_name": (GOOD.replace('name="cable 2"', 'name="cable 1"', 1), "cable 1: a second cable of this name"),
    "second_anchor": (cables_xml([cable(1, ANCHORS[0], PLATFORM[0], 300,
                                        "<attachment><link>0</link><location>9 9 9</location></attachment>")]),
                      "found links ['0', '0', '1']"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_caspr_file_is_one_line_exit_2_and_writes_nothing(tmp_path, case):
    text, message = BAD[case]
    (tmp_path / "bad_cables.xml").write_text(text)
    done = run(tmp_path, "pipeline.caspr", "bad_cables.xml")
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and message in lines[0], done.stderr
    assert not (tmp_path / "conf").exists()


def test_unknown_cable_set_and_a_second_body_are_named(tmp_path):
    (tmp_path / "a_cables.xml").write_text(GOOD)
    (tmp_path / "two_bodies.xml").write_text(BODIES.replace("</links>", '<link_rigid num="2"/></links>'))
    done = run(tmp_path, "pipeline.caspr", "a_cables.xml", "--cable-set", "IROS")
    assert done.returncode == 2 and "no cable_set 'IROS' (cable sets: original)" in done.stderr
    done = run(tmp_path, "pipeline.caspr", "a_cables.xml", "--bodies", "two_bodies.xml")
    assert done.returncode == 2 and "exactly one <link_rigid> (found 2)" in done.stderr
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
    for done in (again, shipped, package):
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
    assert set(yaml.safe_load(text)) == {"defaults", "robot", "tension"}
    assert yaml.safe_load(text)["robot"]["cable_names"][0] == "one?hydra: 1"
    assert text.splitlines()[1].startswith("# Imported from CASPR: x?hydra:?  callbacks:")
