"""ftsmc.trajectory: minimum snap against an independent dense QP solve
(scipy), the shape library, bad input as ValueError, and trajectories
flown through a scenario, the Track environment and ftsmc.plot."""

from __future__ import annotations

import math
import warnings
from typing import List, Tuple

import numpy as np
import pytest

import ftsmc

import scipy.linalg as scipy_linalg  # the [test] extra installs scipy

DEGREE = 7
WAYPOINTS = np.array([[0.0, 0.0, 1.0], [1.0, 0.5, 1.2], [2.0, -0.5, 1.5], [1.2, -1.0, 1.1], [0.0, 0.0, 1.0]])
YAW = np.array([0.0, 0.5, 1.0, 0.4, 0.0])


def falling(k: int, m: int) -> float:
    """k (k−1) … (k−m+1): the m-th derivative's factor of t^k."""
    return float(math.prod(range(k - m + 1, k + 1))) if m <= k else 0.0


def basis(tau: float, m: int) -> np.ndarray:
    """d^m/dt^m of [1, t, …, t^7] at t = tau (physical time of the segment)."""
    return np.array([falling(k, m) * tau ** (k - m) if k >= m else 0.0 for k in range(DEGREE + 1)])


def snap_hessian(duration: float) -> np.ndarray:
    """Q with cᵀ Q c = ∫_0^T (d⁴p/dt⁴)² dt for p = Σ c_k t^k."""
    q = np.zeros((DEGREE + 1, DEGREE + 1))
    for k in range(4, DEGREE + 1):
        for m in range(4, DEGREE + 1):
            power = k + m - 7
            q[k, m] = falling(k, 4) * falling(m, 4) * duration**power / power
    return q


def dense_min_snap(times: np.ndarray, values: np.ndarray) -> Tuple[List[np.ndarray], float]:
    """Minimise Σ ∫ snap² over degree-7 pieces through `values` at `times`,
    at rest (v = a = j = 0) at both ends, C³ at the interior knots: the
    KKT system of the equality-constrained QP, solved densely (scipy)."""
    segments = len(times) - 1
    n = (DEGREE + 1) * segments
    hess = np.zeros((n, n))
    rows: List[np.ndarray] = []
    rhs: List[float] = []

    def row() -> np.ndarray:
        return np.zeros(n)

    for i in range(segments):
        h = times[i + 1] - times[i]
        sl = slice(8 * i, 8 * i + 8)
        hess[sl, sl] = snap_hessian(h)
        for tau, v in ((0.0, values[i]), (h, values[i + 1])):
            a = row()
            a[sl] = basis(tau, 0)
            rows.append(a)
            rhs.append(v)
    for m in (1, 2, 3):
        a = row()
        a[0:8] = basis(0.0, m)
        rows.append(a)
        rhs.append(0.0)
        a = row()
        a[n - 8 : n] = basis(times[-1] - times[-2], m)
        rows.append(a)
        rhs.append(0.0)
        for i in range(segments - 1):
            a = row()
            a[8 * i : 8 * i + 8] = basis(times[i + 1] - times[i], m)
            a[8 * (i + 1) : 8 * (i + 1) + 8] = -basis(0.0, m)
            rows.append(a)
            rhs.append(0.0)
    big_a = np.array(rows)
    k = len(rows)
    kkt = np.block([[2 * hess, big_a.T], [big_a, np.zeros((k, k))]])
    sol = scipy_linalg.solve(kkt, np.concatenate([np.zeros(n), rhs]))
    c = sol[:n]
    return [c[8 * i : 8 * i + 8] for i in range(segments)], float(c @ hess @ c)


def dense_sample(times: np.ndarray, coef: List[np.ndarray], t: float, m: int) -> float:
    i = int(np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2))
    return float(basis(t - times[i], m) @ coef[i])


def test_min_snap_matches_a_dense_qp_solve() -> None:
    traj = ftsmc.trajectory(np.column_stack([WAYPOINTS, YAW]), speed=0.8)
    times = traj.times
    assert times is not None and len(times) == len(WAYPOINTS)
    t = np.linspace(times[0], times[-1], 301)
    s = traj.sample(t)
    ours = [s.position, s.velocity, s.acceleration, s.jerk, s.snap]
    costs = traj.snap_cost()
    assert costs is not None
    for o in range(4):
        coef, cost = dense_min_snap(times, np.append(WAYPOINTS, YAW[:, None], axis=1)[:, o])
        assert costs[o] == pytest.approx(cost, rel=1e-6)
        for m in range(5 if o < 3 else 3):
            dense = np.array([dense_sample(times, coef, tk, m) for tk in t])
            mine = ours[m][:, o] if o < 3 else [s.yaw, s.yaw_rate, s.yaw_acceleration][m]
            scale = float(np.max(np.abs(dense)))
            assert scale > 0
            # The snap jumps at both ends (the trajectory holds at rest outside
            # [start, end], and is at rest there up to the jerk): compared inside.
            inside = slice(1, -1) if m == 4 else slice(None)
            assert np.max(np.abs(np.asarray(mine)[inside] - dense[inside])) <= 1e-6 * scale, (o, m)


def test_min_snap_passes_the_waypoints_at_rest_at_the_ends() -> None:
    traj = ftsmc.trajectory(WAYPOINTS, yaw=YAW, total_time=12.0, start=1.0)
    times = traj.times
    assert times is not None
    assert times[0] == 1.0 and times[-1] == pytest.approx(13.0)
    s = traj.sample(times)
    assert np.allclose(s.position, WAYPOINTS, atol=1e-12)
    assert np.allclose(s.yaw, YAW, atol=1e-12)
    for end in (0, -1):
        assert np.allclose(s.velocity[end], 0.0, atol=1e-12) and np.allclose(s.acceleration[end], 0.0, atol=1e-12)
    # Held before the start and after the end, at rest.
    out = traj.sample([0.0, 20.0])
    assert np.allclose(out.position, WAYPOINTS[[0, -1]]) and not out.velocity.any()
    assert traj.start == 1.0 and traj.end == pytest.approx(13.0) and traj.kind == "min-snap"
    assert "min-snap" in traj.to_toml() and "waypoints" in traj.to_toml()


def test_derivatives_agree_with_finite_differences() -> None:
    for traj in (ftsmc.trajectory(WAYPOINTS, speed=1.0), ftsmc.trajectory("figure-eight", period=6.0, laps=2)):
        end = traj.end
        assert end is not None
        t = np.linspace(traj.start + 0.3, end - 0.3, 50)
        h = 1e-4
        s, plus, minus = traj.sample(t), traj.sample(t + h), traj.sample(t - h)
        for lo, hi, d in (
            (minus.position, plus.position, s.velocity),
            (minus.velocity, plus.velocity, s.acceleration),
            (minus.acceleration, plus.acceleration, s.jerk),
            (minus.jerk, plus.jerk, s.snap),
        ):
            fd = (hi - lo) / (2 * h)
            assert np.max(np.abs(fd - d)) <= 1e-5 * max(1.0, float(np.max(np.abs(d))))


@pytest.mark.parametrize("shape", ftsmc.TRAJECTORY_SHAPES)
def test_every_library_shape_builds_and_samples(shape: str) -> None:
    traj = ftsmc.trajectory(shape, center=[0.5, -0.5, 1.5], period=8.0)
    s = traj.sample(np.linspace(0.0, 20.0, 101))
    assert s.position.shape == (101, 3) and np.isfinite(s.position).all()
    assert np.allclose(s.position[0], traj.position(0.0)[0])
    assert traj.kind == shape and traj.times is None and traj.snap_cost() is None


def test_a_circle_keeps_its_radius_after_the_smooth_start() -> None:
    traj = ftsmc.trajectory("circle", radius=0.7, center=[1.0, 2.0, 1.5], period=5.0, ramp=2.0)
    p = traj.position(np.linspace(2.0, 12.0, 200))
    assert np.allclose(np.hypot(p[:, 0] - 1.0, p[:, 1] - 2.0), 0.7, atol=1e-12)
    assert np.allclose(p[:, 2], 1.5)
    assert traj.end is None


@pytest.mark.parametrize(
    ("waypoints", "kwargs", "message"),
    [
        ([[0, 0, 1], [1, 0, 1], [1, 0, 1]], {"speed": 1.0}, r"`waypoints\[2\]` = \[1, 0, 1\] is invalid .*waypoints\[1\]"),
        ([[0, 0, 1], [1, 0, float("nan")]], {"speed": 1.0}, r"`waypoints\[1\]\[2\]` = NaN"),
        ([[0, 0, 1], [1, 0, 1]], {"speed": 0.0}, r"`speed` = 0 is invalid"),
        ([[0, 0, 1], [1, 0, 1]], {"speed": -1.0}, r"`speed` = -1 is invalid"),
        ([[0, 0, 1], [1, 0, 1]], {"total_time": 0.0}, r"`total_time` = 0 is invalid"),
        ([[0, 0, 1], [1, 0, 1], [2, 0, 1]], {"times": [0.0, 2.0, 2.0]}, r"`times\[2\]` = 2 is invalid"),
        ([[0, 0, 1], [1, 0, 1]], {"times": [0.0]}, r"`times` = 1 times"),
        ([[0, 0, 1], [1, 0, 1]], {}, r"exactly one of `speed` \(m/s\), `total_time`"),
        ([[0, 0, 1], [1, 0, 1]], {"speed": 1.0, "total_time": 2.0}, r"exactly one of"),
        ([[0, 0, 1]], {"speed": 1.0}, r"at least 2 waypoints"),
        ([[0, 0], [1, 0]], {"speed": 1.0}, r"shape \(2, 2\)"),
        ([0, 0, 1], {"speed": 1.0}, r"shape \(3,\)"),
        ([[0, 0, 1], [1, 0, 1]], {"speed": 1.0, "yaw": [0.0]}, r"`yaw` = 1 headings"),
        ([[0, 0, 1, 0], [1, 0, 1, 0]], {"speed": 1.0, "yaw": [0.0, 0.0]}, r"`yaw` is given twice"),
    ],
)
def test_bad_waypoints_are_a_value_error_naming_the_key(waypoints: object, kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        ftsmc.trajectory(np.asarray(waypoints, dtype=float), **kwargs)


def test_too_many_waypoints_are_refused_by_their_count() -> None:
    # 10^6 waypoints: refused from the array's shape, before any copy or solve.
    w = np.zeros((1_000_000, 3))
    with pytest.raises(ValueError, match=r"1000000 waypoints .* at most 10000"):
        ftsmc.trajectory(w, speed=1.0)
    # 10 000 is the limit and solves (linear time).
    w = np.column_stack([np.arange(10_000) * 0.1, np.zeros(10_000), np.ones(10_000)])
    assert ftsmc.trajectory(w, speed=1.0).times is not None


def test_bad_shapes_are_a_value_error() -> None:
    with pytest.raises(ValueError, match="square"):
        ftsmc.trajectory("square")
    with pytest.raises(ValueError, match="radius"):
        ftsmc.trajectory("circle", radius=float("nan"))
    with pytest.raises(ValueError, match="colour"):
        ftsmc.trajectory("circle", colour="red")
    with pytest.raises(ValueError, match="speed"):
        ftsmc.trajectory("circle", speed=1.0)
    with pytest.raises(ValueError, match="min-snap"):
        ftsmc.trajectory("min-snap")


def slow_square() -> ftsmc.Trajectory:
    w = np.array([[0, 0, 1], [0.5, 0, 1], [0.5, 0.5, 1.2], [0, 0.5, 1.2], [0, 0, 1]], dtype=float)
    return ftsmc.trajectory(w, total_time=6.0)


def test_a_trajectory_is_flown_through_a_scenario_and_plotted() -> None:
    traj = slow_square()
    scenario = traj.into_scenario(ftsmc.Scenario.builtin("realistic-calm-1").with_overrides({"duration": 8.0}))
    run = ftsmc.simulate(scenario, "pid")
    assert run.exit.status == "completed"
    c = run.columns
    ref = traj.position(c["t"])
    assert np.allclose(np.stack([c["x_ref"], c["y_ref"], c["z_ref"]], axis=1), ref, atol=1e-9)
    err = np.hypot(np.hypot(c["x"] - ref[:, 0], c["y"] - ref[:, 1]), c["z"] - ref[:, 2])
    assert err.max() < 0.2, err.max()

    fig = ftsmc.plot.trajectory(traj, run)
    ax = fig.axes[0]
    for lim, col in zip((ax.get_xlim(), ax.get_ylim(), ax.get_zlim()), ("x", "y", "z")):
        assert lim[0] <= min(c[col].min(), ref[:, "xyz".index(col)].min())
        assert lim[1] >= max(c[col].max(), ref[:, "xyz".index(col)].max())
    labels = ax.get_legend_handles_labels()[1]
    assert "trajectory (min-snap)" in labels and "waypoints" in labels and "PID/PX4 cascade" in " ".join(labels) or len(labels) == 3
    with pytest.raises(ValueError, match="samples"):
        ftsmc.plot.trajectory(traj, samples=1)


def test_an_infeasible_trajectory_is_refused_or_fitted() -> None:
    fast = ftsmc.trajectory("figure-eight", period=1.0, laps=2, ramp=0.5)
    base = ftsmc.Scenario.builtin("realistic-calm-1")
    with pytest.raises(ValueError, match="the vehicle can fly"):
        fast.into_scenario(base)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fitted = fast.into_scenario(base, time_scale="fit")
    assert isinstance(fitted, ftsmc.Scenario)
    assert any("stretch" in str(w.message) or "slow" in str(w.message) for w in caught), [str(w.message) for w in caught]
    with pytest.raises(ValueError, match="time_scale"):
        fast.into_scenario(base, time_scale="fast")


def test_the_track_env_follows_any_trajectory() -> None:
    gym = pytest.importorskip("gymnasium")
    import ftsmc.gym  # noqa: F401  (registers the environments)

    traj = slow_square()
    env = gym.make("ftsmc/Track-v0", trajectory=traj, observe="truth", max_episode_time=3.0)
    obs, info = env.reset(seed=1)
    assert np.allclose(obs[:6], 0.0, atol=1e-9), obs[:6]  # starts at rest on the trajectory
    engine = env.unwrapped.engine
    for _ in range(100):
        obs, _, terminated, truncated, info = env.step(np.zeros(4, dtype=np.float32))
        if terminated or truncated:
            break
    _, _, reference = engine.pose(0)
    assert np.allclose(reference, traj.position(info["time"])[0], atol=1e-9)
    vec = ftsmc.gym.FtsmcVectorEnv(2, task="track", trajectory=traj, max_episode_time=1.0)
    vec.reset(seed=0)
    assert np.allclose(vec.engine.pose(1)[2], traj.position(0.0)[0])
    with pytest.raises(ValueError, match="only for task"):
        ftsmc.gym.FtsmcEnv(task="hover", trajectory=traj)
    with pytest.raises(ValueError, match="ftsmc.Trajectory"):
        ftsmc.gym.FtsmcEnv(task="track", trajectory="circle")  # type: ignore[arg-type]
