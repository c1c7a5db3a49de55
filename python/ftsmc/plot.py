"""Matplotlib figures of ftsmc runs and Monte Carlo batches.

Every function returns a :class:`matplotlib.figure.Figure` (made with
``pyplot``, so ``plt.show()`` shows it and a notebook displays it) and draws
what the ``ftsmc`` command draws: references dashed *beneath* the flights,
each controller in its CLI colour, a × with the reason where a run diverged
or crashed. Units: m, rad, rad/s, s.

    run = ftsmc.simulate(scenario, "ftaftsmc")
    fig = ftsmc.plot.position([run, other])      # or run.plot("position")
    fig = ftsmc.plot.montecarlo_box(ftsmc.montecarlo(scenario, 100))

Needs matplotlib (``pip install "./python[plot]"``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Dict, List, Optional, Sequence, Union

import numpy as np

from . import label

if TYPE_CHECKING:
    import matplotlib.axes
    import matplotlib.figure
    import pandas

    from . import Run

__all__ = ["attitude", "montecarlo_box", "position", "rotors", "run"]

COLORS: Dict[str, str] = {
    "ftaftsmc": "#1f77b4",
    "ranftsmc": "#ff7f0e",
    "tsm-sta": "#2ca02c",
    "ftaftsmc-no-mass": "#9467bd",
    "pid": "#d62728",
    "se3": "#e377c2",
}
"""Controller → colour, as in the CLI's figures (crates/ftsmc-cli/src/plot.rs)."""

_AXES = {
    "position": [("x", "x_ref", "x (m)"), ("y", "y_ref", "y (m)"), ("z", "z_ref", "z (m)")],
    "attitude": [("phi", "phi_ref", "φ (rad)"), ("theta", "theta_ref", "θ (rad)"), ("psi", "psi_ref", "ψ (rad)")],
}


def _color(name: str) -> Optional[str]:
    return COLORS.get(name)


def _runs(runs: Union[Run, Sequence[Run]]) -> List[Run]:
    from . import Run

    return [runs] if isinstance(runs, Run) else list(runs)


def _end_marker(ax: matplotlib.axes.Axes, run: Run, t: np.ndarray, y: np.ndarray, color: Optional[str]) -> None:
    """A × at the last finite point of a run that stopped early, with the reason."""
    if run.exit.status == "completed":
        return
    ok = np.isfinite(t) & np.isfinite(y)
    if not ok.any():
        return
    k = int(np.flatnonzero(ok)[-1])
    ax.plot([t[k]], [y[k]], marker="x", markersize=8, mew=2, color=color, zorder=5)
    divergence = run.exit.detail.get("divergence")
    reason = divergence.get("reason", "") if isinstance(divergence, dict) else run.exit.detail.get("reason", "")
    why = f" ({str(reason).replace('-', ' ')})" if reason else ""
    ax.annotate(
        f"{run.exit.status}{why} at {run.exit.time:.2f} s",
        (t[k], y[k]),
        xytext=(4, -10),
        textcoords="offset points",
        fontsize=8,
        color=color,
    )


def _tracking(runs: Sequence[Run], what: str) -> matplotlib.figure.Figure:
    import matplotlib.pyplot as plt

    _check_recorded(runs)
    fig, axes = plt.subplots(1, 3, figsize=(10, 3.2), constrained_layout=True)
    for ax, (col, ref, ylabel) in zip(axes, _AXES[what]):
        first = runs[0].columns
        # The reference first: beneath the flights.
        if ref in first:
            ax.plot(first["t"], first[ref], "k--", lw=1.0, label="reference", zorder=1)
        for r in runs:
            c = r.columns
            color = _color(r.controller)
            ax.plot(c["t"], c[col], color=color, lw=1.2, label=label(r.controller), zorder=2)
            _end_marker(ax, r, c["t"], c[col], color)
        ax.set_xlabel("time (s)")
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(f"{what} ({runs[0].scenario})")
    return fig


def position(runs: Union[Run, Sequence[Run]]) -> matplotlib.figure.Figure:
    """x, y, z against time (m), one panel each, with the reference."""
    return _tracking(_runs(runs), "position")


def attitude(runs: Union[Run, Sequence[Run]]) -> matplotlib.figure.Figure:
    """Roll φ, pitch θ, yaw ψ against time (rad), with each run's attitude reference."""
    return _tracking(_runs(runs), "attitude")


def rotors(runs: Union[Run, Sequence[Run]]) -> matplotlib.figure.Figure:
    """Rotor speeds ω1..ω4 (rad/s) against time, one panel per run."""
    import matplotlib.pyplot as plt

    rs = _runs(runs)
    _check_recorded(rs)
    fig, axes = plt.subplots(1, len(rs), figsize=(3.6 * len(rs), 3.2), squeeze=False, constrained_layout=True)
    for ax, r in zip(axes[0], rs):
        c = r.columns
        for i in range(1, 5):
            ax.plot(c["t"], c[f"omega_{i}"], lw=0.8, label=f"ω{i}")
        _end_marker(ax, r, c["t"], c["omega_1"], "k")
        ax.set_title(f"{label(r.controller)} ({r.exit.status})", fontsize=9)
        ax.set_xlabel("time (s)")
        ax.set_ylabel("rotor speed (rad/s)")
        ax.grid(alpha=0.3)
    axes[0][0].legend(fontsize=8)
    return fig


def run(r: Run, what: str = "position") -> matplotlib.figure.Figure:
    """:func:`position`, :func:`attitude` or :func:`rotors` of one run (``Run.plot``)."""
    makers = {"position": position, "attitude": attitude, "rotors": rotors}
    if what not in makers:
        raise ValueError(f"what = {what!r}: expected one of {', '.join(makers)}")
    _check_recorded([r])
    return makers[what](r)


def _check_recorded(runs: Sequence[Run]) -> None:
    """Refuse to plot a run without a recorded time series, saying why."""
    for r in runs:
        if "t" not in r.columns or len(r.columns["t"]) == 0:
            raise ValueError(
                f"{r.controller} on {r.scenario} has no recorded rows to plot "
                "(simulation.record_rate = 0 records none): fly it with record_rate > 0, e.g. "
                "scenario.with_overrides({'simulation.record_rate': 100.0})"
            )


def montecarlo_box(
    rows: pandas.DataFrame, metrics: Sequence[str] = ("ise_x", "ise_y", "ise_z", "ise_psi"), log: bool = True
) -> matplotlib.figure.Figure:
    """One box per controller of each metric (columns of ``runs.csv``, as
    :func:`ftsmc.montecarlo` returns them) over the completed runs: box q1–q3,
    whiskers p5–p95; the tick label says how many runs completed."""
    import matplotlib.pyplot as plt

    for m in metrics:
        if m not in rows.columns:
            raise ValueError(f"metric {m!r} is not a column of the batch (e.g. ise_x, rms_z, settling_time_z)")
    controllers = list(dict.fromkeys(rows["controller"]))
    fig, axes = plt.subplots(1, len(metrics), figsize=(3.4 * len(metrics), 3.6), squeeze=False, constrained_layout=True)
    for ax, m in zip(axes[0], metrics):
        data: List[Any] = []
        names: List[str] = []
        for c in controllers:
            mine = rows[rows["controller"] == c]
            ok = mine[mine["completed"]]
            values = ok[m].to_numpy(dtype=float)
            values = values[np.isfinite(values) & ((values > 0) if log else True)]
            data.append(values)
            names.append(f"{label(c)}\n{len(ok)}/{len(mine)} flew")
        parts = ax.boxplot(data, whis=(5, 95), showfliers=False, patch_artist=True)
        for patch, c in zip(parts["boxes"], controllers):
            patch.set_facecolor(_color(c) or "#7f7f7f")
            patch.set_alpha(0.35)
        ax.set_xticks(range(1, len(names) + 1))
        ax.set_xticklabels(names, fontsize=7)
        if log:
            ax.set_yscale("log")
        ax.set_title(m)
        ax.grid(alpha=0.3, axis="y")
    return fig
