"""ftsmc.gym: every registered environment passes Gymnasium's checker; a seed
gives the same episode bits; the vectorised environment's lane i flies the
single environment's episodes for seed s + i, with next-step auto-reset;
crashes terminate with a reason; bad settings are refused by name."""

from __future__ import annotations

import warnings
from typing import Any, List, Optional, Tuple

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

import ftsmc  # noqa: E402
from ftsmc.gym import ENV_IDS, RENDER_MODES, RENDER_SHAPE, FtsmcEnv, FtsmcVectorEnv  # noqa: E402
from gymnasium.utils.env_checker import check_env  # noqa: E402

# Short episodes keep the suite fast.
SHORT = {"max_episode_time": 0.3}


@pytest.mark.parametrize("render_mode", [None, *RENDER_MODES])
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_check_env_without_warnings(env_id: str, render_mode: Optional[str]) -> None:
    env = gym.make(env_id, render_mode=render_mode, **SHORT)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped)
    assert [str(w.message) for w in caught] == []
    assert env.observation_space.shape == (18,) and env.action_space.shape == (4,)
    assert env.spec is not None and env.spec.max_episode_steps in (1000, 2000)
    assert env.metadata["render_modes"] == ["rgb_array", "human"] and env.metadata["render_fps"] > 0
    env.close()


def test_rgb_array_frames_show_the_vehicle_and_its_target() -> None:
    env = gym.make("ftsmc/Hover-v0", render_mode="rgb_array", **SHORT)
    env.reset(seed=0)
    first = env.render()
    assert first.shape == RENDER_SHAPE and first.dtype == np.uint8
    # The target's red ring and the vehicle's dark arms are drawn.
    red = (first[:, :, 0] > 180) & (first[:, :, 1] < 90) & (first[:, :, 2] < 90)
    dark = first.sum(axis=2) < 200
    assert red.sum() > 50 and dark.sum() > 50
    for _ in range(20):
        env.step(np.array([1.0, 0.5, 0.0, 0.0], dtype=np.float32))  # climb and roll
    later = env.render()
    assert later.shape == RENDER_SHAPE and (later != first).any()
    assert FtsmcEnv(max_episode_time=0.1).render() is None
    with pytest.raises(ValueError, match="render_mode"):
        FtsmcEnv(render_mode="video")


def test_hover_ends_outside_the_radius() -> None:
    env = FtsmcEnv(hover_radius=0.5, observe="truth")
    env.reset(seed=0)
    for _ in range(300):
        obs, reward, terminated, truncated, info = env.step(np.array([1.0, 0, 0, 0], dtype=np.float32))
        if terminated or truncated:
            break
    assert terminated and "position" in info["reason"], info
    assert 0.5 < obs[2] < 0.8 and info["time"] < 3.0  # just beyond 0.5 m above the target
    with pytest.raises(ValueError, match="hover_radius"):
        FtsmcEnv(task="track", hover_radius=1.0)
    with pytest.raises(ValueError, match="hover_radius"):
        FtsmcEnv(hover_radius=-1.0)


def rollout(env: Any, seed: int, steps: int) -> Tuple[np.ndarray, np.ndarray, List[Any]]:
    rng = np.random.default_rng(99)
    obs, _ = env.reset(seed=seed)
    observations, rewards, ends = [obs], [], []
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(rng.uniform(-0.2, 0.2, 4).astype(np.float32))
        observations.append(obs)
        rewards.append(reward)
        if terminated or truncated:
            ends.append(info["reason"])
            obs, _ = env.reset()
            observations.append(obs)
    return np.array(observations), np.array(rewards), ends


def test_same_seed_same_bits() -> None:
    env = gym.make("ftsmc/Hover-v0", **SHORT)
    a = rollout(env, 5, 80)
    b = rollout(env, 5, 80)
    assert a[0].tobytes() == b[0].tobytes() and a[1].tobytes() == b[1].tobytes()
    assert a[2] == b[2] and len(a[2]) >= 2  # episodes ended (and were reset) on the way
    c = rollout(env, 6, 80)
    assert a[0].tobytes() != c[0].tobytes()  # another seed: other noise and turbulence
    # The truth without sensor noise differs from the measurement.
    truth = rollout(gym.make("ftsmc/Hover-v0", observe="truth", **SHORT), 5, 5)
    assert truth[0][0, :3].tolist() == [0.0, 0.0, 0.0] and a[0][0, :3].tolist() != [0.0, 0.0, 0.0]


def test_vector_lanes_fly_the_single_env_episodes_with_next_step_autoreset() -> None:
    n, seed, steps = 3, 11, 70
    venv = gym.make_vec("ftsmc/Hover-v0", num_envs=n, vectorization_mode="vector_entry_point", **SHORT)
    assert isinstance(venv.unwrapped, FtsmcVectorEnv)
    assert venv.metadata["autoreset_mode"] == gym.vector.AutoresetMode.NEXT_STEP
    rng = np.random.default_rng(3)
    actions = rng.uniform(-0.2, 0.2, (steps, n, 4)).astype(np.float32)
    obs, _ = venv.reset(seed=seed)
    vec_obs, vec_rew, vec_term, vec_trunc = [obs], [], [], []
    for k in range(steps):
        obs, rew, term, trunc, info = venv.step(actions[k])
        vec_obs.append(obs), vec_rew.append(rew), vec_term.append(term), vec_trunc.append(trunc)
    ended = np.array(vec_trunc) | np.array(vec_term)
    assert ended[29].all(), "0.3 s at 100 Hz: step 30 ends every episode"
    # NEXT_STEP: the step after the end resets: first observation, reward 0, not done.
    assert (np.array(vec_rew)[30] == 0).all() and not ended[30].any()
    for i in range(n):
        env = gym.make("ftsmc/Hover-v0", **SHORT)
        o, _ = env.reset(seed=seed + i)
        assert o.tobytes() == vec_obs[0][i].tobytes()
        done = False
        for k in range(steps):
            if done:
                o, _ = env.reset()
                r, done = 0.0, False
            else:
                o, r, t, tr, _ = env.step(actions[k, i])
                done = t or tr
                assert (t, tr) == (vec_term[k][i], vec_trunc[k][i])
            assert o.tobytes() == vec_obs[k + 1][i].tobytes(), (i, k)
            assert r == vec_rew[k][i]


def test_crash_terminates_with_reason() -> None:
    env = gym.make("ftsmc/Hover-v0")
    env.reset(seed=0)
    for k in range(200):
        obs, reward, terminated, truncated, info = env.step(np.array([-1, 0, 0, 0], dtype=np.float32))
        if terminated:
            break
    assert terminated and not truncated and info["reason"].startswith("crashed: hit the ground"), info
    assert reward < -5  # the crash penalty (10 by default)
    with pytest.raises(RuntimeError, match="reset"):
        env.step(np.zeros(4, dtype=np.float32))


def test_track_and_motors_fly_their_scenario() -> None:
    env = FtsmcEnv(scenario="paper-scenario-1", task="track", observe="truth", max_episode_time=0.05)
    obs, _ = env.reset(seed=1)
    assert env.engine.step_time == pytest.approx(0.01)
    motors = FtsmcEnv(action="motors", observe="truth", max_episode_time=0.2)
    lo, hi = motors.engine.rotor_speed_range
    assert (lo, hi) == (0.0, 838.0)  # realistic-breeze-1's [actuators]
    obs, _ = motors.reset(seed=1)
    for _ in range(20):
        obs, *_ = motors.step(np.ones(4, dtype=np.float32))
    assert obs[2] > 0.3  # full rotor speed climbs


def test_weights_change_the_reward() -> None:
    base = rollout(gym.make("ftsmc/Hover-v0", **SHORT), 2, 5)[1]
    alive = rollout(gym.make("ftsmc/Hover-v0", reward={"alive": 3.0}, **SHORT), 2, 5)[1]
    np.testing.assert_allclose(alive - base, 2.0)


@pytest.mark.parametrize(
    "kwargs, words",
    [
        ({"agent_rate": 300.0}, ["agent_rate", "300"]),
        ({"reward": {"speed": 1.0}}, ["speed", "alive"]),
        ({"reward": {"position": -1.0}}, ["reward.position", "-1"]),
        ({"action": "torques"}, ["action", "torques"]),
        ({"max_episode_time": 0.0}, ["max_episode_time", "0"]),
        # randomize needs the scenario's [montecarlo] draws: paper scenario 1 has none.
        ({"randomize": True, "scenario": "paper-scenario-1"}, ["montecarlo"]),
        ({"scenario": "no-such-scenario"}, ["no-such-scenario"]),
    ],
)
def test_bad_settings_are_refused_by_name(kwargs: dict, words: List[str]) -> None:
    with pytest.raises((ValueError, OSError)) as err:
        FtsmcEnv(**kwargs)
    assert all(w in str(err.value) for w in words), str(err.value)


def test_randomize_draws_the_plant_per_seed() -> None:
    scenario = ftsmc.Scenario.builtin("realistic-scenario-2")
    assert scenario.has_montecarlo
    env = FtsmcEnv(scenario=scenario, task="track", randomize=True, observe="truth", max_episode_time=0.5)
    first = rollout(env, 1, 30)[0]
    again = rollout(env, 1, 30)[0]
    other = rollout(env, 2, 30)[0]
    assert first.tobytes() == again.tobytes() and first.tobytes() != other.tobytes()
