"""The reproduction report is built from study Parquet files only; dvc.yaml covers every study."""

import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from PIL import Image
import yaml

import pipeline.report
from pipeline.analyses.choice import choose
from pipeline.analyses.results import StudyResults
from pipeline.analyses.survival import survival
from pipeline.analyses.views import robot_traces, write_view
from pipeline.app.results import DIGESTS_KEY, digests_json, write_parquet
from pipeline.workspace.lines import simulate_lines
from pipeline.study import available, record_figures
from pipeline.app.problem import build_problem
from conftest import compute_workspace

STUDIES = ["actuator_choice", "actuator_choice_pulling", "line_simulation", "irpm_fig13_end_ratio",
           "tension_comparison", "evidence_cpr8", "evidence_irpm"]

REPO = Path(__file__).resolve().parent.parent


def save(frame, path, extra=None):
    """A study's table as the study writes it (with the digest of its rows)."""
    write_parquet(frame, path, "test", extra)


@pytest.fixture
def studies(built_studies, tmp_path):
    """A copy of :func:`built_studies` of the test's own (tests change it)."""
    shutil.copytree(built_studies, tmp_path / "studies")
    return tmp_path / "studies"


@pytest.fixture(scope="module")
def built_studies(tmp_path_factory, make_cfg, catalogue):
    root = tmp_path_factory.mktemp("built") / "studies"
    for name in STUDIES:
        (root / name / "figures").mkdir(parents=True)
    summary = pd.DataFrame([compute_workspace(make_cfg(f"actuator={a}"), catalogue)[1] for a in range(1, 6)])
    save(summary, root / "actuator_choice" / "summary.parquet")
    save(choose(summary), root / "actuator_choice" / "choice.parquet")
    _png(root / "actuator_choice" / "figures" / "fig9.png")
    _png(root / "actuator_choice" / "figures" / "fig8_workspace_actuator4.png")
    points, _ = compute_workspace(make_cfg("actuator=4"), catalogue)  # its feasible set as a surface, the robot
    robot = build_problem(make_cfg("actuator=4"), catalogue)[0].robot
    write_view([(points, "feasible", None)], "actuator 4", False,
               root / "actuator_choice" / "figures" / "fig8_workspace_actuator4.json",
               robot_traces(robot, np.array([1.6, 1.1, -1.1]), np.eye(3)))
    pulling = pd.DataFrame([compute_workspace(make_cfg("tension=feasible", f"actuator={a}",
                                                       "model.pinv_columns=translational"), catalogue)[1]
                            for a in range(1, 6)])
    save(pulling, root / "actuator_choice_pulling" / "summary.parquet")
    save(choose(pulling), root / "actuator_choice_pulling" / "choice.parquet")
    configs = [make_cfg("analysis=lines", f"actuator={a}") for a in (1, 2)]
    lines = pd.DataFrame([simulate_lines(cfg, *build_problem(cfg, catalogue))[2] for cfg in configs])
    lines = lines.assign(case="zero", case_label="zero orientation")
    save(lines, root / "line_simulation" / "summary.parquet")
    irpm = pd.DataFrame([compute_workspace(make_cfg("robot=irpm6", "tension.t_max=null", f"robot.r_end={r}",
                                                    f"robot.gamma_deg={g}"), catalogue)[1]
                         for r in (1.2, 6.0) for g in (0, 30)])
    save(irpm, root / "irpm_fig13_end_ratio" / "summary.parquet")
    rows = []
    for model in ("pinv", "feasible"):
        for a in range(1, 6):
            points, row = compute_workspace(make_cfg(f"tension.model={model}", f"actuator={a}",
                                                     "model.pinv_columns=translational"), catalogue)
            (root / "tension_comparison" / "jobs" / f"{model}{a}").mkdir(parents=True)
            job = root / "tension_comparison" / "jobs" / f"{model}{a}"
            save(points, job / "points.parquet")
            save(pd.DataFrame([row]), job / "summary.parquet", {DIGESTS_KEY: digests_json([job / "points.parquet"])})
            rows.append({**row, "job": f"{model}{a}", "case": "zero", "case_label": "zero orientation"})
    save(pd.DataFrame(rows), root / "tension_comparison" / "summary.parquet")
    comparison = survival(StudyResults(root / "tension_comparison"))
    save(comparison, root / "tension_comparison" / "survival.parquet")
    for name, fact, unit in (("evidence_cpr8", "Table 2", "grid points"), ("evidence_irpm", "Fig. 13", "comparisons")):
        save(pd.DataFrame([{"fact": "f", "source": fact, "statement": "a | claim", "reading": reading,
                       "value": value, "matches": matches, "distance": distance, "unit": unit,
                       "default": reading == "default"}
                      for reading, value, matches, distance in (("default", "216 of 216", True, 0.0),
                                                                ("jdot=true", "212 of 216", False, 4.0))
                      ]), root / name / "evidence.parquet")
        save(pd.DataFrame({"job": ["x"]}), root / name / "summary.parquet")
    for name in STUDIES:  # what a study records of the figures it drew
        record_figures(root / name)
    return root


def test_report_compares_paper_and_ours_and_carries_the_figures(studies, tmp_path, monkeypatch):
    monkeypatch.setattr(pipeline.report, "available", lambda folder: STUDIES)
    index = pipeline.report.build(studies, tmp_path / "report")
    text = index.read_text()
    assert "| 4 | 87.04 | 85.19 | -1.85 | voltage 32 |" in text
    assert "| 2 | 96.30 | 96.30 | +0.00 | torque 8 |" in text
    assert "Accepted at x = 90 %: paper [1, 2], ours [1, 2]." in text
    assert "| 1 | 100.00 | 66.67 | yes → no | slack 72 |" in text  # cables that only pull
    assert "| 5 | 11.11 | 14.81 | no → no | slack 72, torque 112 |" in text
    assert "Accepted at x = 90 % with pulling cables: none." in text
    assert "| full, zero orientation | 100.00 | 94.44 |" in text
    assert "| 0.2 | 235.2 | 88.0 |" in text and "| 1.0 | 235.2 | 88.0 |" in text
    assert "γ = 0°: 1.00, γ = 30°: 1.00." in text  # section III: the spread over r_end
    assert "| translational, zero orientation | 66.7 (216 → 144) |" in text
    # actuator 5: every paper point survives and 8 more hold (was "100.0 (24 → 32)": 32 of 24?)
    assert "| 100.0 (24 → 32, 8 new) |" in text
    assert "| fact | source | read the other way | default | jdot=true |" in text  # default first
    # one fact: read the other way, the other reading matches it and wins
    assert "| a \\| claim | Table 2 | best: jdot=true | ✓ 216 of 216 | ✗ 212 of 216, 4 off |" in text
    assert "| a \\| claim | Fig. 13 | best: jdot=true | ✓ 216 of 216 | ✗ 212 of 216 |" in text  # pairs: no points off
    assert "| **score** | | | **1 of 1**, 0 points | **0 of 1**, 4 points |" in text
    assert "Best joint score: default (1 of 1 facts, 0 grid points off)." in text
    assert "![fig9](figures/actuator_choice/fig9.png)" in text
    assert (tmp_path / "report" / "figures" / "actuator_choice" / "fig9.png").read_bytes() == (
        studies / "actuator_choice" / "figures" / "fig9.png").read_bytes()
    assert "*Interactive 3-D view of this figure: index.html.*" in text


def _png(path, caption=None):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(2, 1))
    fig.subplots().plot([0, 1], [0, 1])
    fig.savefig(path, metadata={"Description": caption} if caption else None)


def test_the_report_gives_each_studys_answer_and_the_figures_captions(studies, tmp_path, monkeypatch,
                                                                      make_cfg, catalogue):
    """Captions come from the figures (their PNG Description, written by pipeline.analyses.figures),
    answers from the analysis tables: the choice's verdict, a design study's accepted values."""
    from pipeline.analyses.choice import acceptance

    _png(studies / "actuator_choice" / "figures" / "fig9.png", "Feasible share | per actuator")
    design = studies / "design_mass"
    (design / "figures").mkdir(parents=True)
    summary = pd.DataFrame([{**compute_workspace(make_cfg(f"actuator={a}", f"robot.platform.mass={m}"), catalogue)[1],
                             "job": f"{a}-{m}"} for a in (1, 3) for m in (0.5, 4.0)])
    save(summary, design / "summary.parquet")
    save(acceptance(summary), design / "acceptance.parquet")
    record_figures(studies / "actuator_choice")
    record_figures(design)
    monkeypatch.setattr(pipeline.report, "available", lambda folder: [*STUDIES, "design_mass"])
    text = pipeline.report.build(studies, tmp_path / "report").read_text()
    assert ("Actuator choice at x &gt;= 90 %: accept 1, 2; reject 3 85.19 % (lost to torque 32); "
            "4 85.19 % (lost to voltage 32); 5 0.00 % (lost to torque 216).") in text
    assert "Accepted (x ≥ 90 %) by carried mass m (kg): actuator 1 at 0.5; actuator 3 at 0.5." in text
    assert "![Feasible share \\| per actuator](figures/actuator_choice/fig9.png)" in text
    assert "*Feasible share \\| per actuator*" in text
    # the CPR-8 at the zero orientation: rank 5 everywhere (docs/model.md section 1), said per study
    direction = summary["missing_direction"].iloc[0]
    assert direction.startswith("moment about z")
    assert (f"Degenerate poses: in 4 of 4 jobs the structure matrix is short of rank at some pose, where the cables "
            f"cannot produce {direction} (rank 5, 4 jobs)") in text



def test_html_page_has_the_tables_figures_and_views_and_needs_no_network(studies, tmp_path, monkeypatch):
    monkeypatch.setattr(pipeline.report, "available", lambda folder: STUDIES)
    pipeline.report.build(studies, tmp_path / "report")
    page = (tmp_path / "report" / "index.html").read_text()
    assert "<td>4</td>\n<td>87.04</td>\n<td>85.19</td>" in page.replace(' style="text-align:right"', "")
    assert '<img src="figures/actuator_choice/fig9.png" alt="fig9"' in page
    assert page.count('<figure class="view"') == 1
    assert '"lost to voltage (32)"' in page and '"feasible set (184)"' in page  # actuator 4
    assert '"cables at (1.6, 1.1, -1.1) m"' in page and '"anchors"' in page
    assert (tmp_path / "report" / "plotly.min.js").stat().st_size > 1_000_000  # shipped, not fetched
    assert not re.findall(r'(?:src|href)="(?:https?:)?//', page)


@pytest.mark.slow
def test_html_page_opens_in_headless_chromium(studies, tmp_path, monkeypatch):
    """scripts/check_report.py: every image loads, the 3-D view draws, no JavaScript error;
    and it fails when an image is missing. Chromium comes from scripts/install_chromium.sh."""
    monkeypatch.setattr(pipeline.report, "available", lambda folder: STUDIES)
    pipeline.report.build(studies, tmp_path / "report")
    install = subprocess.run(["bash", str(REPO / "scripts" / "install_chromium.sh")],
                             capture_output=True, text=True, timeout=900)
    assert install.returncode == 0, install.stderr
    check = [sys.executable, str(REPO / "scripts" / "check_report.py"), str(tmp_path / "report")]
    done = subprocess.run([*check, "--screenshot", str(tmp_path / "shot.png")],
                          capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "(0 broken), 1 of 1 3-D views drawn, 0 errors" in done.stdout
    assert (tmp_path / "shot.png").read_bytes()[:4] == b"\x89PNG"
    sys.path.insert(0, str(REPO / "scripts"))  # its --view screenshot, without checking the page again
    try:
        from check_report import screenshot
    finally:
        sys.path.remove(str(REPO / "scripts"))
    screenshot(tmp_path / "report", tmp_path / "view.png", view=1)
    pixels = np.asarray(Image.open(tmp_path / "view.png").convert("RGB"), dtype=int)
    assert (pixels[-25:] > 245).all()  # the bottom of the view is page: the scene is not cut off
    red, green, blue = pixels[..., 0], pixels[..., 1], pixels[..., 2]
    surface = (green > red + 40) & (green > blue + 10)  # the feasible set's surface (#009e73, blended)
    dark = (red < 70) & (green < 70) & (blue < 70)  # anchors, cables and frame
    assert surface.sum() > 20_000 and dark.sum() > 300, (surface.sum(), dark.sum())
    (tmp_path / "report" / "figures" / "actuator_choice" / "fig9.png").unlink()
    broken = subprocess.run(check, capture_output=True, text=True, timeout=900)
    assert broken.returncode == 1 and "(1 broken)" in broken.stdout


def test_report_names_the_studies_without_results(tmp_path):
    with pytest.raises(FileNotFoundError, match="actuator_choice"):
        pipeline.report.build(tmp_path, tmp_path / "report")
    assert not (tmp_path / "report").exists()


def test_dvc_yaml_has_one_stage_per_study_and_a_report_on_all_of_them():
    dvc = yaml.safe_load((REPO / "dvc.yaml").read_text())
    stages = dvc["stages"]
    assert stages["study"]["foreach"] == available()
    assert stages["study"]["do"]["cmd"] == "python -m pipeline.study ${item} --params params.yaml --out outputs/studies"
    assert {f"outputs/studies/{n}" for n in available()} <= set(stages["report"]["deps"])
    for dep in stages["study"]["do"]["deps"]:
        assert (REPO / dep.replace("${item}", available()[0])).exists()


def test_every_dvc_plot_names_columns_its_series_has_and_every_study_is_a_metric():
    """A study's x key renamed (design_mass: load.mass -> robot.platform.mass) must not leave a
    DVC plot pointing at a column its CSV will not have: the columns the study's curve writes
    (``figures._series``: x, then y or one column per hue value) are the plot's."""
    from pipeline.analyses.figures import _field
    from pipeline.study import load_study

    dvc = yaml.safe_load((REPO / "dvc.yaml").read_text())
    curves = [next(iter(p.values())) for p in dvc["plots"] if isinstance(p, dict)]
    assert len(curves) >= 7
    for curve in curves:
        for path, columns in curve["y"].items():
            _, _, study, _, name = Path(path).with_suffix("").parts
            figure = next(f for f in load_study(study).figures if Path(f.file).stem == name)
            assert curve["x"] == _field(figure.x), (path, curve["x"], figure.x)
            prefix = f"{_field(figure.hue)}_" if figure.hue else None
            assert all(c.startswith(prefix) for c in columns) if prefix else columns == [_field(figure.y)], path
    assert dvc["metrics"] == [f"outputs/studies/{n}/metrics.json" for n in available()]


def test_strings_from_result_files_cannot_break_the_report():
    """A criterion, case or catalogue string in a Parquet file is inert text in the Markdown:
    no table cell break, no link, no code span, no HTML tag."""
    from pipeline.report import md

    assert md("x | <script>alert(1)</script> [a](http://e) `c`") == (
        "x \\| &lt;script&gt;alert(1)&lt;/script&gt; \\[a\\](http://e) \\`c\\`")
    assert md("torque 8, tension_max 3") == "torque 8, tension_max 3"


def test_the_report_refuses_an_edited_result_and_a_full_disk_leaves_no_folder(studies, tmp_path, monkeypatch, capsys):
    """The report reads every table through the digest written with it: an edited
    choice.parquet (the verdict of Table 2, its metadata kept) is one line and exit 2, not a
    report. A write that fails (a full disk) is said as such, and leaves no half-written report
    folder behind (it left .report.tmp and blamed the results)."""
    import errno

    import pyarrow as pa
    import pyarrow.parquet as pq

    monkeypatch.setattr(pipeline.report, "available", lambda folder: STUDIES)
    path = studies / "actuator_choice" / "choice.parquet"
    good = path.read_bytes()
    table = pq.read_table(path)
    index = table.column_names.index("accepted")
    edited = table.set_column(index, "accepted", pa.array([True] * table.num_rows))
    pq.write_table(edited.replace_schema_metadata(table.schema.metadata), path)
    with pytest.raises(SystemExit) as raised:
        pipeline.report.main(["--studies", str(studies), "--out", str(tmp_path / "report")])
    err = capsys.readouterr().err.strip().splitlines()
    assert raised.value.code == 2 and len(err) == 1
    assert f"{path}: its rows changed since it was written" in err[0]
    path.write_bytes(good)

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device", str(tmp_path / ".report.tmp" / "index.html"))

    monkeypatch.setattr(pipeline.report, "write_page", full)
    with pytest.raises(SystemExit) as raised:
        pipeline.report.main(["--studies", str(studies), "--out", str(tmp_path / "report")])
    err = capsys.readouterr().err.strip().splitlines()
    assert raised.value.code == 2 and err == [
        f"error: cannot write the report ({tmp_path / '.report.tmp' / 'index.html'}: No space left on device)"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["studies"]


def test_the_report_never_deletes_what_it_did_not_write(studies, tmp_path, monkeypatch, capsys):
    """--out is a new folder, an empty one, or a report folder this command wrote (its marker
    lists its files): a folder of the user's, a report folder the user added a file to, the
    study results themselves and a plain file are each one line and exit 2, every byte kept.
    A report folder is replaced whole on a rerun."""
    monkeypatch.setattr(pipeline.report, "available", lambda folder: STUDIES)

    def report(out):
        with pytest.raises(SystemExit) as raised:
            pipeline.report.main(["--studies", str(studies), "--out", str(out)])
        return raised.value.code, capsys.readouterr().err.strip().splitlines()

    thesis = tmp_path / "thesis"
    (thesis / "chapter").mkdir(parents=True)
    (thesis / "chapter" / "notes.md").write_text("three years of work")
    assert report(thesis) == (2, [f"error: --out={thesis}: holds files this command did not write (no .cdpr-report); "
                                  "name a new or empty folder, or a report folder"])
    assert (thesis / "chapter" / "notes.md").read_text() == "three years of work"
    before = sorted(p.relative_to(studies) for p in studies.rglob("*"))
    for out in (studies, studies / "actuator_choice", tmp_path):  # the results, inside them, around them
        code, err = report(out)
        assert code == 2 and len(err) == 1 and "overlaps --studies" in err[0], out
    assert sorted(p.relative_to(studies) for p in studies.rglob("*")) == before
    plain = tmp_path / "report.txt"
    plain.write_text("mine")
    assert report(plain) == (2, [f"error: --out={plain}: not a folder; name a new folder or a report folder"])
    assert plain.read_text() == "mine"

    out = tmp_path / "report"
    out.mkdir()  # empty: taken
    pipeline.report.main(["--studies", str(studies), "--out", str(out)])
    assert capsys.readouterr().out == f"wrote {out / 'index.html'} (open it in a browser) and {out / 'index.md'}\n"
    listed = (out / ".cdpr-report").read_text().splitlines()
    assert "index.md" in listed and "figures/actuator_choice/fig9.png" in listed
    (out / "figures" / "actuator_choice" / "fig9.png").unlink()  # a file of its own may go missing
    pipeline.report.main(["--studies", str(studies), "--out", str(out)])  # rerun: replaced whole
    assert (out / "figures" / "actuator_choice" / "fig9.png").is_file()
    (out / "my_notes.md").write_text("mine")
    code, err = report(out)
    assert code == 2 and err == [f"error: --out={out}: my_notes.md is not a file of the report; move it out, "
                                 "or name another folder"]
    assert (out / "my_notes.md").read_text() == "mine"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report", "report.txt", "studies", "thesis"]


def test_a_figure_changed_added_or_lost_since_the_study_drew_it_is_one_line(studies, tmp_path, monkeypatch, capsys):
    """Figures are guarded like the tables: the study records each file of figures/ with its
    digest, and the report refuses a figure edited, added or missing since (it copied any PNG
    it found into the report)."""
    monkeypatch.setattr(pipeline.report, "available", lambda folder: STUDIES)
    figure = studies / "actuator_choice" / "figures" / "fig9.png"
    good = figure.read_bytes()

    def report():
        with pytest.raises(SystemExit) as raised:
            pipeline.report.main(["--studies", str(studies), "--out", str(tmp_path / "report")])
        err = capsys.readouterr().err.strip().splitlines()
        assert raised.value.code == 2 and len(err) == 1, err
        return err[0]

    figure.write_bytes(good[:-10] + b"0123456789")
    assert f"{figure}: changed since the study drew it" in report()
    figure.write_bytes(good)
    (figure.parent / "extra.png").write_bytes(good)
    assert f"{figure.parent / 'extra.png'}: not a figure the study drew" in report()
    (figure.parent / "extra.png").unlink()
    figure.unlink()
    assert f"{figure}: missing" in report()
    assert not (tmp_path / "report").exists()
