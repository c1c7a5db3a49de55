"""ftsmc.read_log, ftsmc.identify, ftsmc.validate: flight logs from Python,
on a flight made by ftsmc's own plant (known parameters), with the CLI's
numbers and clear errors for bad logs."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

import ftsmc
from ftsmc.logs import synthetic_log

from conftest import run_cli


def write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_read_log_gives_the_generic_columns_and_the_frame(tmp_path: Path) -> None:
    path = write(tmp_path, "clean.csv", synthetic_log(duration_s=3.0))
    df = ftsmc.read_log(path)
    for column in ["time_s", "x_m", "vz_m_s", "qw", "r_rad_s", "az_m_s2", "motor4"]:
        assert column in df.columns, column
    assert df["time_s"].iloc[0] == 0.0 and df["time_s"].is_monotonic_increasing
    assert df.attrs["frame"] == "zup-flu" and df.attrs["motor_unit"] == "normalised"
    # At rest in z-up/forward-left-up the accelerometer reads about +g.
    assert 9.0 < df["az_m_s2"].iloc[0] < 10.6


def test_identify_recovers_the_vehicle_and_validate_reproduces_a_clean_flight(tmp_path: Path) -> None:
    noisy = write(tmp_path, "noisy.csv", synthetic_log(duration_s=20.0, accel_noise=0.1, gyro_noise=0.01, seed=3))
    ident = ftsmc.identify([noisy], vehicle="crazyflie-2.1", bootstrap=50)
    tau = ident.parameters.set_index("name").loc["tau"]
    assert tau["lo"] <= 0.072 <= tau["hi"] and tau["lo"] >= 0.0
    assert "[vehicle]" in ident.vehicle_toml and ident.report["bootstrap_replicates"] > 0
    clean = write(tmp_path, "clean.csv", synthetic_log(duration_s=12.0))
    val = ftsmc.validate([clean], vehicle="crazyflie-2.1", bootstrap=0)
    pooled = val[val["flight"] == "all"]
    assert len(pooled) == 18
    assert (pooled["r2"] > 1 - 1e-9).all(), pooled[["horizon_s", "quantity", "axis", "r2"]]


def test_identify_equals_the_cli(cli: Path, tmp_path: Path) -> None:
    path = write(tmp_path, "noisy.csv", synthetic_log(duration_s=20.0, accel_noise=0.1, gyro_noise=0.01, seed=3))
    ident = ftsmc.identify([path], bootstrap=20, seed=7)
    out = tmp_path / "id"
    run_cli(cli, "identify", str(path), "--bootstrap", "20", "--seed", "7", "--out", str(out))
    cli_table = pd.read_csv(out / "parameters.csv")
    pd.testing.assert_frame_equal(ident.parameters, cli_table)
    assert (out / "vehicle.toml").read_text() == ident.vehicle_toml


def test_bad_logs_raise_value_errors_naming_the_file(tmp_path: Path) -> None:
    bad = write(tmp_path, "word.csv", "time_s,qw,qx,qy,qz\n0,1,0,0,0\n0.01,seven,0,0,0\n")
    with pytest.raises(ValueError, match="word.csv"):
        ftsmc.read_log(bad)
    with pytest.raises(ValueError, match="missing.ulg"):
        ftsmc.read_log(tmp_path / "missing.ulg")
    with pytest.raises(ValueError, match="at least one"):
        ftsmc.identify([])
    with pytest.raises(ValueError, match="duration_s"):
        synthetic_log(duration_s=0.0)
