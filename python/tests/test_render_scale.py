"""Drawing a vehicle to its scale, in a view that holds the flight: the
3-D replay (ftsmc.plot.animate) and the Gymnasium frames (trail, glyph,
view limits)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import ftsmc

pytest.importorskip("matplotlib")

CRAZYFLIE = {"vehicle.preset": "crazyflie-2", "duration": 3.0}


def arm_lengths_3d(lines: Any) -> np.ndarray:
    out = []
    for line in lines:
        x, y, z = line.get_data_3d()
        out.append(np.sqrt((x[1] - x[0]) ** 2 + (y[1] - y[0]) ** 2 + (z[1] - z[0]) ** 2))
    return np.array(out)


def four_arms(ax: Any) -> list:
    return [ln for ln in ax.get_lines() if ln.get_linewidth() == 2.5]


@pytest.mark.parametrize("overrides", [CRAZYFLIE, {"duration": 3.0}])
def test_animate_draws_the_vehicle_to_its_own_scale(overrides: dict) -> None:
    scenario = ftsmc.Scenario.builtin("realistic-calm-1").with_overrides(overrides)
    run = ftsmc.simulate(scenario, "pid")
    arm = ftsmc._ftsmc.vehicle_arm_length(scenario)
    assert run.arm_length == arm
    anim = ftsmc.plot.animate(run, frames=5)
    anim._func(3)  # draw a frame
    ax = anim.scene_axes
    lines = four_arms(ax)
    assert len(lines) == 4
    assert np.allclose(arm_lengths_3d(lines), arm, rtol=1e-12)
    # A Crazyflie's arms are centimetres, a Hummingbird's about 0.17 m.
    assert (arm < 0.06) == (overrides is CRAZYFLIE)
    # An explicit arm wins.
    anim = ftsmc.plot.animate(run, frames=2, arm=0.3)
    anim._func(1)
    assert np.allclose(arm_lengths_3d(four_arms(anim.scene_axes)), 0.3)
    with pytest.raises(ValueError, match="arm"):
        ftsmc.plot.animate(run, arm=0.0)


def test_animate_axes_hold_the_flight_and_its_reference_and_blit() -> None:
    run = ftsmc.simulate(ftsmc.Scenario.builtin("paper-scenario-1").with_overrides({"duration": 4.0}), "ftaftsmc")
    anim = ftsmc.plot.animate(run, frames=4)
    ax = anim.scene_axes
    c = run.columns
    for lim, col in zip((ax.get_xlim(), ax.get_ylim(), ax.get_zlim()), "xyz"):
        values = np.concatenate([c[col], c[f"{col}_ref"]])
        assert lim[0] <= values.min() and lim[1] >= values.max(), (col, lim)
    # Only the moving artists are redrawn, and no layout engine runs per frame.
    assert anim._blit and anim._fig.get_layout_engine() is None
    moving = anim._func(2)
    assert all(a.get_animated() for a in moving)


def test_gym_frames_show_the_trail_the_vehicle_to_scale_and_fit_the_flight() -> None:
    gym = pytest.importorskip("gymnasium")
    import ftsmc.gym

    scenario = ftsmc.Scenario.builtin("realistic-calm-1").with_overrides({"vehicle.preset": "crazyflie-2"})
    env = gym.make("ftsmc/Hover-v0", scenario=scenario, render_mode="rgb_array", hover_radius=5.0, max_episode_time=3.0)
    env.reset(seed=0)
    steps = 0
    for _ in range(150):  # full thrust: climbs well above the 2 m view around the target
        _, _, terminated, truncated, _ = env.step(np.array([1.0, 0.0, 0.0, 0.0], dtype=np.float32))
        steps += 1
        if terminated or truncated:
            break
    frame = env.render()
    assert frame.shape == ftsmc.gym.RENDER_SHAPE
    renderer = env.unwrapped._renderer
    assert renderer is not None
    # The trail holds every step since the reset (rendered once, at the end).
    assert len(renderer.trail) == min(steps + 1, renderer.max_trail)
    position, _, _ = env.unwrapped.engine.pose(0)
    assert position[2] > 3.0, position
    for ax, line in zip(renderer.axes, renderer.trail_lines):
        xs, ys = line.get_data()
        assert len(xs) == len(renderer.trail)
        # The view holds the whole trail (the vehicle at z > 3 m is not clipped).
        (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
        assert x0 <= np.min(xs) and x1 >= np.max(xs) and y0 <= np.min(ys) and y1 >= np.max(ys)
    # The glyph is the Crazyflie's own size.
    arm = ftsmc._ftsmc.vehicle_arm_length(scenario)
    assert renderer.arm == arm and arm < 0.06
    top_arms = renderer.arm_lines[0]
    x, y = top_arms[0].get_data()
    assert np.hypot(x[1] - x[0], y[1] - y[0]) <= arm + 1e-12
    # The trail's blue is in the picture.
    # (A 1.2-pixel antialiased line: bluish pixels, blue well above red; the
    # 5 m climb in the side view is about 150 pixels long.)
    rgb = frame.astype(int)
    blue = (rgb[:, :, 2] - rgb[:, :, 0] > 60) & (rgb[:, :, 2] > 120)
    assert blue.sum() > 50, blue.sum()
