"""ftsmc.plot returns matplotlib figures drawn like the CLI's (reference
on top, a × where a run stopped early, its reason in the legend); run.plot()
shows position, attitude and rotors; animate replays a run in 3-D;
montecarlo's progress reporting (callable, silent when not interactive)
leaves the rows unchanged."""

from __future__ import annotations

from pathlib import Path
from typing import List, Tuple

import pytest

import ftsmc

matplotlib = pytest.importorskip("matplotlib", reason='pip install "./python[plot]"')
matplotlib.use("Agg")
from matplotlib.figure import Figure  # noqa: E402

REPO = Path(__file__).resolve().parents[2]


def test_import_ftsmc_brings_ftsmc_plot() -> None:
    import subprocess
    import sys

    code = "import ftsmc; print(callable(ftsmc.plot.montecarlo_box))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "True", out.stderr


def test_run_plot_shows_position_attitude_and_rotors_with_the_reference_on_top() -> None:
    run = ftsmc.simulate(ftsmc.Scenario.builtin("paper-scenario-1"), "ftaftsmc")
    fig = run.plot()
    assert isinstance(fig, Figure) and len(fig.axes) == 7  # x, y, z; φ, θ, ψ; rotor speeds
    labels = {ax.get_ylabel() for ax in fig.axes}
    assert {"x (m)", "φ (rad)", "rotor speed (rad/s)"} <= labels, labels
    for what in ("position", "attitude", "rotors"):
        fig = run.plot(what)
        assert isinstance(fig, Figure) and len(fig.axes) >= 1, what
    fig = ftsmc.plot.position(run)
    ax = fig.axes[0]
    reference = [ln for ln in ax.get_lines() if ln.get_label() == "reference"]
    flight = [ln for ln in ax.get_lines() if ln.get_label() == "FTAFTSMC"]
    assert reference and flight and reference[0].get_zorder() > flight[0].get_zorder()
    with pytest.raises(ValueError, match="expected one of"):
        run.plot("bogus")


def test_a_diverged_run_ends_in_a_marker_with_its_reason_in_the_legend() -> None:
    scenario = ftsmc.Scenario.from_file(str(REPO / "scenarios" / "realism" / "rigid-body-scenario-1.toml"))
    run = ftsmc.simulate(scenario, "ftaftsmc")
    assert run.exit.status == "diverged"
    fig = run.plot("position")
    ax = fig.axes[0]
    assert any(ln.get_marker() == "x" for ln in ax.get_lines())
    assert not ax.texts, "no note over the data"
    entries = [t.get_text() for legend in fig.legends for t in legend.get_texts()]
    assert any("diverged (tilt) at" in e for e in entries), entries


def test_animate_replays_a_run_in_3d_and_saves_a_gif(tmp_path: Path) -> None:
    from matplotlib.animation import FuncAnimation

    run = ftsmc.simulate(ftsmc.Scenario.builtin("paper-scenario-1").with_overrides({"duration": 2.0}), "ftaftsmc")
    anim = ftsmc.plot.animate(run, frames=4)
    assert isinstance(anim, FuncAnimation)
    gif = tmp_path / "flight.gif"
    anim.save(str(gif), writer="pillow", dpi=40)
    assert gif.read_bytes()[:6] in (b"GIF87a", b"GIF89a")
    assert "<img" in anim.to_jshtml() or "<script" in anim.to_jshtml()
    with pytest.raises(ValueError, match="frames"):
        ftsmc.plot.animate(run, frames=0)


def test_montecarlo_box_has_a_box_per_controller() -> None:
    rows = ftsmc.montecarlo(ftsmc.Scenario.builtin("paper-scenario-2"), runs=3, progress=False)
    fig = ftsmc.plot.montecarlo_box(rows, ["ise_x", "rms_z"])
    assert len(fig.axes) == 2
    labels = [t.get_text() for t in fig.axes[0].get_xticklabels()]
    assert len(labels) == 3 and all("3/3 flew" in lb for lb in labels), labels
    with pytest.raises(ValueError, match="not a column"):
        ftsmc.plot.montecarlo_box(rows, ["ise_q"])


def test_montecarlo_progress_reaches_the_total_and_leaves_the_rows_unchanged() -> None:
    scenario = ftsmc.Scenario.builtin("paper-scenario-2")
    calls: List[Tuple[int, int]] = []
    with_cb = ftsmc.montecarlo(scenario, runs=6, threads=2, progress=lambda done, total: calls.append((done, total)))
    plain = ftsmc.montecarlo(scenario, runs=6, threads=2, progress=False)
    assert calls and calls[-1][0] == calls[-1][1] > 0
    assert all(a[0] <= b[0] for a, b in zip(calls, calls[1:])), "monotone"
    assert with_cb.equals(plain)


def test_progress_is_silent_when_not_interactive(capfd: pytest.CaptureFixture[str]) -> None:
    ftsmc.montecarlo(ftsmc.Scenario.builtin("paper-scenario-2"), runs=4)
    assert capfd.readouterr().err == ""


def test_an_exception_in_the_progress_callable_reaches_the_caller() -> None:
    def boom(done: int, total: int) -> None:
        raise KeyError("stop")

    with pytest.raises(KeyError, match="stop"):
        ftsmc.montecarlo(ftsmc.Scenario.builtin("paper-scenario-2"), runs=2, progress=boom)
