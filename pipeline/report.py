"""The reproduction report: ``python -m pipeline.report`` -> ``outputs/report/index.md`` and the
same as a web page with interactive 3-D views, ``outputs/report/index.html`` (``pipeline.analyses.webpage``).

Built from the studies' Parquet files and figures only (run the studies first, e.g.
``python -m pipeline.study --all`` or ``dvc repro``). For every number the papers publish that
the project computes, the paper's value, ours and the difference; then every study's figures,
copied next to the report so the folder stands alone.
"""

from __future__ import annotations

import argparse
import shutil
import secrets
import sys
from pathlib import Path
from urllib.parse import quote

import pandas as pd

from pipeline.analyses.choice import verdict
from pipeline.analyses.evidence import POINTS, scores, sensitivity
from pipeline.app.readings import describe_reading
from pipeline.analyses.figures import caption, label
from pipeline.analyses.optimise import OBJECTIVES
from pipeline.analyses.paper import TABLE2_ACCEPTED, TABLE2_FEASIBLE_PCT
from pipeline.analyses.results import table as read_table
from pipeline.errors import ConfigError, one_line, require
from pipeline.app.results import code_version, varying_settings
from pipeline.study import OUTPUT_DIR, available, load_study, studies_folder, verified_figures
from pipeline.analyses.webpage import View, write_page

REPORT_DIR = Path("outputs") / "report"


def build(studies_dir: Path = OUTPUT_DIR, out: Path = REPORT_DIR, config_dir: Path | None = None) -> Path:
    """Write the report; raises FileNotFoundError naming the first study without results.
    ``config_dir``: a user's folder: the report of the studies in its ``studies/`` (their
    figures, captions and answers; the papers' sections belong to the papers' studies)."""
    names = available(studies_folder(config_dir))
    missing = [n for n in names if not (studies_dir / n / "summary.parquet").exists()]
    if missing:
        raise FileNotFoundError(f"no results for stud{'y' if len(missing) == 1 else 'ies'} "
                                f"{', '.join(missing)} in {studies_dir}")
    _check_destination(out, studies_dir)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = _new_folder(out.parent, f".{out.name}.")
    try:
        _write(studies_dir, tmp, config_dir)
        _mark(tmp)
        if out.exists():  # a report this command wrote (checked above): swapped, then removed
            old = _new_folder(out.parent, f".{out.name}.old.")
            out.rename(old / out.name)
            tmp.rename(out)
            shutil.rmtree(old)
        else:
            tmp.rename(out)
    finally:  # a failed report (a full disk, a changed result) leaves no half-written folder
        shutil.rmtree(tmp, ignore_errors=True)
    return out / "index.md"


MARKER = ".cdpr-report"  # in every report folder: the files it holds, one relative path a line


def _check_destination(out: Path, studies_dir: Path) -> None:
    """ConfigError unless ``out`` is new, an empty folder, or a report this command wrote that
    holds only the files its marker lists: the report never deletes what it did not write (a
    user's folder, or the study results it reads)."""
    inside = [a for a, b in ((out, studies_dir), (studies_dir, out)) if a.resolve().is_relative_to(b.resolve())]
    if inside:
        raise ConfigError(f"--out={out}: overlaps --studies={studies_dir}; write the report to a folder of its own")
    if not out.exists() and not out.is_symlink():
        return
    if out.is_symlink() or not out.is_dir():
        raise ConfigError(f"--out={out}: not a folder; name a new folder or a report folder")
    if out.is_dir() and not any(out.iterdir()):
        out.rmdir()  # empty: nothing of anyone's is lost
        return
    marker = out / MARKER
    if not marker.is_file():
        raise ConfigError(f"--out={out}: holds files this command did not write (no {MARKER}); "
                          "name a new or empty folder, or a report folder")
    listed = set(marker.read_text(encoding="utf-8", errors="replace").splitlines()) | {MARKER}
    for path in sorted(out.rglob("*")):
        if path.is_symlink() or (path.is_file() and path.relative_to(out).as_posix() not in listed):
            raise ConfigError(f"--out={out}: {path.relative_to(out)} is not a file of the report; "
                              "move it out, or name another folder")


def _new_folder(parent: Path, prefix: str) -> Path:
    """A folder this call creates (never one that existed), with the umask's permissions."""
    while True:
        folder = parent / f"{prefix}{secrets.token_hex(4)}"
        try:
            folder.mkdir()
            return folder
        except FileExistsError:
            continue


def _mark(folder: Path) -> None:
    """The marker of a report folder: every file the report wrote, one relative path a line."""
    files = sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file())
    (folder / MARKER).write_text("".join(f"{name}\n" for name in files), encoding="utf-8")


def _answer(directory: Path) -> list[str]:
    """A study's answer in words, from its analysis tables: the actuator choice's verdict, the
    values of a design variable at which each actuator is accepted; and from its summary, the
    wrench directions its cables cannot produce where the structure matrix is short of rank."""
    lines = _degenerate(read_table(directory / "summary.parquet")) if (directory / "summary.parquet").exists() else []
    if (directory / "choice.parquet").exists():
        lines += [md(verdict(read_table(directory / "choice.parquet"))).capitalize() + ".", ""]
    if (directory / "best_drive.parquet").exists():
        table = read_table(directory / "best_drive.parquet")
        parts = [f"actuator {r.actuator}: R_i = {r.winch_radius_m:g} m, N_V = {r.gear_ratio:g} "
                 f"({r.best_feasible_pct:.2f} %, {r.motor_torque_demand_Nm:.3g} N m at the motor)"
                 if r.found else f"actuator {r.actuator}: none of its {r.trials} trials (best "
                 f"{r.best_feasible_pct:.2f} %)" for r in table.itertuples()]
        lines += ["The least motor torque that reaches the required share, per actuator: "
                  + "; ".join(parts) + ".", ""]
    if (directory / "exact_drive.parquet").exists():
        lines += _exact_drive(read_table(directory / "exact_drive.parquet"))
    if (directory / "acceptance.parquet").exists():
        table = read_table(directory / "acceptance.parquet")
        parts = []
        for actuator, part in table.groupby("actuator", sort=True):
            values = part.loc[part["accepted"], "value"]
            parts.append(f"actuator {actuator} at " + (", ".join(f"{v:g}" for v in values) if len(values)
                                                        else "none of the values tried"))
        lines += [f"Accepted (x ≥ {table['required_pct'].iloc[0]:g} %) by "
                  f"{md(label(table['parameter'].iloc[0]))}: " + "; ".join(parts) + ".", ""]
    return lines


def _degenerate(summary: pd.DataFrame) -> list[str]:
    """The jobs whose structure matrix is short of rank at some pose, and what their cables then
    cannot produce (the job summaries' ``deficient_rank``, ``missing_direction``: the first such
    pose of each job), the most frequent direction first."""
    if "missing_direction" not in summary or summary["missing_direction"].isna().all():
        return []
    short = summary.dropna(subset=["missing_direction"])
    counts = short.groupby(["deficient_rank", "missing_direction"], sort=False).size().sort_values(ascending=False)
    parts = [f"{md(direction)} (rank {int(rank)}, {count} job{'s' if count > 1 else ''})"
             for (rank, direction), count in counts.items()]
    return [f"Degenerate poses: in {len(short)} of {len(summary)} jobs the structure matrix is short of rank at some "
            f"pose, where the cables cannot produce " + "; ".join(parts) + " (docs/outputs.md: the jobs' logs "
            "name the first such pose).", ""]


def _exact_drive(table: pd.DataFrame) -> list[str]:
    """The search's answer per actuator (``pipeline.analyses.search``) next to the optimiser's best."""
    objective = table["objective_name"].iloc[0]
    words = OBJECTIVES[objective][1]
    with_optimiser = "agree" in table
    rows = [f"Exact to the grid, the least {md(words)} that reaches the required share, per "
            "actuator (every ratio N_V / R_i of the ranges either evaluated or excluded by a bound; "
            "docs/studies.md):", "",
            "| actuator | R_i (m) | N_V | share % | " + md(words) + " | ratios evaluated"
            + (" | optimiser's best | grid steps apart |" if with_optimiser else " |"),
            "| --- | --- | --- | --- | --- | ---" + (" | --- | --- |" if with_optimiser else " |")]
    for r in table.to_dict("records"):
        cells = ([f"{r['winch_radius_m']:g}", f"{r['gear_ratio']:g}", f"{r['feasible_pct']:.2f}",
                  f"{r[objective]:.4g}"] if r["found"] else ["none reaches it", "–", "–", "–"])
        cells.append(f"{r['evaluated']} of {r['candidates']}")
        if with_optimiser:
            best = r.get(f"optimiser_{objective}")
            cells += [f"{best:.4g}" if r["optimiser_found"] else "none",
                      f"{r['steps_apart']:g}" if r["found"] and r["optimiser_found"] else "–"]
        rows.append(f"| {r['actuator']} | " + " | ".join(cells) + " |")
    return rows + [""]


def _model(summary: pd.DataFrame) -> dict:
    """The ``model.*`` switches of a study's jobs (the same for every job), without the prefix."""
    return {key[6:]: summary[key].iloc[0] for key in summary.columns if key.startswith("model.")}


def _table2(studies_dir: Path) -> list[str]:
    choice = read_table(studies_dir / "actuator_choice" / "choice.parquet").set_index("actuator")
    choice_summary = read_table(studies_dir / "actuator_choice" / "summary.parquet")
    rows = ["## CPR-8, Table 2 (Filipovic & Kevac 2018)", "",
            "| actuator | paper x(i_a) % | ours % | difference (pp) | lost to |",
            "| --- | --- | --- | --- | --- |"]
    for actuator, paper in TABLE2_FEASIBLE_PCT.items():
        ours = choice.loc[actuator, "feasible_pct"]
        lost = ", ".join(f"{c[5:]} {int(choice.loc[actuator, c])}" for c in choice.columns
                         if c.startswith("lost_") and not c.endswith("_pct") and choice.loc[actuator, c])
        diff = round(ours - paper, 2) + 0.0  # no "-0.00"
        rows.append(f"| {actuator} | {paper:.2f} | {ours:.2f} | {diff:+.2f} | {md(lost) or '–'} |")
    accepted = sorted(int(a) for a in choice.index[choice["accepted"]])
    rows += ["", f"Accepted at x = 90 %: paper {TABLE2_ACCEPTED}, ours {accepted}.", "",
             f"Reading: {md(describe_reading(_model(choice_summary)))}. The readings are chosen on "
             "all the published evidence, not on Table 2 alone (section \"The readings against "
             "all the published evidence\" below; docs/evidence.md section 1).", ""]
    return rows + _pulling_choice(studies_dir)


def _pulling_choice(studies_dir: Path) -> list[str]:
    """CPR-ACM again with cables that only pull (study ``actuator_choice_pulling``, forces only),
    beside the minimum-norm shares of the same reading (``tension_comparison``)."""
    pulling = read_table(studies_dir / "actuator_choice_pulling" / "choice.parquet").set_index("actuator")
    survival = read_table(studies_dir / "tension_comparison" / "survival.parquet")
    paper_model = survival[(survival["wrench_rows"] == "translational") & (survival["case"] == "zero")
                           ].set_index("actuator")
    required = pulling["required_pct"].iloc[0]
    rows = ["### The same choice when the cables can only pull", "",
            "No paper number: `tension.model=feasible` (pulling tensions that meet the torque, "
            "voltage and slack limits at every acceleration vertex) in place of eq. (20)'s "
            "minimum-norm torques, both with forces only (`model.pinv_columns=translational`): "
            "with the moments too, no pose of the paper's carrier holds at zero orientation "
            "(docs/model.md section 4).", "",
            "| actuator | eq. (20) % | pulling % | accepted (eq. 20 → pulling) | pulling: lost to |",
            "| --- | --- | --- | --- | --- |"]
    for actuator, row in pulling.iterrows():
        before = paper_model.loc[actuator, "paper_pct"]
        rows.append(f"| {actuator} | {before:.2f} | {row['feasible_pct']:.2f} | "
                    f"{'yes' if before >= required else 'no'} → {'yes' if row['accepted'] else 'no'} | "
                    f"{md(row['rejected_by']) or '–'} |")
    accepted = sorted(int(a) for a in pulling.index[pulling["accepted"]])
    rows += ["", f"Accepted at x = {required:g} % with pulling cables: {accepted or 'none'}.", ""]
    return rows


def _lines_agreement(studies_dir: Path) -> list[str]:
    summary = read_table(studies_dir / "line_simulation" / "summary.parquet")
    table = summary.pivot_table(index=["model.pinv_columns", "case_label"], columns="actuator",
                                values="agreement_pct")
    rows = ["## CPR-8, straight lines against the grid (Figs. 4b, 5b, 6)", "",
            "The paper publishes no number here (Fig. 5's share is withheld); it states that "
            "lines and grid match. Share of the 216 grid points with the same verdict (%):", "",
            "| pinv columns, orientation | " + " | ".join(f"act. {a}" for a in table.columns) + " |",
            "| --- |" + " --- |" * len(table.columns)]
    for (reading, case), values in table.iterrows():
        rows.append(f"| {md(reading)}, {md(case)} | " + " | ".join(f"{v:.2f}" for v in values) + " |")
    return rows + [""]


def _irpm(studies_dir: Path) -> list[str]:
    fig13 = read_table(studies_dir / "irpm_fig13_end_ratio" / "summary.parquet")
    table = fig13.pivot_table(index="robot.r_end", columns="robot.gamma_deg", values="volume_m3")
    rows = ["## IRPM (Hamed & Zohoor), Fig. 13", "",
            "The paper withholds its point counts; its conclusions are checked in docs/evidence.md "
            "section 2. Volume (m³) at r_base = 6 m of section III's workspace (0 ≤ s, l ≤ l_max; "
            "no s_max, as the paper defines it):", "",
            "| r_end / r_base | " + " | ".join(f"γ = {g:g}°" for g in table.columns) + " |",
            "| --- |" + " --- |" * len(table.columns)]
    for r_end, values in table.iterrows():
        rows.append(f"| {r_end / 6:.1f} | " + " | ".join(f"{v:.1f}" for v in values) + " |")
    spread = table.max() / table.min()
    rows += ["", "Spread max / min over r_end / r_base (conclusion 1 says 1.00): "
             + ", ".join(f"γ = {g:g}°: {s:.2f}" for g, s in spread.items()) + ".", ""]
    return rows


def _tensions(studies_dir: Path) -> list[str]:
    table = read_table(studies_dir / "tension_comparison" / "survival.parquet")
    rows = ["## CPR-8, the paper's torques against cables that can only pull", "",
            "No paper number: the papers never check the sign of a tension. Share of the "
            "minimum-norm (pinv) feasible points that stay feasible when the tensions must pull "
            "(`tension.model=feasible`), in %, and the feasible counts pinv → pulling of 216 (with the "
            "poses only the pulling model finds feasible, *new*):", "",
            "| wrench rows, orientation | " + " | ".join(
                f"act. {a}" for a in sorted(table["actuator"].unique())) + " |",
            "| --- |" + " --- |" * table["actuator"].nunique()]
    table = table.sort_values("wrench_rows", ascending=False, kind="stable")  # the paper's first
    for (reading, case), part in table.groupby(["wrench_rows", "case_label"], sort=False):
        cells = [f"{'–' if pd.isna(r.survive_pct) else f'{r.survive_pct:.1f}'} "
                 f"({r.n_paper} → {r.n_physical}{f', {r.n_gained} new' if r.n_gained else ''})"
                 for r in part.sort_values("actuator").itertuples()]
        rows.append(f"| {md(reading)}, {md(case)} | " + " | ".join(md(c) for c in cells) + " |")
    return rows + ["", "Forces only is the paper's reading of eq. (20); forces and moments "
                   "(`full`) also keeps the carrier's orientation (docs/model.md section 4).", ""]


def _evidence(studies_dir: Path) -> list[str]:
    """Every published fact against every reading (studies ``evidence_cpr8``, ``evidence_irpm``),
    with each reading's joint score; the default reading's column first."""
    rows = ["## The readings against all the published evidence", "",
            "One row per published fact, one column per reading (the `model.*` switches that "
            "differ from the defaults). ✓ the model agrees with the paper, ✗ it does not; a count "
            "that does not agree says how many grid points it is off. Score: facts matched, then "
            "the grid points off on the others (fewer is better); docs/evidence.md sections 1 and 5 "
            "give the reasons for the defaults. *Read the other way*: the best reading were that "
            "fact's verdict inverted for every reading (its grid points left out); where it "
            "names another reading, the best score rests on that fact.", ""]
    for name, paper in (("evidence_cpr8", "CPR-8 (Filipovic & Kevac 2018)"),
                        ("evidence_irpm", "IRPM (Hamed & Zohoor)")):
        table = read_table(studies_dir / name / "evidence.parquet")
        score = scores(table)
        best_other_way = sensitivity(table)
        readings = [*score.loc[score["default"], "reading"], *score.loc[~score["default"], "reading"]]
        rows += [f"### {paper}", "",
                 "| fact | source | read the other way | " + " | ".join(md(r) for r in readings) + " |",
                 "| --- | --- | --- |" + " --- |" * len(readings)]
        for (fact, source, statement), part in table.groupby(["fact", "source", "statement"], sort=False):
            cells = part.set_index("reading").loc[readings]
            other = best_other_way[fact]
            other = "same best" if other == score["reading"].iloc[0] else f"best: {other}"
            rows.append(f"| {md(statement)} | {md(source)} | {md(other)} | " + " | ".join(
                md(("✓ " if c.matches else "✗ ") + c.value
                   + (f", {c.distance:.0f} off" if not c.matches and c.unit == POINTS else ""))
                for c in cells.itertuples()) + " |")
        by = score.set_index("reading").loc[readings]
        rows += ["| **score** | | | " + " | ".join(
            f"**{r.matched} of {r.facts}**, {r.points:g} points" for r in by.itertuples()) + " |", ""]
        best = score.iloc[0]
        rows += [f"Best joint score: {md(best['reading'])} ({best['matched']} of {best['facts']} "
                 f"facts, {best['points']:g} grid points off).", ""]
    return rows


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m pipeline.report", description=__doc__.split("\n\n")[0])
    parser.add_argument("--version", action="version", version=f"cdpr-studies {code_version()}")
    parser.add_argument("--studies", type=Path, default=OUTPUT_DIR, help="study outputs (default outputs/studies)")
    parser.add_argument("--out", type=Path, default=REPORT_DIR, help="report folder (default outputs/report)")
    parser.add_argument("--config-dir", type=Path, default=None,
                        help="your own folder: the report of the studies in its studies/")
    args = parser.parse_args(argv)
    try:
        for module in ("markdown_it", "plotly"):  # before anything is written
            require(module, "report", "the report")
        index = build(args.studies, args.out, args.config_dir)
        print(f"wrote {index.with_suffix('.html')} (open it in a browser) and {index}")
    except FileNotFoundError as exc:
        where = f" --config-dir {args.config_dir}" if args.config_dir else ""
        print(f"error: {exc}; run `python -m pipeline.study{where} --all` first", file=sys.stderr)
        raise SystemExit(2) from None
    except ConfigError as exc:  # a folder without studies
        print(f"error: {exc}", file=sys.stderr)
        raise SystemExit(2) from None
    except ValueError as exc:  # a result changed since it was written, or not Parquet
        print(f"error: unreadable study results ({one_line(exc)}); rerun the studies", file=sys.stderr)
        raise SystemExit(2) from None
    except OSError as exc:  # writing the report: a full disk, a read-only folder
        print(f"error: cannot write the report ({exc.filename or args.out}: {exc.strerror or exc})", file=sys.stderr)
        raise SystemExit(2) from None


_MARKUP = str.maketrans({"\\": "\\\\", "|": "\\|", "[": "\\[", "]": "\\]", "`": "\\`",
                         "<": "&lt;", ">": "&gt;", "&": "&amp;"})


def _write(studies_dir: Path, tmp: Path, config_dir: Path | None) -> None:
    """The report's files into the folder ``tmp``: the papers' numbers against ours and every
    study's figures, or for a user's folder (``config_dir``) her studies' figures."""
    (tmp / "figures").mkdir(parents=True)
    papers = [
        "# Reproduction report",
        "",
        f"Code version `{code_version()}`. Generated by `python -m pipeline.report` from the "
        "Parquet results of the studies (`outputs/studies/`); see docs/evidence.md for every "
        "reading behind these numbers.",
        "",
        *_table2(studies_dir),
        *_lines_agreement(studies_dir),
        *_irpm(studies_dir),
        *_tensions(studies_dir),
        *_evidence(studies_dir),
    ] if config_dir is None else [
        "# Study report",
        "",
        f"Code version `{code_version()}`. Generated by `python -m pipeline.report --config-dir "
        f"{md(str(config_dir))}` from the Parquet results of the studies in {md(str(config_dir))}/studies/.",
        "",
    ]
    lines = [*papers, "## Figures", ""]
    for name in available(studies_folder(config_dir)):
        study = load_study(name, config_dir=config_dir)
        figures = [f for f in verified_figures(studies_dir / name) if f.parent == studies_dir / name / "figures"]
        lines += [f"### {md(study.title)}", "", f"`{name}`: {md(study.source)}.", "",
                  *_answer(studies_dir / name)]
        if config_dir is not None and (studies_dir / name / "summary.parquet").exists():  # her jobs and robots
            lines += _jobs(read_table(studies_dir / name / "summary.parquet"))
        for figure in figures:
            target = tmp / "figures" / name / figure.name
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(figure, target)
            text = caption(figure)
            lines += [f"![{md(text or figure.stem)}](figures/{quote(name)}/{quote(figure.name)})", ""]
            if text:
                lines += [f"*{md(text)}*", ""]
            if figure.with_suffix(".json").exists():  # a cloud: its interactive view
                lines.append(View(figure.with_suffix(".json"), "(rotate, zoom, hover for the margins)"))
    (tmp / "index.md").write_text("\n".join(
        "*Interactive 3-D view of this figure: index.html.*\n" if isinstance(line, View) else line
        for line in lines))
    write_page(lines, tmp, "Reproduction report" if config_dir is None else "Study report")


JOB_COLUMNS = (("feasible_pct", "feasible (%)", "{:.2f}"), ("volume_m3", "volume (m³)", "{:.4g}"),
               ("mesh_volume_m3", "boundary volume (m³)", "{:.4g}"), ("max_payload_kg_median", "median payload (kg)", "{:.3g}"))
MAX_JOB_ROWS = 60  # a user study's jobs listed in the report; the rest are in its summary.parquet


def _jobs(summary: pd.DataFrame) -> list[str]:
    """A user study's jobs as a table: the settings its sweep varied, the feasible share and the
    volumes (by cells and by the boundary surface), the median largest payload where computed;
    then each robot file's description (anchors, attachments, platform mass, tension limits:
    what its jobs share). A design study's trials: those on its Pareto front first."""
    if "pareto" in summary:
        summary = summary.sort_values("pareto", ascending=False, kind="stable")
    settings = varying_settings({c: summary[c].tolist() for c in summary.columns}, ignore=("job",))
    shown = [(c, name, form) for c, name, form in JOB_COLUMNS if c in summary and summary[c].notna().any()]
    lines = ["| " + " | ".join([*(md(label(s)) for s in settings), "poses", *(name for _, name, _ in shown)]) + " |",
             "|" + " --- |" * (len(settings) + 1 + len(shown))]
    for _, row in summary.head(MAX_JOB_ROWS).iterrows():
        cells = [md(f"{row[s]:.6g}" if isinstance(row[s], float) else row[s]) for s in settings] + [f"{int(row['n_points'])}"]
        cells += [form.format(row[c]) if row[c] == row[c] else "–" for c, _, form in shown]
        lines.append("| " + " | ".join(cells) + " |")
    more = len(summary) - MAX_JOB_ROWS
    lines += [f"*… and {more} more jobs in its summary.parquet.*" if more > 0 else "", ""]
    for robot, rows in summary.groupby("robot_file", sort=True) if "robot_file" in summary else []:
        first = rows.iloc[0]
        parts = [f"{key}: {md(first[key])}" for key in ("robot.anchors", "robot.attachments", "robot.platform.mass",
                                                        "tension.t_min", "tension.t_max")
                 if key in first and rows[key].astype(str).nunique() == 1]  # what its jobs share
        lines += [f"Robot `{md(robot)}` ({md(first['robot.name'])}): " + "; ".join(parts) + ".", ""]
    return lines


def md(value) -> str:
    """A value from a result or study file as inert Markdown text: no table cell break, link,
    code span or HTML tag (``|``, ``[]``, backticks escaped, ``<>`` as entities)."""
    return str(value).translate(_MARKUP)


if __name__ == "__main__":
    main()
