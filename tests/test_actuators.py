import numpy as np
import pandas as pd
import pytest

from pipeline.model.actuators import actuator_model
from pipeline.model.catalogue import load_catalogue
from pipeline.errors import ConfigError


def test_table1_converted_to_si_and_eq22_constants(catalogue):
    act = actuator_model(catalogue.row(1))
    n_v, n_m = 30, 30 * 0.6
    j_r = 3579e-7 * n_v * n_m  # g cm^2 -> kg m^2, reflected to the output shaft
    c_m = 0.095 * n_m
    assert act.G_v == pytest.approx(j_r * 0.369 / c_m, rel=1e-12)
    assert act.L_v == pytest.approx(0.0945 * n_v, rel=1e-12)  # B_c = 0
    assert act.S_v == pytest.approx(0.369 / c_m, rel=1e-12)
    assert act.speed_limit == pytest.approx(4700 / 9.5493 / n_v, rel=1e-5)  # eq. (30)
    assert act.torque_limit == pytest.approx(0.6 * n_m)  # eq. (32)
    assert act.accel_limit == pytest.approx(0.6 * n_m / j_r)  # eq. (33)
    assert act.voltage_limit == 48  # eq. (34)


def test_torque_limit_reading_without_efficiency(catalogue):
    assert actuator_model(catalogue.row(5), xi_in_torque_limit=False).torque_limit == pytest.approx(0.03 * 26)


def test_drive_overrides(catalogue):
    assert actuator_model(catalogue.row(2), winch_radius=0.05).winch_radius == 0.05
    base, geared = actuator_model(catalogue.row(2)), actuator_model(catalogue.row(2), gear_ratio=50)
    assert geared.speed_limit == pytest.approx(base.speed_limit * 25 / 50)
    assert geared.torque_limit == pytest.approx(base.torque_limit * 50 / 25)


def _write(tmp_path, text):
    path = tmp_path / "cat.csv"
    path.write_text(text)
    return path


HEADER = ("id,name,power_W,voltage_V,speed_rpm,torque_Nm,back_emf_V_per_rad_s,torque_constant_Nm_per_A,"
          "viscous_friction_Nm_per_rad_s,resistance_ohm,inertia_g_cm2,gear_ratio,efficiency,winch_radius_m\n")
ROW = "1,a,300,48,4700,0.6,0.0945,0.095,0,0.369,3579,30,0.6,0.08\n"


@pytest.mark.parametrize(
    "text, expected",
    [
        (HEADER.replace(",efficiency", "") + ROW, "missing column(s) efficiency"),
        (HEADER + ROW.replace("3579", "-3579"), "row 2, column inertia_g_cm2: -3579 must be >= 0.001 and at most 1e+12"),
        (HEADER + ROW.replace("0.369", "abc"), "row 2, column resistance_ohm: 'abc' is not a number"),
        (HEADER + ROW + ROW, "row 3, column id: duplicate id 1"),
        (HEADER + ROW.replace("1,a", "x,a"), "row 2, column id: 'x' is not an integer"),
        (HEADER.replace("power_W", "power_kW") + ROW, "column power_kW: unit 'kW' is not supported"),
        (HEADER.replace("torque_constant_Nm_per_A", "torque_constant_mNm_per_A") + ROW,
         "column torque_constant_mNm_per_A: unit 'mNm_per_A'"),
        (HEADER, "no actuator rows"),
        (HEADER + ROW.replace(",0.6,0.08", ",0.6,"), "row 2, column winch_radius_m: '' is not a number"),
        ("", "not a readable table (no header row)"),
        ("\n\n", "not a readable table (no header row)"),
        (HEADER + ROW.replace("\n", ",7\n"), "row 2 has 15 cells, the header 14"),
        (HEADER.replace("name,", "name,name,") + ROW, "column name appears more than once"),
        (HEADER + "2,b\n", "row 2, column power_W: '' is not a number"),  # a short row
        (HEADER + ROW.replace("300", "1_0e"), "row 2, column power_W: '1_0e' is not a number"),
        (HEADER + ROW.replace("300", "nan"), "row 2, column power_W: 'nan' is not a number"),
        (HEADER + ROW.replace("300", "-inf"), "row 2, column power_W: '-inf' is not a number"),
        (HEADER + ROW.replace(",30,", ",1e-300,"), "column gear_ratio: 1e-300 must be >= 0.001 and at most 100000"),
        (HEADER + ROW.replace(",30,", ",1e300,"), "column gear_ratio: 1e+300 must be >= 0.001 and at most 100000"),
        (HEADER + ROW.replace(",0.08", ",80"), "column winch_radius_m: 80 must be >= 0.0001 and at most 10"),  # mm?
        (HEADER + ROW.replace(",0.6,0.08", ",1e-300,0.08"), "column efficiency: 1e-300 must be >= 0.001"),  # LP failed
        (HEADER + ROW.replace(",0.369,", ",1e-300,"), "column resistance_ohm: 1e-300 must be >= 1e-06"),  # model error
        (HEADER + ROW.replace(",48,", ",1e300,"), "column voltage_V: 1e+300 must be >= 0.1 and at most 100000"),
        (HEADER + ROW.replace(",0.6,0.0945", ",1e-12,0.0945"), "column torque_Nm: 1e-12 must be >= 0.0001"),
    ],
)
def test_malformed_catalogue_names_row_and_column(tmp_path, text, expected):
    with pytest.raises(ConfigError) as info:
        load_catalogue(_write(tmp_path, text))
    assert expected in str(info.value)


def test_user_catalogue_loads(tmp_path):
    catalogue = load_catalogue(_write(tmp_path, HEADER + ROW))
    assert catalogue.ids == [1]
    assert np.isclose(catalogue.row(1)["inertia_g_cm2"], 3579)


def test_parquet_catalogue_equals_csv(tmp_path, catalogue):
    path = tmp_path / "cat.parquet"
    catalogue.table().reset_index().to_parquet(path)
    assert load_catalogue(path).rows == catalogue.rows


def test_csv_read_as_a_spreadsheet_writes_it(tmp_path):
    """A byte-order mark, Windows line ends, blank lines, quoted cells and the user's own
    columns (kept as text) are read as pandas' reader read them."""
    text = (HEADER.replace("\n", ",price_eur\n") + "\n"
            + ROW.replace("1,a,", '1,"a, geared",').replace("\n", ",12.5\n"))
    path = tmp_path / "cat.csv"
    path.write_bytes(b"\xef\xbb\xbf" + text.replace("\n", "\r\n").encode())
    catalogue = load_catalogue(path)
    assert catalogue.ids == [1] and catalogue.columns[-1] == "price_eur"
    assert catalogue.row(1)["name"] == "a, geared" and catalogue.row(1)["price_eur"] == "12.5"
    expected = pd.read_csv(path, dtype=str, keep_default_na=False, encoding="utf-8-sig")
    assert catalogue.row(1)["power_W"] == float(expected.loc[0, "power_W"]) == 300.0
    table = catalogue.table()
    assert table.index.name == "id" and list(table.index) == [1]
    assert table["power_W"].dtype == np.float64 and table.loc[1, "price_eur"] == "12.5"
    with pytest.raises(KeyError):
        catalogue.row(2)


def test_a_parquet_catalogue_indexed_by_id_is_read(tmp_path, catalogue):
    """pandas stores a DataFrame's named index as a column of the file: ``id`` is found."""
    path = tmp_path / "cat.parquet"
    catalogue.table().to_parquet(path)
    assert load_catalogue(path).rows == catalogue.rows
    (tmp_path / "broken.parquet").write_bytes(b"PAR1 not really")
    with pytest.raises(ConfigError, match="not a readable table"):
        load_catalogue(tmp_path / "broken.parquet")
