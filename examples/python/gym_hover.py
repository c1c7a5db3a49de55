"""ftsmc's Gymnasium hover environment flown by a random policy and by a
scripted PD baseline (no training), then the PD on 64 environments in one
vectorised call.

    python examples/python/gym_hover.py [--episodes 3] [--seed 0]

The PD reads only the observation (position and velocity error, the rows of
the body-to-world rotation R, body rates) and commands collective thrust and
body rates in [-1, 1], as an agent would (docs/python.md, "Gymnasium
environments").
"""

from __future__ import annotations

import argparse
import math
from typing import List, Tuple

import gymnasium as gym
import numpy as np
import numpy.typing as npt

import ftsmc.gym  # noqa: F401  (registers ftsmc/Hover-v0, ftsmc/HoverMotors-v0, ftsmc/Track-v0)
from ftsmc.gym import FtsmcEnv, FtsmcVectorEnv

F32 = npt.NDArray[np.float32]


class HoverPD:
    """Position PD → desired acceleration → thrust and small-angle tilt
    demand → proportional body-rate demand, normalised to the action box."""

    def __init__(self, mass: float, max_thrust: float, max_rate: List[float], gravity: float = 9.81) -> None:
        self.mass, self.max_thrust, self.max_rate, self.g = mass, max_thrust, max_rate, gravity
        self.kp, self.kd, self.kp_z, self.kd_z, self.k_att = 4.0, 3.5, 6.0, 4.0, 12.0

    def __call__(self, obs: npt.NDArray[np.floating]) -> F32:
        o = np.atleast_2d(np.asarray(obs, dtype=np.float64))
        e, ev = o[:, 0:3], o[:, 3:6]
        r11, r21, r31, r32, r33 = o[:, 6], o[:, 9], o[:, 12], o[:, 13], o[:, 14]
        phi, theta, psi = np.arctan2(r32, r33), -np.arcsin(np.clip(r31, -1, 1)), np.arctan2(r21, r11)
        ax = -self.kp * e[:, 0] - self.kd * ev[:, 0]
        ay = -self.kp * e[:, 1] - self.kd * ev[:, 1]
        az = -self.kp_z * e[:, 2] - self.kd_z * ev[:, 2]
        thrust = self.mass * (self.g + az) / np.maximum(r33, 0.5)
        theta_d = (ax * np.cos(psi) + ay * np.sin(psi)) / self.g
        phi_d = (ax * np.sin(psi) - ay * np.cos(psi)) / self.g
        a = np.stack(
            [
                2.0 * thrust / self.max_thrust - 1.0,
                self.k_att * (phi_d - phi) / self.max_rate[0],
                self.k_att * (theta_d - theta) / self.max_rate[1],
                -2.0 * psi / self.max_rate[2],
            ],
            axis=1,
        )
        out: F32 = np.clip(a, -1.0, 1.0).astype(np.float32)
        return out


def episode(env: gym.Env[F32, F32], policy: str, pd: HoverPD, seed: int) -> Tuple[float, int, str, float]:
    """Return, steps, how it ended, worst position error after 2 s (m)."""
    obs, info = env.reset(seed=seed)
    total, steps, worst = 0.0, 0, 0.0
    while True:
        action = env.action_space.sample() if policy == "random" else pd(obs)[0]
        obs, reward, terminated, truncated, info = env.step(action)
        total += float(reward)
        steps += 1
        if info["time"] > 2.0:
            worst = max(worst, float(np.linalg.norm(obs[:3])))
        if terminated or truncated:
            return total, steps, str(info["reason"]), worst


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--episodes", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    env = gym.make("ftsmc/Hover-v0")
    env.action_space.seed(args.seed)
    raw = env.unwrapped
    assert isinstance(raw, FtsmcEnv)
    engine = raw.engine
    pd = HoverPD(engine.mass, engine.max_thrust, list(engine.max_rate))
    print(f"ftsmc/Hover-v0: {engine.episode_time:g} s episodes, {1 / engine.step_time:g} Hz agent, max thrust {engine.max_thrust:.1f} N")
    for policy in ("random", "pd"):
        for k in range(args.episodes):
            total, steps, reason, worst = episode(env, policy, pd, args.seed + k)
            extra = f", worst error after 2 s {worst:.3f} m" if not math.isnan(worst) and steps > 200 else ""
            print(f"{policy:>6} episode {k}: return {total:8.2f} over {steps:4d} steps, {reason}{extra}")
    env.close()

    venv = gym.make_vec("ftsmc/Hover-v0", num_envs=64, vectorization_mode="vector_entry_point")
    assert isinstance(venv.unwrapped, FtsmcVectorEnv)
    obs, _ = venv.reset(seed=args.seed)
    returns = np.zeros(64)
    for _ in range(1000):  # one 10 s episode per environment
        obs, reward, terminated, truncated, _ = venv.step(pd(obs))
        returns += reward
        if (terminated | truncated).all():
            break
    print(f"pd on 64 vectorised environments: mean return {returns.mean():.2f}, {int(terminated.sum())} terminated")
    venv.close()


if __name__ == "__main__":
    main()
