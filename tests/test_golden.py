"""Every case of the golden file (tests/golden.py): the model gives today the numbers it
pinned, counts exactly and shares to 1e-9 relative. A change that moves one is either a defect
or an intended change of the model, regenerated with ``python tests/golden.py``."""

import re
from pathlib import Path

import pytest

from golden import cases, compute, values

CASES = cases()


@pytest.mark.parametrize("name", sorted(CASES))
def test_the_model_gives_the_golden_numbers(catalogue, name):
    case = CASES[name]
    found = compute(case, catalogue)
    for key, pinned in case["values"].items():
        (each,) = case["each"].values()
        assert len(pinned) == len(each), (name, key)
        if all(isinstance(value, int) for value in pinned):
            assert found[key] == pinned, (name, key)
        else:
            assert found[key] == pytest.approx(pinned, rel=1e-9), (name, key)


def test_the_golden_file_is_data_the_tests_can_trust():
    """Each case sweeps one key over at least one value and pins at least one summary key, with
    one value per setting (a regeneration that lost a value would fail here, not pass empty)."""
    assert len(CASES) >= 20
    for name, case in CASES.items():
        assert set(case) == {"overrides", "each", "values"}, name
        (settings,) = case["each"].values()
        assert settings and case["values"], name
        assert all(len(pinned) == len(settings) for pinned in case["values"].values()), name


MODEL_MD = Path(__file__).parents[1] / "docs" / "evidence.md"
READING_ROWS = {  # docs/evidence.md section 1: a table row's first cell -> the golden case it shows
    "**default** (`pinv_columns=full`)": "full_default", "`model.pinv_columns=translational`": "translational_default",
    "`grid.spacing=centred`": "grid_centred", "`robot.lower_anchor_drop=2.2`": "anchors_at_floor",
    **{f"`{switch}`": f"full_{name}" for switch, name in (
        ("model.velocity_boundary=include", "include"), ("model.acceleration_set=colon", "colon"),
        ("model.jdot=true", "jdot"), ("model.xi_in_torque_limit=false", "noxi"))},
}
FORCES_ONLY_ROWS = {"nothing else": "translational_default", **{
    cell: case.replace("full_", "translational_") for cell, case in READING_ROWS.items() if case.startswith("full_")
    and cell.startswith("`model.") and "pinv" not in cell}}
ASYMMETRIC_ROWS = {"`motion.t_dec=0.91` (braking twice as hard), forces only": "braking_translational",
                "`motion.t_dec=0.91`, all six columns": "braking_full",
                "`model.acceleration_set=colon` ({−0.714, 0.286} per axis), forces only": "colon_translational"}


def _table_rows(header: str) -> dict[str, list[str]]:
    """The rows of the docs/evidence.md table whose header line starts with ``header``: first cell
    -> the other cells."""
    lines = MODEL_MD.read_text().splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(header))
    rows = {}
    for line in lines[start + 2:]:
        if not line.startswith("|"):
            return rows
        first, *cells = [cell.strip() for cell in line.strip("|").split("|")]
        rows[first] = cells
    return rows


def _counts(text: str) -> list[int]:
    return [int(n) for n in re.findall(r"\d+", text.split("(")[0].replace("*", ""))]


def test_the_documented_tables_of_docs_model_md_are_the_golden_numbers():
    """docs/evidence.md section 1 states the counts of every reading and of asymmetric acceleration
    sets, and the lines' agreement: each cell is the golden case's (one source)."""
    for header, mapping in (("| reading (switch)", READING_ROWS), ("| `pinv_columns=translational` and", FORCES_ONLY_ROWS)):
        rows = _table_rows(header)
        for cell, case in mapping.items():
            zero, rotated = rows[cell]
            assert _counts(zero) == CASES[f"{case}_zero"]["values"]["n_feasible"], cell
            assert _counts(rotated) == CASES[f"{case}_rotated"]["values"]["n_feasible"], cell
        assert len(rows) == len(mapping) + (header.startswith("| reading")), header  # + the paper's row
    rows = _table_rows("| asymmetric setting")
    for cell, case in ASYMMETRIC_ROWS.items():
        zero, rotated = rows[cell]
        assert _counts(zero) == CASES[f"{case}_zero"]["values"]["n_feasible"], cell
        assert _counts(rotated) == CASES[f"{case}_rotated"]["values"]["n_feasible"], cell
    for part, orientation in zip(rows["lines vs grid agreement (%), forces only"], ("zero", "rotated")):
        shown = [float(n) for n in re.findall(r"\d+(?:\.\d+)?", part)]
        pinned = CASES[f"lines_translational_{orientation}"]["values"]["agreement_pct"]
        assert shown == [round(value, 2) for value in pinned], orientation


def test_an_asymmetric_acceleration_set_moves_the_counts():
    """Braking twice as hard, or the colon set, changes the counts of the default box (t_acc =
    t_dec): the acceleration set's asymmetry reaches the verdicts (docs/evidence.md section 1)."""
    for case, default in (("braking_full", "full_default"), ("braking_translational", "translational_default"),
                          ("colon_translational", "translational_default")):
        assert values(f"{case}_zero") != values(f"{default}_zero") or values(f"{case}_rotated") != values(
            f"{default}_rotated"), case
