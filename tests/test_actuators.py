import numpy as np
import pandas as pd
import pytest

from pipeline.model.actuators import actuator_model
from pipeline.model.catalogue import load_catalogue
from pipeline.errors import ConfigError


def test_table1_converted_to_si_and_eq22_constants(catalogue):
    act = actuator_model(catalogue.loc[1])
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
    assert actuator_model(catalogue.loc[5], xi_in_torque_limit=False).torque_limit == pytest.approx(0.03 * 26)


def test_drive_overrides(catalogue):
    assert actuator_model(catalogue.loc[2], winch_radius=0.05).winch_radius == 0.05
    base, geared = actuator_model(catalogue.loc[2]), actuator_model(catalogue.loc[2], gear_ratio=50)
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
        (HEADER + ROW.replace("3579", "-3579"), "row 2, column inertia_g_cm2: -3579 must be > 0"),
        (HEADER + ROW.replace("0.369", "abc"), "row 2, column resistance_ohm: 'abc' is not a number"),
        (HEADER + ROW + ROW, "row 3, column id: duplicate id 1"),
        (HEADER + ROW.replace("1,a", "x,a"), "row 2, column id: 'x' is not an integer"),
        (HEADER.replace("power_W", "power_kW") + ROW, "column power_kW: unit 'kW' is not supported"),
        (HEADER.replace("torque_constant_Nm_per_A", "torque_constant_mNm_per_A") + ROW,
         "column torque_constant_mNm_per_A: unit 'mNm_per_A'"),
        (HEADER, "no actuator rows"),
        (HEADER + ROW.replace(",0.6,0.08", ",0.6,"), "row 2, column winch_radius_m: '' is not a number"),
    ],
)
def test_malformed_catalogue_names_row_and_column(tmp_path, text, expected):
    with pytest.raises(ConfigError) as info:
        load_catalogue(_write(tmp_path, text))
    assert expected in str(info.value)


def test_user_catalogue_loads(tmp_path):
    table = load_catalogue(_write(tmp_path, HEADER + ROW))
    assert list(table.index) == [1]
    assert np.isclose(table.loc[1, "inertia_g_cm2"], 3579)


def test_parquet_catalogue_equals_csv(tmp_path, catalogue):
    path = tmp_path / "cat.parquet"
    catalogue.reset_index().to_parquet(path)
    pd.testing.assert_frame_equal(load_catalogue(path), catalogue)
