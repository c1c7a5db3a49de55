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
    fig = ftsmc.plot.trajectory(traj, run)       # a trajectory in 3-D, the flight over it

Needs matplotlib (``pip install "./python[plot]"``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import label

if TYPE_CHECKING:
    import matplotlib.animation
    import matplotlib.axes
    import matplotlib.figure
    import pandas

    from . import Run, Trajectory

__all__ = ["animate", "attitude", "montecarlo_box", "overview", "position", "rotors", "run", "trajectory"]

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


_PIXELS: List[Any] = []
"""The artist class of :func:`_Pixels`, made once."""


def _Pixels(frame: np.ndarray) -> Any:
    """An artist that copies ``frame`` (H×W×4 uint8, bottom row first) onto
    the figure's pixels; resized (Pillow) when the figure is drawn at
    another size (``anim.save(..., dpi=…)``)."""
    if _PIXELS:
        return _PIXELS[0](frame)
    from matplotlib.artist import Artist

    class Pixels(Artist):
        def __init__(self, frame: np.ndarray) -> None:
            super().__init__()
            self.frame = frame

        # Defined here so that matplotlib does not build a signature and
        # docstring of every setter for this class (half a second).
        def set(self, **kwargs: Any) -> Any:
            return Artist.set(self, **kwargs)

        def draw(self, renderer: Any) -> None:
            w, h = (int(round(v)) for v in renderer.get_canvas_width_height())
            im = self.frame
            if im.shape[:2] != (h, w):
                from PIL import Image

                im = np.asarray(Image.fromarray(im, "RGBA").resize((w, h), Image.Resampling.BILINEAR))
            gc = renderer.new_gc()
            renderer.draw_image(gc, 0, 0, im)
            gc.restore()
            self.stale = False

    _PIXELS.append(Pixels)
    return Pixels(frame)


def _fit_box(points: np.ndarray, margin: float, least: float) -> Tuple[np.ndarray, np.ndarray]:
    """Per-axis limits (low, high) holding every finite point of ``points``
    (K × 3) with ``margin`` around it, each axis at least ``least`` wide, m."""
    pts = points[np.isfinite(points).all(axis=1)]
    if len(pts) == 0:
        pts = np.zeros((1, 3))
    lo, hi = pts.min(axis=0) - margin, pts.max(axis=0) + margin
    mid, half = (lo + hi) / 2, np.maximum((hi - lo) / 2, least / 2)
    return mid - half, mid + half


def animate(
    r: Run, frames: int = 120, interval: float = 50.0, arm: Optional[float] = None
) -> matplotlib.animation.FuncAnimation:
    """A 3-D replay of one run: its path (up to the frame's time) and its
    reference (black, dashed), and the vehicle — a "+" of four arms rotated
    by its attitude ``R = Rz(ψ) Ry(θ) Rx(φ)`` (paper Eq. 1), the front arm
    red, drawn to scale — at ``frames`` evenly spaced times, ``interval`` ms apart.

    arm: the arm length drawn, m (default: the flown vehicle's,
        ``run.arm_length``, set by :func:`ftsmc.simulate`; else ``ARM``).
        A dot marks the vehicle's centre, so a small vehicle stays visible.

    The axes hold the whole flight and reference (with an arm's margin) at
    one scale on the three axes, seen from matplotlib's default 3-D view.
    The axes, reference and legend are drawn once; each frame restores
    those pixels and draws only the moving artists on them (blitting), and
    the animation shows the composed frames as an image — so a saved GIF
    costs milliseconds per frame, not a full 3-D redraw.
    ``anim.scene_axes`` is the 3-D axes the frames are drawn from.

    Returns a :class:`matplotlib.animation.FuncAnimation`:
    ``anim.save("flight.gif", writer="pillow")`` writes a GIF (Pillow comes
    with matplotlib); in a notebook ``IPython.display.HTML(anim.to_jshtml())``
    plays it (``to_html5_video()`` needs ffmpeg).
    """
    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from ._render import ARM, arms

    if frames < 1:
        raise ValueError(f"frames = {frames} is invalid (expected at least 1)")
    c = r.columns
    t = c["t"]
    if len(t) == 0:
        raise ValueError(f"run {r!r} recorded no time series (its scenario's record_rate is 0)")
    length = float(arm if arm is not None else (r.arm_length if r.arm_length is not None else ARM))
    if not (np.isfinite(length) and length > 0):
        raise ValueError(f"arm = {length} is invalid (expected a finite arm length > 0, m)")
    p = np.stack([c["x"], c["y"], c["z"]], axis=1)
    att = np.stack([c["phi"], c["theta"], c["psi"]], axis=1)
    ok = np.isfinite(p).all(axis=1) & np.isfinite(att).all(axis=1)
    last = int(np.flatnonzero(ok)[-1]) if ok.any() else 0
    picks = np.unique(np.linspace(0, last, frames).round().astype(int))
    has_ref = all(k in c for k in ("x_ref", "y_ref", "z_ref"))
    ref = np.stack([c["x_ref"], c["y_ref"], c["z_ref"]], axis=1) if has_ref else np.empty((0, 3))
    lo, hi = _fit_box(np.vstack([p[: last + 1][ok[: last + 1]], ref]), 1.5 * length, 6 * length)

    # The scene: a 3-D axes on its own Agg canvas. Its static part (axes,
    # panes, ticks, reference, legend) is drawn once and kept as pixels;
    # each frame restores them and draws only the moving artists (blitting).
    dpi = 100
    scene = Figure(figsize=(6, 5), dpi=dpi)
    canvas: Any = FigureCanvasAgg(scene)  # draw, copy_from_bbox, restore_region: untyped in matplotlib
    scene.subplots_adjust(left=0.0, right=0.95, bottom=0.02, top=0.92)
    ax: Any = scene.add_subplot(projection="3d")  # mpl_toolkits' Axes3D (set_zlim, plot in 3-D)
    if has_ref:
        ax.plot(ref[:, 0], ref[:, 1], ref[:, 2], "k--", lw=1.0, label="reference", zorder=4)
    color = _color(r.controller) or "#1f77b4"
    (path,) = ax.plot([], [], [], color=color, lw=1.4, label=label(r.controller) + _ending(r), animated=True)
    arm_lines = [
        ax.plot([], [], [], color="#d62728" if k == 0 else "#222222", lw=2.5, animated=True)[0] for k in range(4)
    ]
    (up,) = ax.plot([], [], [], color="#1f77b4", lw=1.5, animated=True)
    (centre,) = ax.plot([], [], [], marker="o", ms=3, color="#111111", ls="none", animated=True)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(tuple(hi - lo))  # one scale on x, y and z: the glyph is not distorted
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title(r.scenario, fontsize=10)
    # The clock is the only text redrawn per frame (glyphs cost more than lines).
    title = ax.text2D(1.0, 1.0, "", transform=ax.transAxes, ha="right", va="bottom", fontsize=9, animated=True)
    moving = [path, up, centre, title, *arm_lines]
    canvas.draw()  # the static part (animated artists are skipped)
    background = canvas.copy_from_bbox(scene.bbox)

    def compose(i: int) -> np.ndarray:
        k = int(picks[i])
        path.set_data_3d(p[: k + 1, 0], p[: k + 1, 1], p[: k + 1, 2])
        tips, top = arms(p[k], att[k], length)
        for line, tip in zip(arm_lines, tips):
            line.set_data_3d([p[k, 0], tip[0]], [p[k, 1], tip[1]], [p[k, 2], tip[2]])
        up.set_data_3d([p[k, 0], top[0]], [p[k, 1], top[1]], [p[k, 2], top[2]])
        centre.set_data_3d([p[k, 0]], [p[k, 1]], [p[k, 2]])
        title.set_text(f"t = {t[k]:.2f} s")
        canvas.restore_region(background)
        for artist in moving:
            ax.draw_artist(artist)
        return np.asarray(canvas.buffer_rgba())[::-1].copy()  # rows bottom-up, as draw_image takes them

    # What is shown and saved: the composed frames, copied pixel for pixel
    # onto the figure (an AxesImage would resample every frame).
    fig = plt.figure(figsize=(6, 5), dpi=dpi)
    fig.patch.set_visible(False)  # the frame covers it
    pixels = _Pixels(compose(0))
    fig.add_artist(pixels)

    def draw(i: int) -> List[Any]:
        pixels.frame = compose(i)
        pixels.stale = True
        return [pixels]

    anim = FuncAnimation(fig, draw, frames=len(picks), init_func=lambda: draw(0), interval=interval, blit=True)
    anim.scene_axes = ax  # type: ignore[attr-defined]  # the 3-D axes the frames are drawn from
    plt.close(fig)  # shown through the animation, not as a still figure
    return anim


def trajectory(
    traj: Trajectory, runs: Union[None, Run, Sequence[Run]] = None, until: Optional[float] = None, samples: int = 1000
) -> matplotlib.figure.Figure:
    """A trajectory in 3-D (black, dashed; a minimum-snap one's waypoints
    as black dots) with each run's flown path over it in its controller's
    colour (a × where a run stopped early, the reason in the legend).

    until: last time drawn, s (default: the trajectory's end, else the
        runs' last recorded time, else 10 s after its start).
    samples: points of the trajectory drawn (evenly spaced in time).
    The axes hold everything drawn, at one scale on x, y and z.
    """
    import matplotlib.pyplot as plt

    rs = [] if runs is None else _runs(runs)
    _check_recorded(rs)
    if samples < 2:
        raise ValueError(f"samples = {samples} is invalid (expected at least 2)")
    if until is None:
        ends = [float(r.columns["t"][-1]) for r in rs]
        until = traj.end if traj.end is not None else (max(ends) if ends else traj.start + 10.0)
    if not (np.isfinite(until) and until > traj.start):
        raise ValueError(f"until = {until} is invalid (expected a time after the trajectory's start, {traj.start} s)")
    ref = traj.position(np.linspace(traj.start, until, samples))
    fig = plt.figure(figsize=(6, 5), layout="constrained")
    ax: Any = fig.add_subplot(projection="3d")
    drawn = [ref]
    for r in rs:
        c = r.columns
        xyz = np.stack([c["x"], c["y"], c["z"]], axis=1)
        color = _color(r.controller)
        ax.plot(xyz[:, 0], xyz[:, 1], xyz[:, 2], color=color, lw=1.2, label=label(r.controller) + _ending(r), zorder=2)
        ok = np.isfinite(xyz).all(axis=1)
        if r.exit.status != "completed" and ok.any():
            k = int(np.flatnonzero(ok)[-1])
            ax.plot([xyz[k, 0]], [xyz[k, 1]], [xyz[k, 2]], marker="x", markersize=8, mew=2, color=color, zorder=5)
        drawn.append(xyz)
    ax.plot(ref[:, 0], ref[:, 1], ref[:, 2], "k--", lw=1.0, label=f"trajectory ({traj.kind})", zorder=4)
    knots = traj.times
    if knots is not None:
        w = traj.position(knots)
        ax.plot(w[:, 0], w[:, 1], w[:, 2], "ko", ms=4, ls="none", label="waypoints", zorder=5)
    span = float(np.ptp(ref, axis=0).max()) if len(ref) else 1.0
    lo, hi = _fit_box(np.vstack(drawn), 0.05 * max(span, 0.1), 0.1 * max(span, 0.1))
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(tuple(hi - lo))
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title(f"{traj.kind}: {traj.start:g}–{until:g} s" + (f" ({rs[0].scenario})" if rs else ""), fontsize=9)
    return fig
