"""Every example runs headless, and `mypy --strict` accepts the examples and
the package against the hand-written stubs."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
EXAMPLES = REPO / "examples" / "python"
TUNER_BENCHMARK = REPO / "examples" / "tuner-benchmark"


def run(args: list, tmp_path: Path) -> str:
    env = dict(os.environ, MPLBACKEND="Agg")
    done = subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_table3_and_fig4(tmp_path: Path) -> None:
    out = run([str(EXAMPLES / "table3_fig4.py"), "--out", str(tmp_path)], tmp_path)
    assert "paper-scenario-2  z" in out and (tmp_path / "fig4.png").stat().st_size > 10_000


def test_montecarlo_box_plot(tmp_path: Path) -> None:
    runs = os.environ.get("FTSMC_EXAMPLE_RUNS", "1000")
    out = run([str(EXAMPLES / "montecarlo_boxplot.py"), "--runs", runs, "--out", str(tmp_path)], tmp_path)
    assert f"{3 * int(runs)} flights" in out and (tmp_path / "montecarlo-ise.png").is_file()


def test_pd_controller(tmp_path: Path) -> None:
    out = run([str(EXAMPLES / "pd_controller.py")], tmp_path)
    assert "pd: completed" in out


def test_rotorpy_example(tmp_path: Path) -> None:
    pytest.importorskip("rotorpy")
    out = run([str(EXAMPLES / "rotorpy_ftaftsmc.py"), "--duration", "2.5", "--out", str(tmp_path)], tmp_path)
    assert "FTAFTSMC: exit" in out and (tmp_path / "rotorpy.png").is_file()


def test_mypy_strict_on_the_examples_and_package() -> None:
    if shutil.which("mypy") is None and not (Path(sys.executable).parent / "mypy").exists():
        pytest.fail("mypy is not installed (.ci/run installs it)")
    mypy = [sys.executable, "-m", "mypy", "--strict", "--ignore-missing-imports", "--no-incremental"]
    examples = [str(p) for p in sorted(EXAMPLES.glob("*.py"))] + [str(TUNER_BENCHMARK / "table.py")]
    for target in (["-p", "ftsmc"], examples):
        done = subprocess.run([*mypy, *target], capture_output=True, text=True, cwd=REPO)
        assert done.returncode == 0, done.stdout + done.stderr


def test_gym_hover_example(tmp_path: Path) -> None:
    pytest.importorskip("gymnasium")
    out = run([str(EXAMPLES / "gym_hover.py"), "--episodes", "1"], tmp_path)
    # The scripted PD flies every episode to its end; the random policy does not.
    assert "pd episode 0: return" in out and "steps, completed" in out, out
    assert "random episode 0" in out and "random episode 0: return" in out and ", completed" not in out.split("pd episode")[0], out
    assert "0 terminated" in out, out


def test_train_hover_runs_and_plots_its_reward_curve(tmp_path: Path) -> None:
    # Two tiny iterations: the example runs end to end (docs/python.md shows a full run's curve).
    args = ["--iterations", "2", "--population", "6", "--episode-time", "0.5", "--out", str(tmp_path)]
    out = run([str(EXAMPLES / "train_hover.py"), *args], tmp_path)
    assert out.count("iteration") == 2 and "held-out seeds" in out, out
    assert (tmp_path / "train-hover-reward.png").stat().st_size > 5_000


def test_tuner_benchmark_table(cli: Path, tmp_path: Path) -> None:
    """table.py reads what run.sh leaves: two committed tuned files per
    controller of paper-scenario-1 (standing in for the two tuners) flown
    by `ftsmc compare` on 4 draws; the same file twice ties every cell."""
    from conftest import run_cli

    controllers = ["ftaftsmc", "ranftsmc", "tsm-sta", "pid", "se3"]
    for c in controllers:
        d = tmp_path / "cmp" / f"paper-scenario-1-{c}"
        d.mkdir(parents=True)
        text = (REPO / "scenarios" / "tuned" / f"paper-scenario-1-{c}.toml").read_text()
        (d / "first.toml").write_text(text)
        (d / "current.toml").write_text(text)
        out = d / "out"
        run_cli(cli, "compare", "paper-scenario-1", "-c", f"{d / 'first.toml'},{d / 'current.toml'}",
                "--runs", "4", "--seed", "2026", "--out", str(out), "--no-figures")
    lines = run([str(TUNER_BENCHMARK / "table.py"), str(tmp_path), "paper-scenario-1"], tmp_path).splitlines()
    rows = [line for line in lines if line.startswith("| paper-scenario-1 |")]
    assert len(rows) == 5, lines
    assert all("4/4 [51.0, 100.0] | 4/4 [51.0, 100.0]" in r and r.endswith("| one flight |") for r in rows), rows
    assert lines[-1] == "new better in 0, no difference shown in 5, first better in 0: at least as good in 5 of 5", lines
    # The completion table: the same gains complete the same flights.
    lines = run([str(TUNER_BENCHMARK / "table.py"), "--completion", str(tmp_path), "paper-scenario-1"], tmp_path)
    rows = [line for line in lines.splitlines() if line.startswith("| paper-scenario-1 |")]
    assert len(rows) == 5 and all(r.endswith("| 4/4 | 4/4 | 0 / 0 | 1 |") for r in rows), rows


def test_tuner_benchmark_mcnemar_and_holm_match_scipy() -> None:
    """table.py's exact McNemar test is scipy's two-sided binomial test of
    the discordant pairs, and its Holm adjustment statsmodels' definition."""
    import importlib.util

    from scipy.stats import binomtest

    spec = importlib.util.spec_from_file_location("tuner_table", TUNER_BENCHMARK / "table.py")
    assert spec is not None and spec.loader is not None
    table = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(table)
    for b, c in [(0, 0), (1, 0), (4, 0), (14, 0), (30, 7), (5, 5), (3, 40), (100, 80)]:
        expected = binomtest(min(b, c), b + c, 0.5).pvalue if b + c else 1.0
        assert table.mcnemar_exact(b, c) == pytest.approx(expected, rel=1e-12), (b, c)
    # Holm: sorted p times (m − rank), made monotone, capped at 1, in the input's order.
    assert table.holm([0.01, 0.04, 0.03, 0.5]) == pytest.approx([0.04, 0.09, 0.09, 0.5])
