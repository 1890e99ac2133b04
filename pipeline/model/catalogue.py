"""Actuator catalogues: CSV files with units in the column names (Table 1 of Filipovic & Kevac
2018 is shipped as ``pipeline/data/actuators_table1.csv``), read and checked cell by cell.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np
import pandas as pd

from pipeline.errors import ConfigError

TABLE1 = resources.files("pipeline") / "data" / "actuators_table1.csv"

# column -> (lower bound, bound is inclusive); every numeric column must be finite
NUMERIC_COLUMNS: dict[str, tuple[float, bool]] = {
    "power_W": (0.0, False),
    "voltage_V": (0.0, False),
    "speed_rpm": (0.0, False),
    "torque_Nm": (0.0, False),
    "back_emf_V_per_rad_s": (0.0, False),
    "torque_constant_Nm_per_A": (0.0, False),
    "viscous_friction_Nm_per_rad_s": (0.0, True),
    "resistance_ohm": (0.0, False),
    "inertia_g_cm2": (0.0, False),
    "gear_ratio": (0.0, False),
    "efficiency": (0.0, False),
    "winch_radius_m": (0.0, False),
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
def load_catalogue(path: str | Path | None = None) -> pd.DataFrame:
    """Read and validate a catalogue (CSV, or Parquet by its ``.parquet`` suffix); ``None`` is the
    shipped Table 1. Indexed by integer ``id``. Raises ConfigError naming the row and column."""
    source = TABLE1 if path is None else Path(path)
    table = _read_as_text(source, path)
    _check_columns(table, source)
    if table.empty:
        raise ConfigError(f"catalogue={source}: no actuator rows")
    ids = []
    for row, text in enumerate(table["id"], start=2):
        if not text.strip().isdigit():
            raise ConfigError(f"catalogue={source}: row {row}, column id: {text!r} is not an integer")
        ids.append(int(text))
    duplicated = pd.Series(ids).duplicated()
    if duplicated.any():
        row = int(np.flatnonzero(duplicated)[0]) + 2
        raise ConfigError(f"catalogue={source}: row {row}, column id: duplicate id {ids[row - 2]}")
    out = pd.DataFrame({"id": ids, "name": table["name"].astype(str)})
    for column, (bound, inclusive) in NUMERIC_COLUMNS.items():
        values = pd.to_numeric(table[column], errors="coerce")
        for row, (text, value) in enumerate(zip(table[column], values), start=2):
            if not np.isfinite(value):
                raise ConfigError(
                    f"catalogue={source}: row {row}, column {column}: {text!r} is not a number"
                )
            if value < bound or (value == bound and not inclusive):
                rule = ">= 0" if inclusive else "> 0"
                raise ConfigError(
                    f"catalogue={source}: row {row}, column {column}: {value:g} must be {rule}"
                )
            if column in FRACTIONS and value > 1:
                raise ConfigError(f"catalogue={source}: row {row}, column {column}: {value:g} must "
                                  "be a fraction in (0, 1] (per cent? divide by 100)")
        out[column] = values.astype(float)
    for column in table.columns.difference(["id", "name", *NUMERIC_COLUMNS], sort=False):
        out[column] = table[column].to_numpy()  # the user's own columns (a price, a mass), as text
    return out.set_index("id")


def _read_as_text(source, path) -> pd.DataFrame:
    """Every cell as text, so that validation sees exactly what the user wrote. Rows are
    numbered as in a CSV file (header = row 1) for both formats."""
    try:
        if str(source).endswith(".parquet"):
            return pd.read_parquet(source).astype(str)
        with source.open("r") as handle:
            return pd.read_csv(handle, dtype=str, keep_default_na=False)
    except OSError as exc:
        raise ConfigError(f"catalogue={path}: cannot read ({exc.strerror or exc})") from exc
    except (ValueError, pd.errors.ParserError) as exc:
        raise ConfigError(f"catalogue={path}: not a readable table ({exc})") from exc


def _check_columns(table: pd.DataFrame, source) -> None:
    """Missing columns; a known quantity in another unit (``power_kW``) is named as such."""
    missing = [c for c in ("id", "name", *NUMERIC_COLUMNS) if c not in table.columns]
    if not missing:
        return
    for column in missing:
        quantity = QUANTITY.get(column)
        for other in table.columns:
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
