"""``ftsmc.compare`` and ``ftsmc.stats.summary`` give the command's numbers:
the same rows as ``ftsmc compare``'s runs.csv, the same intervals and
verdicts as its summary.json, and the intervals of ``ftsmc montecarlo``'s
summary.json; bad contestants are refused with the name in the message."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import ftsmc
from ftsmc import stats

from conftest import run_cli


def _short(name: str = "realistic-calm-1") -> ftsmc.Scenario:
    return ftsmc.Scenario.builtin(name).with_overrides({"duration": 4.0})


def _close(a: float, b: float | None) -> bool:
    if b is None:  # JSON has no inf: an unbounded side is null
        return math.isinf(a) or math.isnan(a)
    return a == b


def test_compare_equals_the_command(cli: Path, tmp_path: Path) -> None:
    scenario = _short()
    (tmp_path / "s.toml").write_text(scenario.to_toml())
    run_cli(cli, "compare", str(tmp_path / "s.toml"), "-c", "pid,se3", "--runs", "8", "--confidence", "0.9",
            "--out", str(tmp_path), "--no-figures")
    folder = tmp_path / scenario.name
    result = ftsmc.compare(scenario, ["pid", "se3"], runs=8, confidence=0.9, threads=2)
    assert result.runs_flown == 8 and result.confidence == 0.9
    expected = pd.read_csv(folder / "runs.csv")
    assert list(result.runs.columns) == list(expected.columns)
    np.testing.assert_array_equal(result.runs["rms_x"].to_numpy(), expected["rms_x"].to_numpy())
    assert list(result.runs["controller"]) == list(expected["controller"])
    summary = json.loads((folder / "summary.json").read_text())
    assert list(result.summary.index) == ["pid", "se3"]
    for name, row in result.summary.iterrows():
        cli_intervals = summary["contestants"][name]["intervals"]
        assert row["runs"] == 8 and row["successes"] == cli_intervals["successes"]
        for ours, theirs in (("success", "success_rate"), ("completed", "completed_rate"), ("rms_median", "rms_median")):
            for part, suffix in (("estimate", ""), ("lo", "_lo"), ("hi", "_hi")):
                assert _close(row[ours + suffix], cli_intervals[theirs][part]), (name, ours, part)
        # every row: lo <= estimate <= hi
        for x in ("success", "completed", "crashed", "diverged", "rms_median", "rms_mean"):
            if not math.isnan(row[x]):
                assert row[x + "_lo"] <= row[x] <= row[x + "_hi"], (name, x)
    assert len(result.verdicts) == len(summary["verdicts"]) == 2
    for (_, ours), theirs in zip(result.verdicts.iterrows(), summary["verdicts"]):
        assert (ours["a"], ours["b"]) == (theirs["a"], theirs["b"])
        assert ours["p"] == theirs["p"] and ours["p_holm"] == theirs["p_holm"]
        assert ours["verdict"] in ("no difference shown", f"{ours['a']} better", f"{ours['b']} better")
    # the verdict sentence and the command's verdict agree
    for (_, ours), theirs in zip(result.verdicts.iterrows(), summary["verdicts"]):
        word = {"A better": f"{theirs['a']} better", "B better": f"{theirs['b']} better"}.get(theirs["verdict"], theirs["verdict"])
        assert ours["verdict"] == word


def test_a_tuned_file_is_a_contestant_and_bad_ones_are_refused(tmp_path: Path) -> None:
    scenario = _short()
    tuned = Path(__file__).resolve().parents[2] / "scenarios" / "tuned" / "realistic-calm-1-pid.toml"
    result = ftsmc.compare(scenario, ["pid", str(tuned)], runs=3, threads=1)
    # A file is labelled by what it holds: its controller, "tuned", vehicle and rung.
    assert list(result.summary.index) == ["pid", "pid (tuned, hummingbird, calm-1)"]
    with pytest.raises(ValueError, match="no-such-controller"):
        ftsmc.compare(scenario, ["pid", "no-such-controller"], runs=2)
    with pytest.raises(ValueError, match="given twice"):
        ftsmc.compare(scenario, ["pid", "pid"], runs=2)
    with pytest.raises(ValueError, match="at least two"):
        ftsmc.compare(scenario, ["pid"], runs=2)
    with pytest.raises(TypeError):
        ftsmc.compare(scenario, "pid", runs=2)
    with pytest.raises(ValueError, match="confidence"):
        ftsmc.compare(scenario, ["pid", "se3"], runs=2, confidence=1.5)


def test_stats_summary_equals_the_montecarlo_summary(cli: Path, tmp_path: Path) -> None:
    run_cli(cli, "montecarlo", "paper-scenario-2", "--runs", "6", "--confidence", "0.9", "--out", str(tmp_path),
            "--no-figures")
    expected = json.loads((tmp_path / "paper-scenario-2" / "summary.json").read_text())
    rows = ftsmc.montecarlo(ftsmc.Scenario.builtin("paper-scenario-2"), 6, threads=2)
    table = stats.summary(rows, confidence=0.9)
    assert sorted(table.index) == sorted(expected["controllers"])
    for name, row in table.iterrows():
        intervals = expected["controllers"][name]["intervals"]
        assert intervals["confidence"] == 0.9
        for ours, theirs in (("success", "success_rate"), ("diverged", "diverged_rate"), ("rms_median", "rms_median"),
                             ("rms_mean", "rms_mean")):
            for part, suffix in (("estimate", ""), ("lo", "_lo"), ("hi", "_hi")):
                assert _close(row[ours + suffix], intervals[theirs][part]), (name, ours, part)
