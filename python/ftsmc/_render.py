"""Drawing a quadrotor: its arms from its attitude, and the frames of ftsmc.gym.

The vehicle is drawn as a "+" of four arms of ``ARM`` m (a drawing size, not
the scenario's arm length) rotated by the body-to-world rotation
``R = Rz(ψ) Ry(θ) Rx(φ)`` (Z-Y-X Euler angles, paper Eq. 1), with a short
line along the body z axis (the thrust direction). World frame, z up, m.

:class:`FrameRenderer` draws an environment frame with matplotlib's Agg
canvas (no display needed): a top view (x–y) and a side view (x–z) around
the target, the target as a red ring, the vehicle, and its recent trail.
"""

from __future__ import annotations

from typing import Any, List, Optional, Sequence, Tuple

import numpy as np
import numpy.typing as npt

ARM = 0.25
"""Drawn arm length, m."""

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


class FrameRenderer:
    """H×W×3 uint8 frames of a vehicle and its target (module docs).

    span: half-width of each view around the target, m.
    """

    def __init__(self, height: int = 320, width: int = 640, span: float = 2.0, trail: int = 200) -> None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        self.height, self.width, self.span = int(height), int(width), float(span)
        dpi = 100
        self.figure = Figure(figsize=(self.width / dpi, self.height / dpi), dpi=dpi)
        self.canvas: Any = FigureCanvasAgg(self.figure)
        self.axes = self.figure.subplots(1, 2)
        self.figure.subplots_adjust(left=0.08, right=0.98, bottom=0.14, top=0.84, wspace=0.25)
        self.trail: List[FloatArray] = []
        self.max_trail = int(trail)

    def clear_trail(self) -> None:
        """Forget the trail (a new episode)."""
        self.trail = []

    def draw(self, position: Sequence[float], attitude: Sequence[float], target: Sequence[float], time: float) -> Any:
        """The frame (H×W×3 uint8) of the vehicle at ``position`` (m) with
        ``attitude`` (φ, θ, ψ, rad) and the target at ``target`` (m), at ``time`` s."""
        p = np.asarray(position, dtype=float)
        t = np.asarray(target, dtype=float)
        self.trail.append(p)
        if len(self.trail) > self.max_trail:
            self.trail = self.trail[-self.max_trail :]
        path = np.array(self.trail)
        tips, up = arms(p, attitude)
        views = [((0, 1), "top view", "x (m)", "y (m)"), ((0, 2), "side view", "x (m)", "z (m)")]
        for ax, ((i, j), title, xl, yl) in zip(self.axes, views):
            ax.clear()
            ax.set_xlim(t[i] - self.span, t[i] + self.span)
            ax.set_ylim(t[j] - self.span, t[j] + self.span)
            ax.set_aspect("equal")
            ax.grid(alpha=0.3)
            ax.set_title(title, fontsize=9)
            ax.set_xlabel(xl, fontsize=8)
            ax.set_ylabel(yl, fontsize=8)
            ax.tick_params(labelsize=7)
            if j == 2:
                ax.axhspan(t[j] - 10 * self.span, 0.0, color="#d9c9a3", alpha=0.5, zorder=0)  # the ground, z < 0
            ax.plot(path[:, i], path[:, j], color="#9ecae1", lw=1.0, zorder=1)
            ax.plot([t[i]], [t[j]], marker="o", ms=12, mfc="none", mec="#d62728", mew=2, zorder=2)
            for k, color in ((0, "#d62728"), (1, "#333333"), (2, "#333333"), (3, "#333333")):
                ax.plot([p[i], tips[k, i]], [p[j], tips[k, j]], color=color, lw=2.5, zorder=3)
                ax.plot([tips[k, i]], [tips[k, j]], marker="o", ms=5, color=color, zorder=3)
            ax.plot([p[i], up[i]], [p[j], up[j]], color="#1f77b4", lw=1.5, zorder=3)
        self.figure.suptitle(f"t = {time:.2f} s   (target: red ring; front arm red)", fontsize=9)
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
