"""Files users share, fuzzed (issue 38): robot files, CASPR model files and study files, each
mutated by a seeded generator from a valid one. Every case ends in one of two ways: a ConfigError
of one line (exit 2 and nothing written, end to end), or a result whose numbers hold together
(counts, verdicts and margins agree pose by pose). Never another exception, a hang or a silent
change: a mutation that leaves a file valid must give the result of the file it now is."""

from __future__ import annotations

import random
import re
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pytest
import yaml

from pipeline import caspr
from pipeline.app.plan import plan
from pipeline.app.problem import grid_size
from conftest import compute_workspace, SPREAD_ANCHORS, SPREAD_PLATFORM, command
from pipeline.errors import ConfigError
from pipeline.study import load_study, sweep_command
from pipeline.workspace.verdict import snap


CASPR_DATA = Path(__file__).parent / "data" / "caspr"
JUNK = [None, "", "abc", "a\nb: c", -1, 0, 1e308, -1e308, ".nan", ".inf", [], [[]], [1, 2], [[1, 2, 3]],
        {"a": 1}, True, [[[1]]], "1e400", [".nan", 0, 0], [[0, 0, 0]] * 50, "${oc.env:HOME}", "*alias"]
MAX_RUN_POSES = 3000  # a valid mutant is run when its grid is at most this (the rest are planned only)


def one_line(exc: ConfigError) -> str:
    text = str(exc)
    assert text and "\n" not in text and "Traceback" not in text, text
    return text


def junk(rng: random.Random):
    value = rng.choice(JUNK)
    if value == ".nan":
        return float("nan")
    if value == ".inf":
        return rng.choice([float("inf"), float("-inf")])
    return value


def mutate_tree(tree, rng: random.Random):
    """Replace, delete or add one entry somewhere in a nest of dicts and lists."""
    path, node = [], tree
    while isinstance(node, (dict, list)) and node and rng.random() < 0.7:
        key = rng.choice(list(node)) if isinstance(node, dict) else rng.randrange(len(node))
        path.append((node, key))
        node = node[key]
    if not path:
        return junk(rng) if rng.random() < 0.3 else tree
    parent, key = path[-1]
    action = rng.random()
    if action < 0.2 and isinstance(parent, dict):
        del parent[key]
    elif action < 0.3 and isinstance(parent, dict):
        parent[rng.choice(["extra", "anchor", "Search", "lo", "hydra"])] = junk(rng)
    elif action < 0.45 and isinstance(node, (int, float)) and not isinstance(node, bool):
        parent[key] = node * rng.choice([-1, 0, 1e-12, 1e12, 1.5])
    else:
        parent[key] = junk(rng)
    return tree


def consistent(points, summary) -> None:
    """The verdicts of a run hold together: counts, the gates and margins of every pose."""
    margins = points[[c for c in points.columns if c.startswith("margin_")]].to_numpy()
    assert np.isfinite(margins).all()
    assert (points["feasible"] == (snap(margins, 1e-9) >= 0).all(axis=1)).all()
    lost = {c[len("lost_"):]: n for c, n in summary.items() if c.startswith("lost_")}
    assert summary["n_feasible"] + sum(lost.values()) == summary["n_points"] == len(points)
    failing = points[~points["feasible"]]
    for name, count in lost.items():
        assert (failing["limiting"] == name).sum() == count
    assert (np.take_along_axis(
        snap(failing[[f"margin_{n}" for n in lost]].to_numpy(), 1e-9),
        np.array([list(lost).index(n) for n in failing["limiting"]], dtype=int)[:, None], axis=1) < 0).all()


def base_robot() -> dict:
    return {"defaults": ["points", "_self_"], "anchors": [list(a) for a in SPREAD_ANCHORS],
            "attachments": [list(a) for a in SPREAD_PLATFORM],
            "platform": {"mass": 1.0, "com": [0.0, 0.0, 0.0]}, "l_max": None,
            "search": {"lo": [-1.5, -1.0, 0.25], "hi": [1.5, 1.0, 1.75], "step": 0.5}}


@pytest.mark.parametrize("seed", range(4))
def test_fuzzed_robot_files_fail_in_one_line_or_give_a_consistent_result(tmp_path, catalogue, seed):
    rng = random.Random(seed)
    outcomes = {"refused": 0, "ran": 0, "planned": 0}
    for case in range(30):
        tree = base_robot()
        for _ in range(rng.randint(1, 3)):
            tree = mutate_tree(tree, rng)
        folder = tmp_path / f"{case}" / "robot"
        folder.mkdir(parents=True)
        text = yaml.safe_dump(tree) if not isinstance(tree, str) else tree
        if rng.random() < 0.1:  # an alias, or a file cut short
            text = rng.choice([text.replace("anchors:", "anchors: &a", 1) + "extra: *a\n", text[: len(text) // 2]])
        (folder / "fz.yaml").write_text(text)
        analysis = rng.choice(["statics", "payload", "cpr_wwa", "statics tension=pinv"]).split()
        argv = ["--config-dir", str(folder.parent), "robot=fz", f"analysis={analysis[0]}", *analysis[1:],
                "compute.n_jobs=1"]
        try:
            (job,) = plan(argv).jobs
        except ConfigError as exc:
            one_line(exc)
            outcomes["refused"] += 1
            continue
        if grid_size(job.cfg) > MAX_RUN_POSES:
            outcomes["planned"] += 1
            continue
        try:
            points, summary = compute_workspace(job.cfg, job.catalogue)
        except ConfigError as exc:  # a rule only the built problem can check
            one_line(exc)
            outcomes["refused"] += 1
            continue
        consistent(points, summary)
        outcomes["ran"] += 1
    assert outcomes["refused"] and outcomes["ran"], outcomes  # the generator reaches both ends


def test_fuzzed_robot_files_end_to_end_exit_2_and_write_nothing(tmp_path):
    """A sample of the refused mutants through the command line: one line, exit 2, no file."""
    rng = random.Random(99)
    tried = 0
    while tried < 4:
        tree = mutate_tree(base_robot(), rng)
        (tmp_path / "conf" / "robot").mkdir(parents=True, exist_ok=True)
        (tmp_path / "conf" / "robot" / "fz.yaml").write_text(yaml.safe_dump(tree))
        try:
            plan(["--config-dir", str(tmp_path / "conf"), "robot=fz"])
            continue
        except ConfigError:
            tried += 1
        run = tmp_path / "run"
        run.mkdir(exist_ok=True)
        done = command(run, "pipeline", "--config-dir", str(tmp_path / "conf"), "robot=fz")
        assert done.returncode == 2 and done.stderr.count("\n") == 1 and done.stderr.startswith("error: "), done.stderr
        assert list(run.iterdir()) == []


def mutate_xml(text: str, rng: random.Random) -> str:
    """One change to a CASPR file: an element dropped or doubled, a number or attribute made
    junk, or the text cut or garbled."""
    action = rng.random()
    if action < 0.1:
        return text[: rng.randrange(len(text))]
    if action < 0.15:
        at = rng.randrange(len(text))
        return text[:at] + rng.choice(["<", "&", "]]>", "\x00", "<x>"]) + text[at:]
    root = ElementTree.fromstring(text.split("?>", 1)[-1].split("]>", 1)[-1] if "DOCTYPE" in text else text)
    elements = list(root.iter())
    element = rng.choice(elements)
    parent = next((p for p in elements if element in list(p)), None)
    if action < 0.35 and parent is not None:
        parent.remove(element)
    elif action < 0.45 and parent is not None:
        parent.append(element)
    elif action < 0.75 and element.text and element.text.strip():
        element.text = rng.choice(["abc", "nan", "1e400", "", "-5", "1 2", "0 0 0 0", "inf -inf 1", "1e12 0 0"])
    elif element.attrib:
        key = rng.choice(list(element.attrib))
        element.attrib[key] = rng.choice(["", "abc", "-1", "nan", "1e400", "x\ny"])
    else:
        element.tag = rng.choice(["unknown", "cable", "link_rigid", "attachment"])
    return ElementTree.tostring(root, encoding="unicode")


@pytest.mark.parametrize("model, seed", [("Octo", 0), ("Octo", 1), ("Quad_planar", 2)])
def test_fuzzed_caspr_files_fail_in_one_line_or_import_a_robot_that_runs(tmp_path, capsys, catalogue, model, seed):
    rng = random.Random(seed)
    cables_text = (CASPR_DATA / f"{model}_cables.xml").read_text()
    bodies_text = (CASPR_DATA / f"{model}_bodies.xml").read_text()
    outcomes = {"refused": 0, "imported": 0}
    for case in range(25):
        folder = tmp_path / str(case)
        folder.mkdir()
        cables, bodies = folder / f"{model}_cables.xml", folder / f"{model}_bodies.xml"
        which = rng.random()
        cables.write_text(mutate_xml(cables_text, rng) if which < 0.6 else cables_text)
        bodies.write_text(mutate_xml(bodies_text, rng) if which >= 0.4 else bodies_text)
        out = folder / "conf" / "robot" / "fz.yaml"
        capsys.readouterr()  # only the importer's own output below (a first run's compile notes go)
        try:
            caspr.main([str(cables), "--bodies", str(bodies), "--step", "0.5", "--out", str(out)])
        except SystemExit as exit_:
            err = capsys.readouterr().err
            assert exit_.code == 2 and err.count("\n") == 1 and err.startswith("error: "), err
            assert not out.exists()
            outcomes["refused"] += 1
            continue
        capsys.readouterr()
        outcomes["imported"] += 1
        try:
            (job,) = plan(["--config-dir", str(out.parent.parent), "robot=fz", "compute.n_jobs=1"]).jobs
        except ConfigError as exc:  # e.g. a joint box too large for compute.max_poses
            one_line(exc)
            continue
        if grid_size(job.cfg) <= MAX_RUN_POSES:
            consistent(*compute_workspace(job.cfg, job.catalogue))
    assert outcomes["refused"] and outcomes["imported"], outcomes


def base_study() -> dict:
    return {"title": "t", "source": "s", "overrides": ["grid.n=2"],
            "sweep": {"actuator": "1,2", "load.mass": "0.5,1"},
            "cases": {"zero": [], "tilted": ["orientation.psi=0.1"]},
            "analyses": ["choice"],
            "figures": [{"kind": "curve", "file": "f_{case}.png", "x": "load.mass", "y": "feasible_pct",
                         "hue": "actuator", "per": "case"}]}


@pytest.mark.parametrize("seed", range(2))
def test_fuzzed_study_files_fail_in_one_line_or_plan_their_jobs(tmp_path, seed):
    rng = random.Random(seed)
    outcomes = {"refused": 0, "planned": 0}
    for case in range(40):
        tree = base_study()
        for _ in range(rng.randint(1, 2)):
            tree = mutate_tree(tree, rng)
        if isinstance(tree, dict) and rng.random() < 0.3:  # an override of junk
            tree["overrides"] = [rng.choice(["grid.n=-1", "grid.n=abc", "robot=nope", "+x=1", "load.mass=[1",
                                             "hydra.run.dir=x", "actuator=", "=1", "grid.n=1e9"])]
        name = f"fz{case}"
        (tmp_path / f"{name}.yaml").write_text(yaml.safe_dump(tree))
        try:
            study = load_study(name, tmp_path)
            for overrides in (study.cases or {"": []}).values():
                argv = sweep_command(study, list(overrides), tmp_path / "jobs", "serial")
                plan(argv[argv.index("-m"):])
        except ConfigError as exc:
            text = one_line(exc)
            assert not re.search(r"object at 0x|<class ", text), text
            outcomes["refused"] += 1
            continue
        outcomes["planned"] += 1
    assert outcomes["refused"] and outcomes["planned"], outcomes
    assert sorted(p.suffix for p in tmp_path.iterdir()) == [".yaml"] * 40  # planning writes nothing


@pytest.mark.parametrize("change, message", [
    ({"search": {"lo": [-1e308, -1, 0], "hi": [1e308, 1, 1], "step": 0.5}},
     r"^robot.search.step=0.5: the box from lo=\[-1e\+308, -1.0, 0.0\] to hi=\[1e\+308, 1.0, 1.0\] holds more grid "
     r"points than a number can count$"),  # was an OverflowError
    ({"l_max": "${oc.env:HOME}"},  # was an InterpolationValidationError
     r"^robot.l_max=.*interpolation '\$\{oc.env:HOME\}'.*could not be converted to Float$"),
    ({"l_max": "a\nb: c"}, r"^robot.l_max=a\\nb: c: .*could not be converted to Float$"),  # was two lines
])
def test_what_the_fuzzer_found_in_robot_files_stays_one_line(tmp_path, change, message):
    (tmp_path / "robot").mkdir()
    (tmp_path / "robot" / "fz.yaml").write_text(yaml.safe_dump({**base_robot(), **change}))
    with pytest.raises(ConfigError, match=message):
        plan(["--config-dir", str(tmp_path), "robot=fz"])


@pytest.mark.parametrize("change, message", [
    ({"title": None}, r"fz.yaml: title: Incompatible value 'None' for field of type 'str'$"),
    ({"analyses": [["choice"]]}, r"fz.yaml: analyses: \['choice'\] is not a string$"),  # was a TypeError
    ({"cases": {"zero": [["grid.n=3"]]}}, r"fz.yaml: cases.zero: 'ListConfig' is incompatible with type hint 'str'$"),
])
def test_what_the_fuzzer_found_in_study_files_stays_one_line(tmp_path, change, message):
    (tmp_path / "fz.yaml").write_text(yaml.safe_dump({**base_study(), **change}))
    with pytest.raises(ConfigError, match=message):
        load_study("fz", tmp_path)


def test_a_study_file_without_its_title_is_one_line(tmp_path):
    (tmp_path / "fz.yaml").write_text("source: s\n")  # was an OmegaConf traceback from to_object
    with pytest.raises(ConfigError, match=r"fz.yaml: title: .*missing mandatory value: title$"):
        load_study("fz", tmp_path)
