"""Python results equal the CLI's on the paper scenarios: the same
summary.json entries, byte-identical CSV time series, the same columns,
and the same Monte Carlo rows as runs.csv."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import ftsmc

from conftest import run_cli

PAPER = ["paper-scenario-1", "paper-scenario-2", "ftaftsmc-tuned-scenario-1"]


@pytest.mark.parametrize("name", PAPER)
def test_single_runs_equal_the_cli(cli: Path, tmp_path: Path, name: str) -> None:
    scenario = ftsmc.Scenario.builtin(name)
    run_cli(cli, "run", name, "--out", str(tmp_path), "--no-figures")
    folder = tmp_path / scenario.name
    summary = json.loads((folder / "summary.json").read_text())["scenarios"][scenario.name]
    assert sorted(summary) == sorted(scenario.controllers)
    for controller in scenario.controllers:
        run = ftsmc.simulate(scenario, controller)
        assert run.controller == controller
        # metrics: the same keys and values as summary.json's entry
        assert run.metrics == summary[controller], controller
        assert run.exit.text == summary[controller]["exit"]
        # time series: byte for byte, and as columns
        cli_csv = (folder / f"{controller}.csv").read_bytes()
        assert run.to_csv() == cli_csv, controller
        cli_frame = pd.read_csv(folder / f"{controller}.csv", float_precision="round_trip")
        assert list(run.columns) == list(cli_frame.columns)
        for column, values in run.columns.items():
            assert values.dtype == np.float64 and values.ndim == 1
            np.testing.assert_array_equal(values, cli_frame[column].to_numpy(), err_msg=column)
        pd.testing.assert_frame_equal(run.to_pandas(), cli_frame, check_exact=True)


def test_resolved_scenario_text_equals_the_cli_scenario_toml(cli: Path, tmp_path: Path) -> None:
    run_cli(cli, "run", "paper-scenario-1", "-c", "ftaftsmc", "--out", str(tmp_path), "--no-figures")
    scenario = ftsmc.Scenario.builtin("paper-scenario-1").with_overrides({"controllers": ["ftaftsmc"]})
    assert scenario.to_toml() == (tmp_path / "paper-scenario-1" / "scenario.toml").read_text()


def _cli_runs(path: Path) -> pd.DataFrame:
    frame = pd.read_csv(path, float_precision="round_trip")
    # pandas reads integers as int64 where they fit; ftsmc gives uint64.
    for column in ("run", "seed", "saturated_periods"):
        frame[column] = frame[column].astype(np.uint64)
    # Text columns: ftsmc gives Python objects (str, None for an empty cell
    # such as margin_binds where no envelope limits the flight), whatever
    # string dtype this pandas's read_csv infers (object before pandas 3,
    # `str` from 3.0 on).
    for column in ("controller", "exit", "margin_binds"):
        frame[column] = pd.Series([None if pd.isna(v) else v for v in frame[column]], dtype=object)
    return frame


def test_montecarlo_rows_equal_runs_csv(cli: Path, tmp_path: Path) -> None:
    runs = 6
    run_cli(cli, "montecarlo", "paper-scenario-2", "--runs", str(runs), "--out", str(tmp_path), "--no-figures")
    expected = _cli_runs(tmp_path / "paper-scenario-2" / "runs.csv")
    scenario = ftsmc.Scenario.builtin("paper-scenario-2")
    frame = ftsmc.montecarlo(scenario, runs, threads=2)
    assert len(frame) == runs * len(scenario.controllers)
    pd.testing.assert_frame_equal(frame, expected, check_exact=True)
    # The rows do not depend on the thread count.
    pd.testing.assert_frame_equal(ftsmc.montecarlo(scenario, runs, threads=1), frame, check_exact=True)


def test_montecarlo_seed_and_controllers_as_the_cli(cli: Path, tmp_path: Path) -> None:
    args = ["montecarlo", "paper-scenario-2", "--runs", "3", "--seed", "7", "-c", "ftaftsmc,ranftsmc"]
    run_cli(cli, *args, "--out", str(tmp_path), "--no-figures")
    expected = _cli_runs(tmp_path / "paper-scenario-2" / "runs.csv")
    frame = ftsmc.montecarlo(ftsmc.Scenario.builtin("paper-scenario-2"), 3, seed=7, controllers=["ftaftsmc", "ranftsmc"])
    pd.testing.assert_frame_equal(frame, expected, check_exact=True)
    other = ftsmc.montecarlo(ftsmc.Scenario.builtin("paper-scenario-2"), 3, seed=8, controllers=["ftaftsmc"])
    assert not np.array_equal(other["seed"].to_numpy(), frame["seed"].to_numpy()[::2])
