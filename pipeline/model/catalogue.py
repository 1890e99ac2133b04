"""Actuator catalogues: CSV files with units in the column names (Table 1 of Filipovic & Kevac
2018 is shipped as ``pipeline/data/actuators_table1.csv``), read and checked cell by cell.

A CSV catalogue is read with the standard library (a Parquet one with pandas), so that a job
process does not import pandas (``docs/performance.md``, "What a process imports");
:meth:`Catalogue.table` gives the pandas view the studies use.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from functools import cached_property
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

from pipeline.errors import ConfigError

if TYPE_CHECKING:
    import pandas as pd

TABLE1 = resources.files("pipeline") / "data" / "actuators_table1.csv"

GEAR_RATIOS = (1e-3, 1e5)  # past any gearbox, where the drive's constants of eq. 22 overflow or divide by zero
WINCH_RADII = (1e-4, 10.0)  # m: a tenth of a millimetre to 10 m
# column -> (smallest value, it included, largest value): past either end no catalogue motor, a
# unit typed wrong, and the drive's constants (eq. 22) and the LPs' bounds leave what a double and
# HiGHS (1e20 is its infinity) carry; every numeric column must be finite
NUMERIC_COLUMNS: dict[str, tuple[float, bool, float]] = {
    "power_W": (1e-3, True, 1e7),
    "voltage_V": (0.1, True, 1e5),
    "speed_rpm": (1.0, True, 1e6),
    "torque_Nm": (1e-4, True, 1e6),
    "back_emf_V_per_rad_s": (1e-6, True, 1e3),
    "torque_constant_Nm_per_A": (1e-6, True, 1e3),
    "viscous_friction_Nm_per_rad_s": (0.0, True, 1e3),
    "resistance_ohm": (1e-6, True, 1e6),
    "inertia_g_cm2": (1e-3, True, 1e12),
    "gear_ratio": (GEAR_RATIOS[0], True, GEAR_RATIOS[1]),
    "efficiency": (1e-3, True, 1.0),  # FRACTIONS
    "winch_radius_m": (WINCH_RADII[0], True, WINCH_RADII[1]),
}
FRACTIONS = ("efficiency",)  # dimensionless, in (0, 1]
# column -> physical quantity its name starts with (the rest of the name is the unit)
QUANTITY = {
    "power_W": "power",
    "voltage_V": "voltage",
    "speed_rpm": "speed",
    "torque_Nm": "torque",
    "back_emf_V_per_rad_s": "back_emf",
    "torque_constant_Nm_per_A": "torque_constant",
    "viscous_friction_Nm_per_rad_s": "viscous_friction",
    "resistance_ohm": "resistance",
    "inertia_g_cm2": "inertia",
    "winch_radius_m": "winch_radius",
}
@dataclass(frozen=True)
class Catalogue:
    """A validated actuator catalogue (:func:`load_catalogue`), rows in file order. Each row
    holds ``id`` (int), ``name`` (text), every column of :data:`NUMERIC_COLUMNS` (float, SI
    prefixes as the column names say) and the user's own columns (a price, a mass) as text."""

    source: str
    rows: tuple[dict, ...]

    @property
    def ids(self) -> list[int]:
        return [row["id"] for row in self.rows]

    @property
    def columns(self) -> list[str]:
        """The columns besides ``id``: name, the numeric ones, the user's own."""
        return [column for column in self.rows[0] if column != "id"]

    def row(self, actuator: int) -> dict:
        """The row of id ``actuator`` (KeyError if none: ids are checked against :attr:`ids`
        when a config is validated)."""
        return self._by_id[actuator]

    @cached_property
    def _by_id(self) -> dict[int, dict]:
        return {row["id"]: row for row in self.rows}

    def table(self) -> pd.DataFrame:
        """The catalogue as a pandas DataFrame indexed by ``id`` (imports pandas)."""
        import pandas as pd

        return pd.DataFrame(list(self.rows)).set_index("id")


def load_catalogue(path: str | Path | None = None) -> Catalogue:
    """Read and validate a catalogue (CSV, or Parquet by its ``.parquet`` suffix); ``None`` is the
    shipped Table 1. Raises ConfigError naming the row and column."""
    source = TABLE1 if path is None else Path(path)
    header, lines = _read_as_text(source, path)
    _check_columns(header, source)
    if not lines:
        raise ConfigError(f"catalogue={source}: no actuator rows")
    rows, seen = [], set()
    for number, line in enumerate(lines, start=2):  # numbered as in the file, header = row 1
        if len(line) > len(header):
            raise ConfigError(f"catalogue={source}: row {number} has {len(line)} cells, the header "
                              f"{len(header)}")
        texts = dict(zip(header, line + [""] * (len(header) - len(line))))  # short: empty cells
        row = {"id": _id(texts["id"], number, source), "name": texts["name"]}
        if row["id"] in seen:
            raise ConfigError(f"catalogue={source}: row {number}, column id: duplicate id {row['id']}")
        seen.add(row["id"])
        for column in NUMERIC_COLUMNS:
            row[column] = _number(texts[column], number, column, source)
        row.update((column, text) for column, text in texts.items() if column not in row)
        rows.append(row)
    return Catalogue(str(source), tuple(rows))


def _id(text: str, number: int, source) -> int:
    if not text.strip().isdigit():
        raise ConfigError(f"catalogue={source}: row {number}, column id: {text!r} is not an integer")
    return int(text)


def as_number(text: str) -> float:
    """A cell's number (``float``'s reading of the text); NaN for text that is none."""
    try:
        return float(text)
    except ValueError:
        return math.nan


def _number(text: str, number: int, column: str, source) -> float:
    """The cell's value, checked against its column's bound (:data:`NUMERIC_COLUMNS`)."""
    value = as_number(text)
    if not math.isfinite(value):
        raise ConfigError(f"catalogue={source}: row {number}, column {column}: {text!r} is not a number")
    low, inclusive, high = NUMERIC_COLUMNS[column]
    if column in FRACTIONS and value > 1:
        raise ConfigError(f"catalogue={source}: row {number}, column {column}: {value:g} must "
                          f"be a fraction in [{low:g}, 1] (per cent? divide by 100)")
    if value < low or (value == low and not inclusive) or value > high:
        raise ConfigError(f"catalogue={source}: row {number}, column {column}: {value:g} must be "
                          f"{'>=' if inclusive else '>'} {low:g} and at most {high:g}")
    return value


def _read_as_text(source, path) -> tuple[list[str], list[list[str]]]:
    """(header, rows): every cell as text, so that validation sees exactly what the user wrote;
    blank lines are skipped."""
    try:
        if str(source).endswith(".parquet"):  # often a DataFrame saved by pandas: read by pandas
            import pandas as pd

            frame = pd.read_parquet(source)
            if any(name is not None for name in frame.index.names):  # e.g. indexed by id
                frame = frame.reset_index()
            header = [str(name) for name in frame.columns]
            lines = frame.astype(str).to_numpy().tolist()
        else:
            with source.open("r", encoding="utf-8-sig", newline="") as handle:
                header, *lines = [line for line in csv.reader(handle) if line] or [[]]
    except OSError as exc:
        raise ConfigError(f"catalogue={path}: cannot read ({exc.strerror or exc})") from exc
    except (ValueError, csv.Error) as exc:  # pyarrow's and the codec's errors derive from ValueError
        raise ConfigError(f"catalogue={path}: not a readable table ({exc})") from exc
    if not header:
        raise ConfigError(f"catalogue={path}: not a readable table (no header row)")
    repeated = sorted({name for name in header if header.count(name) > 1})
    if repeated:
        raise ConfigError(f"catalogue={path}: column {repeated[0]} appears more than once")
    return header, lines


def _check_columns(header: list[str], source) -> None:
    """Missing columns; a known quantity in another unit (``power_kW``) is named as such."""
    missing = [c for c in ("id", "name", *NUMERIC_COLUMNS) if c not in header]
    if not missing:
        return
    for column in missing:
        quantity = QUANTITY.get(column)
        for other in header:
            if quantity and other.startswith(f"{quantity}_") and _quantity(other) == quantity:
                raise ConfigError(
                    f"catalogue={source}: column {other}: unit {other[len(quantity) + 1:]!r} is "
                    f"not supported, give {quantity} as column {column}"
                )
    raise ConfigError(f"catalogue={source}: missing column(s) {', '.join(missing)}")


def _quantity(column: str) -> str | None:
    """The longest known quantity name that ``column`` starts with."""
    matches = [q for q in QUANTITY.values() if q and column.startswith(f"{q}_")]
    return max(matches, key=len) if matches else None
