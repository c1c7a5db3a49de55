"""Gymnasium environments of ftsmc, stepped in Rust (docs/python.md, "Gymnasium environments").

``import ftsmc.gym`` registers:

- ``ftsmc/Hover-v0``: hold a point (default 1 m above the origin) from rest
  there; collective thrust and body rates (``action="ctbr"``); 10 s episodes.
- ``ftsmc/HoverMotors-v0``: the same with the four rotor speeds as the action
  (``action="motors"``).
- ``ftsmc/Track-v0``: track the scenario's own reference from its initial
  state; collective thrust and body rates; the scenario's duration.

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

__all__ = ["FtsmcEnv", "FtsmcVectorEnv", "OBSERVATION_NAMES", "DEFAULT_SCENARIO", "ENV_IDS"]

ObsArray = npt.NDArray[np.float32]
ActArray = npt.NDArray[np.float32]
AnyArray = npt.NDArray[Any]

DEFAULT_SCENARIO = "realistic-breeze-1"
"""The scenario flown when none is given."""

OBSERVATION_NAMES: List[str] = list(_ftsmc.GymBatch.observation_names())
"""The 18 observation entries: position error (m), velocity error (m/s), rows of R, body rates (rad/s)."""

ENV_IDS = ("ftsmc/Hover-v0", "ftsmc/HoverMotors-v0", "ftsmc/Track-v0")
"""The registered environment ids."""

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


def _batch(scenario: ScenarioLike, num_envs: int, settings: Mapping[str, Any]) -> _ftsmc.GymBatch:
    s = _scenario(scenario)
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
) -> Dict[str, Any]:
    return {
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


def _spaces() -> Tuple[spaces.Space[ObsArray], spaces.Space[ActArray]]:
    obs = spaces.Box(low=-np.inf, high=np.inf, shape=(len(OBSERVATION_NAMES),), dtype=np.float32)
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

    ``terminated`` on a crash (ground) or divergence (position error, tilt,
    non-finite state), with ``info["reason"]`` (e.g. ``"crashed: hit the
    ground at 4.3 m/s at t = 0.478 s"``); ``truncated`` at the end of the episode (``"completed"``).
    ``info["time"]`` is the time into the episode (s), ``info["seed"]`` the
    episode's seed (its sensor noise and turbulence).
    """

    metadata: Dict[str, Any] = {"render_modes": []}

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
    ) -> None:
        settings = _settings(task, target, action, observe, agent_rate, max_episode_time, reward, rate_gain, max_rate, randomize)
        self._batch = _batch(scenario, 1, settings)
        self.observation_space, self.action_space = _spaces()
        self._ended = True
        self._no_seed = np.zeros(1, dtype=np.uint64)

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
        return obs[0], {"time": 0.0, "seed": episode_seed}

    def step(self, action: ActArray) -> Tuple[ObsArray, SupportsFloat, bool, bool, Dict[str, Any]]:
        """Fly one environment step with ``action`` held."""
        if self._ended:
            raise RuntimeError("step() called before reset() or after the episode ended: call reset() first")
        a = np.asarray(action, dtype=np.float64).reshape(1, 4)
        obs, reward, terminated, truncated, reason, time, _ = self._batch.step(a, self._no_seed)
        info: Dict[str, Any] = {"time": float(time[0])}
        if terminated[0] or truncated[0]:
            info["reason"] = reason[0]
            self._ended = True
        return obs[0], float(reward[0]), bool(terminated[0]), bool(truncated[0]), info


class FtsmcVectorEnv(VectorEnv[ObsArray, ActArray, AnyArray]):
    """``num_envs`` flights of one scenario stepped in Rust in one call (GIL released).

    Same keywords as :class:`FtsmcEnv`. Auto-reset is Gymnasium's
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
    ) -> None:
        if int(num_envs) < 1:
            raise ValueError(f"`num_envs` = {num_envs} is invalid (expected at least 1 environment)")
        settings = _settings(task, target, action, observe, agent_rate, max_episode_time, reward, rate_gain, max_rate, randomize)
        self.num_envs = int(num_envs)
        self._batch = _batch(scenario, self.num_envs, settings)
        self.single_observation_space, self.single_action_space = _spaces()
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
    kwargs: Dict[str, Dict[str, Any]] = {
        "ftsmc/Hover-v0": {"task": "hover", "action": "ctbr", "max_episode_time": 10.0},
        "ftsmc/HoverMotors-v0": {"task": "hover", "action": "motors", "max_episode_time": 10.0},
        "ftsmc/Track-v0": {"task": "track", "action": "ctbr"},
    }
    for env_id, kw in kwargs.items():
        if env_id not in gym.registry:
            gym.register(
                id=env_id, entry_point="ftsmc.gym:FtsmcEnv", vector_entry_point="ftsmc.gym:FtsmcVectorEnv", kwargs=kw
            )


_register()
