"""Gymnasium environments of ftsmc, stepped in Rust (docs/python.md, "Gymnasium environments").

``import ftsmc.gym`` registers:

- ``ftsmc/Hover-v0``: hold a point (default 1 m above the origin) from rest
  there; collective thrust and body rates (``action="ctbr"``); 10 s episodes
  (``max_episode_steps`` 1000 at the default 100 Hz), which end (terminated)
  once the vehicle is more than ``hover_radius`` (default 2 m) from the
  target along any axis.
- ``ftsmc/HoverMotors-v0``: the same with the four rotor speeds as the action
  (``action="motors"``).
- ``ftsmc/Track-v0``: track the scenario's own reference from its initial
  state — or any :class:`ftsmc.Trajectory` (``trajectory=``), from rest on
  its first point; collective thrust and body rates; the scenario's duration
  (``max_episode_steps`` 2000: the default scenario's 20 s at 100 Hz).

``max_episode_steps`` matches the default ``agent_rate``; the environment
itself truncates at its episode time, so with another rate pass
``max_episode_steps`` to ``gym.make`` too (or ``None``).

``render_mode="rgb_array"`` makes :meth:`FtsmcEnv.render` return an H×W×3
uint8 frame (``RENDER_SHAPE``): a top view (x–y) and a side view (x–z) of
the vehicle (a "+" of its arms, to the scale of the scenario's vehicle,
rotated by its true attitude, the front arm red), its trail (its position
at each of the last 200 steps, recorded at every step) and the target (a
red ring), each view grown to hold the vehicle and its trail, drawn with matplotlib's Agg
canvas (no display needed); ``render_mode="human"`` shows the same frames
in a matplotlib window at ``metadata["render_fps"]``.

The default scenario is ``realistic-breeze-1``, the breeze rung of the wind
ladder (an AscTec Hummingbird rigid body with lagged motors and PX4's mixer,
motion capture at 200 Hz / 6 ms and an IMU at 1 kHz / 1 ms, a 5 kt wind with
its Dryden turbulence, the ground). Any scenario can
be flown: ``gym.make("ftsmc/Hover-v0", scenario=ftsmc.Scenario.builtin(...))``
or a file path or built-in name.

Every keyword of :class:`FtsmcEnv` is accepted by ``gym.make`` and
``gym.make_vec`` (``vectorization_mode="vector_entry_point"`` steps all
environments in one Rust call: :class:`FtsmcVectorEnv`).
"""

from __future__ import annotations

from os import PathLike
from typing import Any, Dict, List, Mapping, Optional, Sequence, SupportsFloat, Tuple, Union, cast

import gymnasium as gym
import numpy as np
import numpy.typing as npt
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from . import _ftsmc
from ._ftsmc import Scenario
from ._trajectory import Trajectory
from ._render import FrameRenderer, HumanWindow

__all__ = [
    "FtsmcEnv",
    "FtsmcVectorEnv",
    "OBSERVATION_NAMES",
    "DEFAULT_SCENARIO",
    "ENV_IDS",
    "HOVER_RADIUS",
    "RENDER_MODES",
    "RENDER_SHAPE",
]

ObsArray = npt.NDArray[np.float32]
ActArray = npt.NDArray[np.float32]
AnyArray = npt.NDArray[Any]

DEFAULT_SCENARIO = "realistic-breeze-1"
"""The scenario flown when none is given."""

OBSERVATION_NAMES: List[str] = list(_ftsmc.GymBatch.observation_names())
"""The 18 observation entries: position error (m), velocity error (m/s), rows of R, body rates (rad/s)."""

ENV_IDS = ("ftsmc/Hover-v0", "ftsmc/HoverMotors-v0", "ftsmc/Track-v0")
"""The registered environment ids."""

HOVER_RADIUS = 2.0
"""Default ``hover_radius``, m: a hover episode ends (terminated, ``"diverged
(position error)"``) once any axis of the position error exceeds it."""

RENDER_MODES = ["rgb_array", "human"]
"""The render modes."""

RENDER_SHAPE = (320, 640, 3)
"""Shape of a frame of ``render_mode="rgb_array"`` (H, W, RGB), uint8."""

RENDER_FPS = 100
"""Frames per second of ``render_mode="human"`` (one per environment step at
the default ``agent_rate``)."""

ScenarioLike = Union[None, Scenario, str, "PathLike[str]"]

_SEED_BOUND = 2**63


def _scenario(scenario: ScenarioLike) -> Scenario:
    """A Scenario from None (the default), a Scenario, a built-in name or a file path."""
    if scenario is None:
        return Scenario.builtin(DEFAULT_SCENARIO)
    if isinstance(scenario, Scenario):
        return scenario
    text = str(scenario)
    if not text.endswith(".toml") or "/" not in text:
        try:
            return Scenario.builtin(text)
        except ValueError:
            pass
    return Scenario.from_file(text)


def _flown(scenario: ScenarioLike, task: str, trajectory: Optional[Trajectory], time_scale: str) -> Scenario:
    """The scenario an environment flies: with ``trajectory`` (task
    ``"track"`` only) as its reference, started at rest on its first point."""
    s = _scenario(scenario)
    if trajectory is None:
        return s
    if task != "track":
        raise ValueError(f"`trajectory` is only for task = \"track\" (task = {task!r})")
    if not isinstance(trajectory, Trajectory):
        raise ValueError(f"`trajectory` = {trajectory!r} is invalid (expected an ftsmc.Trajectory: ftsmc.trajectory(...))")
    return trajectory.into_scenario(s, time_scale=time_scale)


def _batch(scenario: Scenario, num_envs: int, settings: Mapping[str, Any]) -> _ftsmc.GymBatch:
    s = scenario
    # Priced before anything is allocated for the environments.
    _ftsmc.gym_check_envs(s, num_envs)
    return _ftsmc.GymBatch(s, [0] * num_envs, **settings)


def _settings(
    task: str,
    target: Optional[Sequence[float]],
    action: str,
    observe: str,
    agent_rate: float,
    max_episode_time: Optional[float],
    reward: Optional[Mapping[str, float]],
    rate_gain: Optional[Sequence[float]],
    max_rate: Optional[Sequence[float]],
    randomize: bool,
    hover_radius: Optional[float] = None,
) -> Dict[str, Any]:
    if hover_radius is None and task == "hover":
        hover_radius = HOVER_RADIUS
    return {
        "hover_radius": None if hover_radius is None else float(hover_radius),
        "task": task,
        "target": None if target is None else [float(v) for v in target],
        "action": action,
        "observe": observe,
        "agent_rate": float(agent_rate),
        "max_episode_time": None if max_episode_time is None else float(max_episode_time),
        "reward": None if reward is None else {str(k): float(v) for k, v in reward.items()},
        "rate_gain": None if rate_gain is None else [float(v) for v in rate_gain],
        "max_rate": None if max_rate is None else [float(v) for v in max_rate],
        "randomize": bool(randomize),
    }


MAX_BODY_RATE = 200.0 * np.pi
"""Bound of the observed body rates, rad/s (100 revolutions per second:
beyond any quadrotor; ``max_tilt`` ends a flight long before)."""

WIND_ALLOWANCE = 100.0
"""Speed, m/s, added to the thrust-and-gravity bound of the velocity error
(a wind can carry the vehicle and the reference can move)."""


def _spaces(engine: _ftsmc.GymBatch) -> Tuple[spaces.Space[ObsArray], spaces.Space[ActArray]]:
    """Observation bounds that the physics and the episode's end guarantee:
    the rows of R lie in [-1, 1]; the velocity error stays below
    ``(max_thrust / mass + g) · episode_time + WIND_ALLOWANCE``; the position
    error below ``max_position_error`` (the divergence limit, or
    ``hover_radius``) plus one step at that speed plus 1 m of sensor error
    (a divergence ends the episode after the step that crossed it); the body
    rates below ``MAX_BODY_RATE``."""
    speed = (engine.max_thrust / engine.mass + 9.81) * engine.episode_time + WIND_ALLOWANCE
    position = engine.max_position_error + speed * engine.step_time + 1.0
    high = np.array([position] * 3 + [speed] * 3 + [1.0] * 9 + [MAX_BODY_RATE] * 3, dtype=np.float32)
    obs = spaces.Box(low=-high, high=high, dtype=np.float32)
    act = spaces.Box(low=-1.0, high=1.0, shape=(4,), dtype=np.float32)
    return cast("spaces.Space[ObsArray]", obs), cast("spaces.Space[ActArray]", act)


def _draw_seed(rng: np.random.Generator) -> int:
    return int(rng.integers(0, _SEED_BOUND, dtype=np.uint64))


class FtsmcEnv(gym.Env[ObsArray, ActArray]):
    """One quadrotor flight of a scenario as a Gymnasium environment.

    scenario: a :class:`ftsmc.Scenario`, a built-in name or a file path
        (default ``realistic-breeze-1``).
    task: ``"hover"`` (hold ``target``, m, world frame z up, yaw 0, starting
        there at rest) or ``"track"`` (the scenario's reference and initial state).
    action: ``"ctbr"``: ``a = (thrust, p, q, r)`` in [-1, 1]; thrust
        ``(a0 + 1)/2 · max_thrust`` N, body rates ``a1..3 · max_rate`` rad/s
        (default (7, 7, 3)) held by the body-rate loop ``u = J k (Ω_cmd − Ω)``
        with ``k = rate_gain`` 1/s (default 20) at the control rate.
        ``"motors"``: the four rotor speeds, ``ω_min + (a_i + 1)/2 (ω_max − ω_min)``.
        Either goes through the scenario's actuator stage (limits, lag, mixer).
    observe: ``"sensors"`` (the scenario's measurement, what a controller would
        see) or ``"truth"``; 18 float32: position error (m), velocity error
        (m/s), the rows of the body-to-world rotation, body rates (rad/s).
    agent_rate: environment steps per second (Hz); it must divide the
        scenario's control rate (the action is held over the periods between).
    max_episode_time: episode length, s (default: the scenario's duration).
    reward: weights by name (``alive``, ``position``, ``velocity``, ``yaw``,
        ``rate``, ``action``, ``crash``; docs/python.md has the formula).
    randomize: draw the plant (and initial offsets) from the scenario's
        ``[montecarlo]`` at every reset.
    hover_radius: m (task ``"hover"`` only; default ``HOVER_RADIUS`` = 2):
        the episode is terminated once the true position is farther than
        this from the target along any axis.
    trajectory: task ``"track"`` only: an :class:`ftsmc.Trajectory` to
        track instead of the scenario's reference; the episode starts at
        rest on its first point (heading ψ there).
    time_scale: with ``trajectory``: ``"fixed"`` refuses (ValueError) one
        the vehicle's thrust or tilt cannot fly, ``"fit"`` slows it until
        it can (with a warning saying by how much).
    render_mode: ``None``, ``"rgb_array"`` or ``"human"`` (module docs).

    ``terminated`` on a crash (ground) or divergence (position error beyond
    ``hover_radius`` or ``simulation.max_position_error``, tilt,
    non-finite state), with ``info["reason"]`` (e.g. ``"crashed: hit the
    ground at 4.3 m/s at t = 0.478 s"``); ``truncated`` at the end of the episode (``"completed"``).
    ``info["time"]`` is the time into the episode (s), ``info["seed"]`` the
    episode's seed (its sensor noise and turbulence).
    """

    metadata: Dict[str, Any] = {"render_modes": RENDER_MODES, "render_fps": RENDER_FPS}

    def __init__(
        self,
        scenario: ScenarioLike = None,
        task: str = "hover",
        target: Optional[Sequence[float]] = None,
        action: str = "ctbr",
        observe: str = "sensors",
        agent_rate: float = 100.0,
        max_episode_time: Optional[float] = None,
        reward: Optional[Mapping[str, float]] = None,
        rate_gain: Optional[Sequence[float]] = None,
        max_rate: Optional[Sequence[float]] = None,
        randomize: bool = False,
        hover_radius: Optional[float] = None,
        trajectory: Optional[Trajectory] = None,
        time_scale: str = "fixed",
        render_mode: Optional[str] = None,
    ) -> None:
        if render_mode is not None and render_mode not in RENDER_MODES:
            raise ValueError(f"`render_mode` = {render_mode!r} is invalid (expected None, {', '.join(map(repr, RENDER_MODES))})")
        settings = _settings(
            task, target, action, observe, agent_rate, max_episode_time, reward, rate_gain, max_rate, randomize, hover_radius
        )
        flown = _flown(scenario, task, trajectory, time_scale)
        self._batch = _batch(flown, 1, settings)
        self._arm = _ftsmc.vehicle_arm_length(flown)
        self.observation_space, self.action_space = _spaces(self._batch)
        self._ended = True
        self._no_seed = np.zeros(1, dtype=np.uint64)
        self.render_mode = render_mode
        self._span = float(settings["hover_radius"] or HOVER_RADIUS)
        self._renderer: Optional[FrameRenderer] = None
        self._window: Optional[HumanWindow] = None
        self._time = 0.0

    @property
    def engine(self) -> _ftsmc.GymBatch:
        """The Rust engine (scales: ``max_thrust``, ``rotor_speed_range``, ``mass``, ``max_rate``, ``step_time``)."""
        return self._batch

    def reset(self, *, seed: Optional[int] = None, options: Optional[Dict[str, Any]] = None) -> Tuple[ObsArray, Dict[str, Any]]:
        """Start an episode; its seed is drawn from ``np_random`` (seeded by ``seed``)."""
        super().reset(seed=seed)
        episode_seed = _draw_seed(self.np_random)
        obs, _, _, _, _, _, _ = self._batch.reset(np.array([episode_seed], dtype=np.uint64))
        self._ended = False
        self._time = 0.0
        if self.render_mode is not None:
            self._frames().clear_trail()
            self._frames().record(self._batch.pose(0)[0])
        if self.render_mode == "human":
            self.render()
        return obs[0], {"time": 0.0, "seed": episode_seed}

    def step(self, action: ActArray) -> Tuple[ObsArray, SupportsFloat, bool, bool, Dict[str, Any]]:
        """Fly one environment step with ``action`` held."""
        if self._ended:
            raise RuntimeError("step() called before reset() or after the episode ended: call reset() first")
        a = np.asarray(action, dtype=np.float64).reshape(1, 4)
        obs, reward, terminated, truncated, reason, time, _ = self._batch.step(a, self._no_seed)
        info: Dict[str, Any] = {"time": float(time[0])}
        self._time = float(time[0])
        if self._renderer is not None:
            self._renderer.record(self._batch.pose(0)[0])
        if terminated[0] or truncated[0]:
            info["reason"] = reason[0]
            self._ended = True
        if self.render_mode == "human":
            self.render()
        return obs[0], float(reward[0]), bool(terminated[0]), bool(truncated[0]), info

    def render(self) -> Optional[AnyArray]:
        """The current frame (``render_mode="rgb_array"``: ``RENDER_SHAPE``
        uint8), or show it (``"human"``); ``None`` without a render mode."""
        if self.render_mode is None:
            return None
        position, attitude, target = self._batch.pose(0)
        frame: AnyArray = self._frames().draw(position, attitude, target, self._time)
        if self.render_mode == "rgb_array":
            return frame
        if self._window is None:
            self._window = HumanWindow(self.metadata["render_fps"])
        self._window.show(frame)
        return None

    def _frames(self) -> FrameRenderer:
        if self._renderer is None:
            self._renderer = FrameRenderer(RENDER_SHAPE[0], RENDER_SHAPE[1], span=self._span, arm=self._arm)
        return self._renderer

    def close(self) -> None:
        """Close the render window, if any."""
        if self._window is not None:
            self._window.close()
            self._window = None


class FtsmcVectorEnv(VectorEnv[ObsArray, ActArray, AnyArray]):
    """``num_envs`` flights of one scenario stepped in Rust in one call (GIL released).

    Same keywords as :class:`FtsmcEnv`, and ``max_episode_steps`` (what
    ``gym.make_vec`` passes from the registration): episodes are truncated
    at ``min(max_episode_time, max_episode_steps / agent_rate)``. Auto-reset is Gymnasium's
    ``NEXT_STEP``: an environment whose episode ended at one step is reset
    at the next, which ignores its action and returns its first observation
    with reward 0, ``terminated`` and ``truncated`` False. Seeds follow
    ``SyncVectorEnv``: ``reset(seed=s)`` seeds environment ``i`` with ``s + i``
    (or a list, one per environment), and every episode's seed is drawn from
    that environment's own generator, so environment ``i`` flies exactly the
    episodes of ``FtsmcEnv`` reset with seed ``s + i`` and then without a seed.
    ``infos`` holds ``time`` (s) and, where an episode ended, ``reason`` (with
    the mask ``_reason``).
    """

    metadata: Dict[str, Any] = {"render_modes": [], "autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(
        self,
        num_envs: int = 1,
        scenario: ScenarioLike = None,
        task: str = "hover",
        target: Optional[Sequence[float]] = None,
        action: str = "ctbr",
        observe: str = "sensors",
        agent_rate: float = 100.0,
        max_episode_time: Optional[float] = None,
        reward: Optional[Mapping[str, float]] = None,
        rate_gain: Optional[Sequence[float]] = None,
        max_rate: Optional[Sequence[float]] = None,
        randomize: bool = False,
        hover_radius: Optional[float] = None,
        max_episode_steps: Optional[int] = None,
        trajectory: Optional[Trajectory] = None,
        time_scale: str = "fixed",
    ) -> None:
        if int(num_envs) < 1:
            raise ValueError(f"`num_envs` = {num_envs} is invalid (expected at least 1 environment)")
        if max_episode_steps is not None:
            # Gymnasium's make_vec passes the registration's TimeLimit: the
            # episodes end at whichever comes first.
            if int(max_episode_steps) < 1:
                raise ValueError(f"`max_episode_steps` = {max_episode_steps} is invalid (expected at least 1)")
            by_steps = int(max_episode_steps) / float(agent_rate)
            max_episode_time = by_steps if max_episode_time is None else min(float(max_episode_time), by_steps)
        settings = _settings(
            task, target, action, observe, agent_rate, max_episode_time, reward, rate_gain, max_rate, randomize, hover_radius
        )
        self.num_envs = int(num_envs)
        self._batch = _batch(_flown(scenario, task, trajectory, time_scale), self.num_envs, settings)
        self.single_observation_space, self.single_action_space = _spaces(self._batch)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._rngs: List[np.random.Generator] = [seeding.np_random(None)[0] for _ in range(self.num_envs)]
        self._started = False

    @property
    def engine(self) -> _ftsmc.GymBatch:
        """The Rust engine (see :attr:`FtsmcEnv.engine`)."""
        return self._batch

    def reset(
        self, *, seed: Optional[Union[int, Sequence[Optional[int]]]] = None, options: Optional[Dict[str, Any]] = None
    ) -> Tuple[ObsArray, Dict[str, Any]]:
        """Start an episode in every environment (seeds as in the class docs)."""
        if seed is None:
            seeds: List[Optional[int]] = [None] * self.num_envs
        elif isinstance(seed, (int, np.integer)):
            super().reset(seed=int(seed))
            seeds = [int(seed) + i for i in range(self.num_envs)]
        else:
            seeds = [None if s is None else int(s) for s in seed]
            if len(seeds) != self.num_envs:
                raise ValueError(f"{len(seeds)} seeds for {self.num_envs} environments")
        for i, s in enumerate(seeds):
            if s is not None or not self._started:
                self._rngs[i] = seeding.np_random(s)[0]
        self._started = True
        episode = np.array([_draw_seed(r) for r in self._rngs], dtype=np.uint64)
        obs, _, _, _, _, time, _ = self._batch.reset(episode)
        return obs, {"time": time}

    def step(self, actions: ActArray) -> Tuple[ObsArray, AnyArray, AnyArray, AnyArray, Dict[str, Any]]:
        """One step of every environment (next-step auto-reset)."""
        if not self._started:
            raise RuntimeError("step() called before reset(): call reset() first")
        a = np.ascontiguousarray(actions, dtype=np.float64).reshape(self.num_envs, 4)
        seeds = np.zeros(self.num_envs, dtype=np.uint64)
        for i in np.flatnonzero(self._batch.done()):
            seeds[i] = _draw_seed(self._rngs[i])
        obs, reward, terminated, truncated, reason, time, _ = self._batch.step(a, seeds)
        infos: Dict[str, Any] = {"time": time}
        ended = terminated | truncated
        if ended.any():
            infos["reason"] = np.array(reason, dtype=object)
            infos["_reason"] = ended
        return obs, reward, terminated, truncated, infos


def _register() -> None:
    kwargs: Dict[str, Tuple[Dict[str, Any], int]] = {
        "ftsmc/Hover-v0": ({"task": "hover", "action": "ctbr", "max_episode_time": 10.0}, 1000),
        "ftsmc/HoverMotors-v0": ({"task": "hover", "action": "motors", "max_episode_time": 10.0}, 1000),
        "ftsmc/Track-v0": ({"task": "track", "action": "ctbr"}, 2000),
    }
    for env_id, (kw, steps) in kwargs.items():
        if env_id not in gym.registry:
            gym.register(
                id=env_id,
                entry_point="ftsmc.gym:FtsmcEnv",
                vector_entry_point="ftsmc.gym:FtsmcVectorEnv",
                kwargs=kw,
                max_episode_steps=steps,
            )


_register()
