"""Matplotlib figures of ftsmc runs and Monte Carlo batches.

Every function returns a :class:`matplotlib.figure.Figure` (made with
``pyplot``, so ``plt.show()`` shows it and a notebook displays it) and draws
what the ``ftsmc`` command draws: references black and dashed *on top of*
the flights, each controller in its CLI colour, a × where a run diverged or
crashed, with the reason and time in its legend entry (not over the data).
Units: m, rad, rad/s, s. :func:`animate` replays a flight in 3-D.

    run = ftsmc.simulate(scenario, "ftaftsmc")
    fig = run.plot()                             # position, attitude, rotors
    fig = ftsmc.plot.position([run, other])      # or run.plot("position")
    fig = ftsmc.plot.montecarlo_box(ftsmc.montecarlo(scenario, 100))
    anim = ftsmc.plot.animate(run)               # anim.save("flight.gif", writer="pillow")

Needs matplotlib (``pip install "./python[plot]"``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Dict, List, Optional, Sequence, Union

import numpy as np

from . import label

if TYPE_CHECKING:
    import matplotlib.animation
    import matplotlib.axes
    import matplotlib.figure
    import pandas

    from . import Run

__all__ = ["animate", "attitude", "montecarlo_box", "overview", "position", "rotors", "run"]

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


def _ending(run: Run) -> str:
    """"" for a completed run, else e.g. " — diverged (tilt) at 6.49 s"."""
    if run.exit.status == "completed":
        return ""
    divergence = run.exit.detail.get("divergence")
    reason = divergence.get("reason", "") if isinstance(divergence, dict) else run.exit.detail.get("reason", "")
    why = f" ({str(reason).replace('-', ' ')})" if reason else ""
    return f" — {run.exit.status}{why} at {run.exit.time:.2f} s"


def _end_marker(ax: matplotlib.axes.Axes, run: Run, t: np.ndarray, y: np.ndarray, color: Optional[str]) -> None:
    """A × at the last finite point of a run that stopped early (the reason
    is in the legend, :func:`_ending`)."""
    if run.exit.status == "completed":
        return
    ok = np.isfinite(t) & np.isfinite(y)
    if not ok.any():
        return
    k = int(np.flatnonzero(ok)[-1])
    ax.plot([t[k]], [y[k]], marker="x", markersize=8, mew=2, color=color, zorder=5)


def _tracking_into(axes: Sequence[matplotlib.axes.Axes], runs: Sequence[Run], what: str) -> None:
    for ax, (col, ref, ylabel) in zip(axes, _AXES[what]):
        first = runs[0].columns
        for r in runs:
            c = r.columns
            color = _color(r.controller)
            ax.plot(c["t"], c[col], color=color, lw=1.2, label=label(r.controller) + _ending(r), zorder=2)
            _end_marker(ax, r, c["t"], c[col], color)
        # The reference last: dashed on top of the flights, so it stays visible.
        if ref in first:
            ax.plot(first["t"], first[ref], "k--", lw=1.0, label="reference", zorder=4)
        ax.set_xlabel("time (s)")
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)


def _legend_below(fig: matplotlib.figure.Figure, ax: matplotlib.axes.Axes) -> None:
    handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=min(4, max(1, len(labels))), fontsize=8)


def _tracking(runs: Sequence[Run], what: str) -> matplotlib.figure.Figure:
    import matplotlib.pyplot as plt

    _check_recorded(runs)
    fig, axes = plt.subplots(1, 3, figsize=(10, 3.6), layout="constrained")
    _tracking_into(axes, runs, what)
    _legend_below(fig, axes[0])
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
    fig, axes = plt.subplots(1, len(rs), figsize=(3.6 * len(rs), 3.4), squeeze=False, layout="constrained")
    for ax, r in zip(axes[0], rs):
        _rotors_into(ax, r)
    _legend_below(fig, axes[0][0])
    return fig


def _rotors_into(ax: matplotlib.axes.Axes, r: Run) -> None:
    c = r.columns
    for i in range(1, 5):
        ax.plot(c["t"], c[f"omega_{i}"], lw=0.8, label=f"ω{i}")
    _end_marker(ax, r, c["t"], c["omega_1"], "k")
    ax.set_title(f"{label(r.controller)}{_ending(r) or ' (completed)'}", fontsize=9)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("rotor speed (rad/s)")
    ax.grid(alpha=0.3)


def overview(r: Run) -> matplotlib.figure.Figure:
    """One run's position (x, y, z), attitude (φ, θ, ψ) and rotor speeds
    ω1..ω4, one row each, with its references (``run.plot()``)."""
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(10, 8.4), layout="constrained")
    subs: Any = fig.subfigures(3, 1)
    top, middle, bottom = subs[0], subs[1], subs[2]
    _tracking_into(top.subplots(1, 3), [r], "position")
    top.suptitle("position", fontsize=10)
    attitude_axes = middle.subplots(1, 3)
    _tracking_into(attitude_axes, [r], "attitude")
    middle.suptitle("attitude", fontsize=10)
    _rotors_into(bottom.subplots(1, 1), r)
    bottom.suptitle("rotor speeds", fontsize=10)
    handles, labels = attitude_axes[0].get_legend_handles_labels()
    rotor_handles, rotor_labels = bottom.axes[0].get_legend_handles_labels()
    bottom.legend(handles + rotor_handles, labels + rotor_labels, loc="outside lower center", ncols=6, fontsize=8)
    fig.suptitle(f"{label(r.controller)} — {r.scenario}")
    return fig


def run(r: Run, what: str = "all") -> matplotlib.figure.Figure:
    """:func:`overview` (``"all"``), :func:`position`, :func:`attitude` or
    :func:`rotors` of one run (``Run.plot``)."""
    makers = {"all": overview, "position": position, "attitude": attitude, "rotors": rotors}
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


def animate(r: Run, frames: int = 120, interval: float = 50.0) -> matplotlib.animation.FuncAnimation:
    """A 3-D replay of one run: its path (up to the frame's time) and its
    reference (black, dashed), and the vehicle — a "+" of four arms rotated
    by its attitude ``R = Rz(ψ) Ry(θ) Rx(φ)`` (paper Eq. 1), the front arm
    red — at ``frames`` evenly spaced times, ``interval`` ms apart.

    Returns a :class:`matplotlib.animation.FuncAnimation`:
    ``anim.save("flight.gif", writer="pillow")`` writes a GIF (Pillow comes
    with matplotlib); in a notebook ``IPython.display.HTML(anim.to_jshtml())``
    plays it (``to_html5_video()`` needs ffmpeg).
    """
    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation

    from ._render import arms

    if frames < 1:
        raise ValueError(f"frames = {frames} is invalid (expected at least 1)")
    c = r.columns
    t = c["t"]
    if len(t) == 0:
        raise ValueError(f"run {r!r} recorded no time series (its scenario's record_rate is 0)")
    p = np.stack([c["x"], c["y"], c["z"]], axis=1)
    att = np.stack([c["phi"], c["theta"], c["psi"]], axis=1)
    ok = np.isfinite(p).all(axis=1) & np.isfinite(att).all(axis=1)
    last = int(np.flatnonzero(ok)[-1]) if ok.any() else 0
    picks = np.unique(np.linspace(0, last, frames).round().astype(int))
    span = float(np.nanmax(np.ptp(p[: last + 1], axis=0))) if last > 0 else 1.0
    arm = max(0.05, 0.06 * span)

    fig = plt.figure(figsize=(6, 5), layout="constrained")
    ax: Any = fig.add_subplot(projection="3d")  # mpl_toolkits' Axes3D (set_zlim, plot in 3-D)
    if all(k in c for k in ("x_ref", "y_ref", "z_ref")):
        ax.plot(c["x_ref"], c["y_ref"], c["z_ref"], "k--", lw=1.0, label="reference", zorder=4)
    color = _color(r.controller) or "#1f77b4"
    (path,) = ax.plot([], [], [], color=color, lw=1.4, label=label(r.controller) + _ending(r))
    arm_lines = [ax.plot([], [], [], color="#d62728" if k == 0 else "#222222", lw=2.5)[0] for k in range(4)]
    (up,) = ax.plot([], [], [], color="#1f77b4", lw=1.5)
    lo, hi = np.nanmin(p[: last + 1], axis=0) - arm, np.nanmax(p[: last + 1], axis=0) + arm
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    ax.legend(loc="upper left", fontsize=8)
    title = ax.set_title("")

    def draw(i: int) -> List[Any]:
        k = int(picks[i])
        path.set_data_3d(p[: k + 1, 0], p[: k + 1, 1], p[: k + 1, 2])
        tips, top = arms(p[k], att[k], arm)
        for line, tip in zip(arm_lines, tips):
            line.set_data_3d([p[k, 0], tip[0]], [p[k, 1], tip[1]], [p[k, 2], tip[2]])
        up.set_data_3d([p[k, 0], top[0]], [p[k, 1], top[1]], [p[k, 2], top[2]])
        title.set_text(f"{r.scenario}: t = {t[k]:.2f} s")
        return [path, up, title, *arm_lines]

    anim = FuncAnimation(fig, draw, frames=len(picks), interval=interval, blit=False)
    plt.close(fig)  # shown through the animation, not as a still figure
    return anim
