"""Drawing a quadrotor: its arms from its attitude, and the frames of ftsmc.gym.

The vehicle is drawn as a "+" of four arms of its own arm length (the
scenario's vehicle geometry, ``ftsmc._ftsmc.vehicle_arm_length``; ``ARM``
when unknown) rotated by the body-to-world rotation
``R = Rz(ψ) Ry(θ) Rx(φ)`` (Z-Y-X Euler angles, paper Eq. 1), with a short
line along the body z axis (the thrust direction). World frame, z up, m.

:class:`FrameRenderer` draws an environment frame with matplotlib's Agg
canvas (no display needed): a top view (x–y) and a side view (x–z) around
the target, grown to hold the vehicle and its trail, the target as a red
ring, the vehicle, and its recent trail (its position at each of the last
``trail`` environment steps).
"""

from __future__ import annotations

from typing import Any, List, Optional, Sequence, Tuple

import numpy as np
import numpy.typing as npt

ARM = 0.25
"""Arm length drawn when the vehicle's is not known, m."""

FloatArray = npt.NDArray[np.float64]


def rotation(attitude: npt.ArrayLike) -> FloatArray:
    """Body-to-world rotation ``Rz(ψ) Ry(θ) Rx(φ)`` of Euler angles (φ, θ, ψ), rad."""
    phi, theta, psi = (float(a) for a in np.asarray(attitude, dtype=float))
    cf, sf = np.cos(phi), np.sin(phi)
    ct, st = np.cos(theta), np.sin(theta)
    cp, sp = np.cos(psi), np.sin(psi)
    return np.array(
        [
            [cp * ct, cp * st * sf - sp * cf, cp * st * cf + sp * sf],
            [sp * ct, sp * st * sf + cp * cf, sp * st * cf - cp * sf],
            [-st, ct * sf, ct * cf],
        ]
    )


def arms(position: npt.ArrayLike, attitude: npt.ArrayLike, arm: float = ARM) -> Tuple[FloatArray, FloatArray]:
    """World coordinates (m) of the four arm tips (4×3) and of the tip of the
    body z axis (3,) of a vehicle at ``position`` with ``attitude``."""
    r = rotation(attitude)
    body = np.array([[arm, 0, 0], [0, arm, 0], [-arm, 0, 0], [0, -arm, 0]], dtype=float)
    p = np.asarray(position, dtype=float)
    tips = p + body @ r.T
    up = p + r @ np.array([0.0, 0.0, 0.6 * arm])
    return tips, up


def view_limits(
    center: npt.ArrayLike, span: float, points: npt.ArrayLike, margin: float
) -> Tuple[FloatArray, FloatArray]:
    """Limits (low, high) per axis of a view that holds ``center ± span``
    and every point of ``points`` (K × D) with ``margin`` around it, m."""
    c = np.asarray(center, dtype=float)
    lo, hi = c - span, c + span
    pts = np.asarray(points, dtype=float).reshape(-1, c.size)
    pts = pts[np.isfinite(pts).all(axis=1)]
    if len(pts):
        lo = np.minimum(lo, pts.min(axis=0) - margin)
        hi = np.maximum(hi, pts.max(axis=0) + margin)
    return lo, hi


class FrameRenderer:
    """H×W×3 uint8 frames of a vehicle and its target (module docs).

    span: least half-width of each view around the target, m; the view
        grows to hold the vehicle and its whole trail.
    arm: the vehicle's arm length, m (drawn to scale; a dot marks its
        centre, so a small vehicle stays visible in a wide view).
    trail: positions kept in the trail (the last ``trail`` recorded).
    """

    def __init__(
        self, height: int = 320, width: int = 640, span: float = 2.0, trail: int = 200, arm: float = ARM
    ) -> None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        self.height, self.width, self.span, self.arm = int(height), int(width), float(span), float(arm)
        dpi = 100
        self.figure = Figure(figsize=(self.width / dpi, self.height / dpi), dpi=dpi)
        self.canvas: Any = FigureCanvasAgg(self.figure)
        self.axes = list(self.figure.subplots(1, 2))
        self.figure.subplots_adjust(left=0.08, right=0.98, bottom=0.14, top=0.84, wspace=0.25)
        self.trail: List[FloatArray] = []
        self.max_trail = int(trail)
        self.views = [((0, 1), "top view", "x (m)", "y (m)"), ((0, 2), "side view", "x (m)", "z (m)")]
        # The artists are made once and moved at every frame (no ax.clear()).
        self.trail_lines: List[Any] = []
        self.targets: List[Any] = []
        self.arm_lines: List[List[Any]] = []
        self.rotors: List[Any] = []
        self.centres: List[Any] = []
        self.ups: List[Any] = []
        self.grounds: List[Any] = []
        for ax, ((_, j), title, xl, yl) in zip(self.axes, self.views):
            ax.set_aspect("equal")
            ax.grid(alpha=0.3)
            ax.set_title(title, fontsize=9)
            ax.set_xlabel(xl, fontsize=8)
            ax.set_ylabel(yl, fontsize=8)
            ax.tick_params(labelsize=7)
            if j == 2:  # the ground, z < 0
                self.grounds.append(ax.axhspan(-1e6, 0.0, color="#d9c9a3", alpha=0.5, zorder=0))
            (line,) = ax.plot([], [], color="#1f77b4", lw=1.2, alpha=0.8, zorder=1, label="trail")
            self.trail_lines.append(line)
            (target,) = ax.plot([], [], marker="o", ms=12, mfc="none", mec="#d62728", mew=2, ls="none", zorder=2)
            self.targets.append(target)
            arms_here = []
            for k in range(4):
                (a,) = ax.plot([], [], color="#d62728" if k == 0 else "#333333", lw=2.5, zorder=3)
                arms_here.append(a)
            self.arm_lines.append(arms_here)
            (rotor,) = ax.plot([], [], marker="o", ms=4, color="#333333", ls="none", zorder=3)
            self.rotors.append(rotor)
            (centre,) = ax.plot([], [], marker="o", ms=3, color="#111111", ls="none", zorder=4)
            self.centres.append(centre)
            (up,) = ax.plot([], [], color="#1f77b4", lw=1.5, zorder=3)
            self.ups.append(up)
        self.title = self.figure.suptitle("", fontsize=9)

    def clear_trail(self) -> None:
        """Forget the trail (a new episode)."""
        self.trail = []

    def record(self, position: npt.ArrayLike) -> None:
        """Add ``position`` (m) to the trail (called at every environment step)."""
        self.trail.append(np.asarray(position, dtype=float))
        if len(self.trail) > self.max_trail:
            del self.trail[: len(self.trail) - self.max_trail]

    def draw(self, position: Sequence[float], attitude: Sequence[float], target: Sequence[float], time: float) -> Any:
        """The frame (H×W×3 uint8) of the vehicle at ``position`` (m) with
        ``attitude`` (φ, θ, ψ, rad) and the target at ``target`` (m), at ``time`` s."""
        p = np.asarray(position, dtype=float)
        t = np.asarray(target, dtype=float)
        if not self.trail or not np.array_equal(self.trail[-1], p):
            self.record(p)
        path = np.array(self.trail)
        tips, up = arms(p, attitude, self.arm)
        margin = max(0.1 * self.span, 1.5 * self.arm)
        for n, (ax, ((i, j), _, _, _)) in enumerate(zip(self.axes, self.views)):
            lo, hi = view_limits(t[[i, j]], self.span, np.vstack([path[:, [i, j]], tips[:, [i, j]]]), margin)
            half = float(np.max(hi - lo)) / 2  # one scale on both axes (equal aspect)
            mid = (lo + hi) / 2
            ax.set_xlim(mid[0] - half, mid[0] + half)
            ax.set_ylim(mid[1] - half, mid[1] + half)
            self.trail_lines[n].set_data(path[:, i], path[:, j])
            self.targets[n].set_data([t[i]], [t[j]])
            for k, line in enumerate(self.arm_lines[n]):
                line.set_data([p[i], tips[k, i]], [p[j], tips[k, j]])
            self.rotors[n].set_data(tips[:, i], tips[:, j])
            self.centres[n].set_data([p[i]], [p[j]])
            self.ups[n].set_data([p[i], up[i]], [p[j], up[j]])
        self.title.set_text(f"t = {time:.2f} s   (target: red ring; front arm red; trail blue)")
        self.canvas.draw()
        rgba = np.asarray(self.canvas.buffer_rgba())
        return np.ascontiguousarray(rgba[:, :, :3], dtype=np.uint8)


class HumanWindow:
    """Shows frames in a matplotlib window (``render_mode="human"``); with a
    non-interactive backend (Agg) nothing is shown and nothing is printed."""

    def __init__(self, fps: float) -> None:
        self.fps = float(fps)
        self.figure: Optional[Any] = None
        self.image: Optional[Any] = None

    def show(self, frame: Any) -> None:
        """Show ``frame`` (H×W×3 uint8) and wait one frame period."""
        import matplotlib
        import matplotlib.pyplot as plt

        interactive = matplotlib.get_backend().lower() not in {"agg", "pdf", "ps", "svg", "cairo", "template"}
        if self.figure is None:
            h, w = frame.shape[:2]
            self.figure = plt.figure(figsize=(w / 100, h / 100), dpi=100)
            ax = self.figure.add_axes((0, 0, 1, 1))
            ax.set_axis_off()
            self.image = ax.imshow(frame)
            if interactive:
                plt.show(block=False)
        elif self.image is not None:
            self.image.set_data(frame)
        if interactive:
            self.figure.canvas.draw_idle()
            self.figure.canvas.start_event_loop(1.0 / self.fps)

    def close(self) -> None:
        """Close the window."""
        if self.figure is not None:
            import matplotlib.pyplot as plt

            plt.close(self.figure)
            self.figure = None
