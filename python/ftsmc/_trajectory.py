"""Trajectories from Python: minimum snap through waypoints and the shape
library of ``[reference] trajectory`` (docs/scenarios.md, "Trajectories"),
built and sampled by the simulator's own code (``ftsmc_sim::trajectory``).

    traj = ftsmc.trajectory(np.array([[0, 0, 1], [1, 0.5, 1.2], [2, -0.5, 1.5]]), speed=1.0)
    s = traj.sample(np.linspace(0.0, traj.end, 200))   # s.position (200, 3), s.snap, s.yaw …
    scenario = traj.into_scenario(ftsmc.Scenario.builtin("realistic-calm-1"))
    run = ftsmc.simulate(scenario, "pid")
    fig = ftsmc.plot.trajectory(traj, run)

Minimum snap (Mellinger and Kumar, ICRA 2011): each of x, y, z and ψ is a
degree-7 polynomial per segment minimising ``Σ ∫ (d⁴q/dt⁴)² dt``, through
every waypoint at its time, at rest at both ends; the interior velocities,
accelerations and jerks solve the closed-form unconstrained QP of Richter,
Bry and Roy (2016, Eq. 31). Units: m, rad, s.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, NamedTuple, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

from . import _ftsmc

if TYPE_CHECKING:
    from ._ftsmc import Scenario

FloatArray = npt.NDArray[np.float64]

SHAPES = tuple(_ftsmc.NativeTrajectory.shape_names())
"""The library's shape names (``ftsmc.trajectory("circle", radius=1.0)``)."""


class TrajectorySample(NamedTuple):
    """A trajectory at N times: every vector is (N, 3), world frame, z up."""

    position: FloatArray
    """m"""
    velocity: FloatArray
    """m/s"""
    acceleration: FloatArray
    """m/s²"""
    jerk: FloatArray
    """m/s³"""
    snap: FloatArray
    """m/s⁴"""
    yaw: FloatArray
    """ψ, rad, (N,)"""
    yaw_rate: FloatArray
    """ψ̇, rad/s, (N,)"""
    yaw_acceleration: FloatArray
    """ψ̈, rad/s², (N,)"""


class Trajectory:
    """A 3-D trajectory with heading whose derivatives up to snap are exact.

    Made by :func:`ftsmc.trajectory`. ``kind`` is ``"min-snap"`` or the
    shape's name; ``start`` and ``end`` (s; ``end`` is None for a shape
    flown without ``laps``) bound its motion: before ``start`` it holds its
    first point, after ``end`` its last, at rest.
    """

    def __init__(self, native: _ftsmc.NativeTrajectory) -> None:
        self._native = native

    @property
    def native(self) -> _ftsmc.NativeTrajectory:
        """The Rust object."""
        return self._native

    @property
    def kind(self) -> str:
        """``"min-snap"`` or the shape's name."""
        return self._native.kind

    @property
    def start(self) -> float:
        """Time the motion starts, s."""
        return self._native.start

    @property
    def end(self) -> Optional[float]:
        """Time it comes to rest for good, s (None: never, a shape without ``laps``)."""
        return self._native.end

    @property
    def times(self) -> Optional[FloatArray]:
        """Minimum snap: the time of each waypoint, s (None for a shape)."""
        return self._native.knot_times()

    def snap_cost(self) -> Optional[FloatArray]:
        """Minimum snap: ``Σ_i ∫ (d⁴q/dt⁴)² dt`` for q = x, y, z (m²/s⁷) and ψ
        (rad²/s⁷), the cost it minimises (None for a shape)."""
        costs = [self._native.snap_cost(o) for o in range(4)]
        if any(c is None for c in costs):
            return None
        return np.array(costs, dtype=float)

    def sample(self, t: Union[float, Sequence[float], npt.ArrayLike]) -> TrajectorySample:
        """Position, velocity, acceleration, jerk and snap ((N, 3) each) and
        ψ, ψ̇, ψ̈ ((N,)) at the times ``t`` (s; a scalar samples one time, N = 1)."""
        times = np.ascontiguousarray(np.atleast_1d(np.asarray(t, dtype=np.float64)).ravel())
        return TrajectorySample(*self._native.sample(times))

    def position(self, t: Union[float, npt.ArrayLike]) -> FloatArray:
        """Position (N, 3) at the times ``t``, m."""
        return self.sample(t).position

    def to_toml(self) -> str:
        """The spec as a TOML inline table: ``[reference] trajectory = …`` in a scenario file."""
        return self._native.to_toml()

    def into_scenario(self, scenario: Scenario, time_scale: str = "fixed", start_on_it: bool = True) -> Scenario:
        """``scenario`` with this trajectory as its ``[reference]``.

        time_scale: ``"fixed"`` refuses (ValueError, the first violating time
            and the limit) a trajectory the vehicle's thrust or tilt limits
            cannot fly; ``"fit"`` stretches its time by the smallest factor
            that fits, with a warning saying by how much.
        start_on_it: start the flight at rest on the trajectory's first point,
            heading ψ there (else the scenario's own initial state).
        """
        return self._native.into_scenario(scenario, time_scale, start_on_it)

    def __repr__(self) -> str:
        end = "never" if self.end is None else f"{self.end:g} s"
        return f"Trajectory({self.kind}, start {self.start:g} s, at rest from {end})"


def trajectory(
    waypoints: Union[str, npt.ArrayLike],
    *,
    speed: Optional[float] = None,
    total_time: Optional[float] = None,
    times: Optional[npt.ArrayLike] = None,
    yaw: Optional[npt.ArrayLike] = None,
    start: Optional[float] = None,
    min_segment_time: Optional[float] = None,
    **shape: Any,
) -> Trajectory:
    """A trajectory: minimum snap through ``waypoints``, or a library shape.

    waypoints: an N × 3 array ``[x, y, z]`` (m), or N × 4 with the heading ψ
        (rad) as the fourth column (2 to 10 000 points, consecutive ones
        different); or a shape name of :data:`SHAPES` with its keys
        (``ftsmc.trajectory("figure-eight", amplitude=[1.0, 0.5], period=8.0, laps=2)``;
        docs/scenarios.md, "Shapes").
    speed: mean speed along each segment, m/s: segment i lasts
        ``max(|w_{i+1} − w_i| / speed, min_segment_time)``.
    total_time: the whole trajectory's duration, s, shared among segments
        in proportion to their lengths.
    times: the time of every waypoint, s, strictly increasing.
        Exactly one of ``speed``, ``total_time`` and ``times``.
    yaw: N headings, rad (with N × 3 waypoints; default 0).
    start: time of the first waypoint with ``speed`` or ``total_time``, s
        (None: the scenario file's default, 0).
    min_segment_time: shortest segment with ``speed``, s (None: the file's default, 0.5).

    Bad input (repeated waypoints, NaN, a speed of 0, non-increasing times,
    too many waypoints, an unknown shape or key) raises ValueError naming
    the key, index and value.
    """
    if isinstance(waypoints, str):
        given = {"speed": speed, "total_time": total_time, "times": times, "yaw": yaw, "min_segment_time": min_segment_time}
        wrong = [k for k, v in given.items() if v is not None]
        if wrong:
            raise ValueError(f"trajectory {waypoints!r}: {', '.join(wrong)} are for waypoints (a shape takes its own keys)")
        if start is not None:
            shape["start"] = start
        return Trajectory(_ftsmc.NativeTrajectory.shape(waypoints, shape))
    if shape:
        raise ValueError(f"unexpected keyword(s) for waypoints: {', '.join(sorted(shape))}")
    w = np.asarray(waypoints, dtype=np.float64)
    if w.ndim != 2:
        raise ValueError(f"trajectory `waypoints` of shape {w.shape} is invalid (expected N × 3 [x, y, z] m, or N × 4 with ψ)")
    try:
        native = _ftsmc.NativeTrajectory.min_snap(
            np.ascontiguousarray(w),
            yaw=_vector(yaw),
            speed=None if speed is None else float(speed),
            duration=None if total_time is None else float(total_time),
            times=_vector(times),
            start=None if start is None else float(start),
            min_segment_time=None if min_segment_time is None else float(min_segment_time),
        )
    except ValueError as e:
        # The file's key is `duration`; this function's is `total_time`.
        raise ValueError(str(e).replace("`duration`", "`total_time`")) from None
    return Trajectory(native)


def _vector(v: Optional[npt.ArrayLike]) -> Optional[FloatArray]:
    return None if v is None else np.ascontiguousarray(np.asarray(v, dtype=np.float64).ravel())
