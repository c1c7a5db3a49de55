"""Learn to hover in ``ftsmc/Hover-v0`` with the cross-entropy method (CEM),
numpy only, and plot its reward curve.

    python examples/python/train_hover.py [--iterations 30] [--population 48] [--out DIR]

Why CEM and not a deep-RL library: PPO or SAC (stable-baselines3) need
PyTorch, a download of several hundred MB that CI on a CPU machine should
not carry; CEM (Rubinstein 1999; as a policy search, Szita & Lőrincz 2006)
is the minimal baseline that still learns from the reward alone. Gymnasium
environments are the same for either: swap in any library's agent.

The policy is linear in the observation, ``a = clip(W f + b, -1, 1)``, on
the features ``f`` = position error (3), velocity error (3), the rows of R
that carry roll, pitch and yaw (r31, r32, r21) and the body rates (3), so
``W`` is 4 × 12 (48 numbers) plus the bias ``b`` (4). CEM keeps a Gaussian
over those 52 numbers: each iteration draws ``population`` policies, flies
each for one episode (all in one vectorised call, ``FtsmcVectorEnv``), and
refits the mean and standard deviation to the best ``elite`` share. The
thrust bias starts at hover thrust (``2 m g / max_thrust − 1``, from the
engine's scales), everything else at zero.

Prints the mean and best return per iteration, the return on held-out
seeds of the final mean policy and of the starting one (hover thrust, no
feedback: the wind carries it away), and writes ``train-hover-reward.png``.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import List, Tuple

import numpy as np
import numpy.typing as npt

from ftsmc.gym import FtsmcVectorEnv

F64 = npt.NDArray[np.float64]

FEATURES = [0, 1, 2, 3, 4, 5, 12, 13, 9, 15, 16, 17]
"""Observation entries the policy reads: ex ey ez, evx evy evz, r31 r32 r21, p q r."""


def act(params: F64, obs: npt.NDArray[np.float32]) -> npt.NDArray[np.float32]:
    """Actions of a batch of policies (``params``: N × 52) on their observations (N × 18)."""
    n = params.shape[0]
    w = params[:, : 4 * len(FEATURES)].reshape(n, 4, len(FEATURES))
    b = params[:, 4 * len(FEATURES) :]
    f = obs[:, FEATURES].astype(np.float64)
    a = np.einsum("nij,nj->ni", w, f) + b
    out: npt.NDArray[np.float32] = np.clip(a, -1.0, 1.0).astype(np.float32)
    return out


def episode_returns(env: FtsmcVectorEnv, params: F64, seed: int, steps: int) -> F64:
    """One episode per row of ``params`` (env ``i`` flies policy ``i``), seeds ``seed + i``."""
    obs, _ = env.reset(seed=seed)
    total = np.zeros(params.shape[0])
    alive = np.ones(params.shape[0], dtype=bool)
    for _ in range(steps):
        obs, reward, terminated, truncated, _ = env.step(act(params, obs))
        total += np.where(alive, reward, 0.0)
        alive &= ~(terminated | truncated)
        if not alive.any():
            break
    return total


def train(
    iterations: int, population: int, elite: float, episode_time: float, seed: int
) -> Tuple[F64, F64, List[Tuple[float, float]], FtsmcVectorEnv]:
    env = FtsmcVectorEnv(num_envs=population, task="hover", max_episode_time=episode_time)
    steps = int(round(episode_time / env.engine.step_time))
    dim = 4 * len(FEATURES) + 4
    mean = np.zeros(dim)
    mean[4 * len(FEATURES)] = 2.0 * env.engine.mass * 9.81 / env.engine.max_thrust - 1.0
    start = mean.copy()
    std = np.full(dim, 0.3)
    rng = np.random.default_rng(seed)
    n_elite = max(2, int(round(elite * population)))
    curve: List[Tuple[float, float]] = []
    for k in range(iterations):
        params = mean + std * rng.standard_normal((population, dim))
        returns = episode_returns(env, params, seed=seed + 1000 * k, steps=steps)
        best = np.argsort(returns)[-n_elite:]
        mean = params[best].mean(axis=0)
        std = params[best].std(axis=0) + 0.02 * (1.0 - k / max(1, iterations))  # a little noise early on
        curve.append((float(returns.mean()), float(returns.max())))
        print(f"iteration {k + 1:3d}: mean return {returns.mean():9.1f}, best {returns.max():8.1f}", flush=True)
    return start, mean, curve, env


def plot(curve: List[Tuple[float, float]], final: float, before: float, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    it = np.arange(1, len(curve) + 1)
    fig, ax = plt.subplots(figsize=(6, 3.6), layout="constrained")
    ax.plot(it, [c[0] for c in curve], marker="o", ms=3, label="population mean")
    ax.plot(it, [c[1] for c in curve], marker="o", ms=3, label="best of population")
    ax.axhline(final, color="k", ls="--", lw=1, label=f"final mean policy, held-out seeds ({final:.0f})")
    ax.axhline(before, color="#d62728", ls=":", lw=1, label=f"starting policy, held-out seeds ({before:.0f})")
    ax.set_xlabel("CEM iteration")
    ax.set_ylabel("episode return")
    ax.set_title("ftsmc/Hover-v0: CEM on a linear policy")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="lower right")
    fig.savefig(path, dpi=110)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--iterations", type=int, default=30)
    p.add_argument("--population", type=int, default=48)
    p.add_argument("--elite", type=float, default=0.2, help="share of the population refitted to")
    p.add_argument("--episode-time", type=float, default=4.0, help="s per training episode")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", type=Path, default=Path("."))
    args = p.parse_args()
    start, mean, curve, env = train(args.iterations, args.population, args.elite, args.episode_time, args.seed)
    steps = int(round(args.episode_time / env.engine.step_time))
    held_out = 10**6  # seeds never used in training
    final = float(episode_returns(env, np.tile(mean, (env.num_envs, 1)), held_out, steps).mean())
    before = float(episode_returns(env, np.tile(start, (env.num_envs, 1)), held_out, steps).mean())
    print(f"final mean policy on held-out seeds: mean return {final:.1f} (starting policy: {before:.1f})")
    args.out.mkdir(parents=True, exist_ok=True)
    plot(curve, final, before, args.out / "train-hover-reward.png")
    print(f"wrote {args.out / 'train-hover-reward.png'}")


if __name__ == "__main__":
    main()
