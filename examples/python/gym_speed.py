"""Environment steps per second of ftsmc's Gymnasium environments (the single
``FtsmcEnv`` and ``FtsmcVectorEnv`` at N = 1, 64, 1024), and of RotorPy's
batched ``QuadrotorEnv`` (rotorpy.learning.quadrotor_environments) at the
same N, measured in alternation so that both see the same machine load.

    python examples/python/gym_speed.py                     # ftsmc only
    python examples/python/gym_speed.py --rotorpy-python /path/to/python   # beside RotorPy

Both fly 100 Hz environment steps with random collective-thrust/body-rate
actions (RotorPy's ``cmd_ctbr``); ftsmc flies ``ftsmc/Hover-v0`` on
``realistic-breeze-1`` (1 kHz control, rigid body, motors, sensors,
Dryden turbulence, ground: 10 control periods per environment step),
RotorPy its Crazyflie at ``sim_rate = 100`` (one RK4 step per environment
step, no wind). RotorPy runs in the interpreter given (it needs torch and
stable-baselines3, which ftsmc does not depend on).
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
from typing import Any, Dict, List

import numpy as np


def ftsmc_rate(n: int, steps: int, single: bool) -> float:
    import gymnasium as gym

    import ftsmc.gym  # noqa: F401

    rng = np.random.default_rng(0)
    if single:
        env = gym.make("ftsmc/Hover-v0", max_episode_time=100.0)
        env.reset(seed=0)
        actions = rng.uniform(-0.1, 0.1, (steps, 4)).astype(np.float32)
        t0 = time.perf_counter()
        for k in range(steps):
            _, _, terminated, truncated, _ = env.step(actions[k])
            if terminated or truncated:
                env.reset()
        return steps / (time.perf_counter() - t0)
    venv = gym.make_vec("ftsmc/Hover-v0", num_envs=n, vectorization_mode="vector_entry_point", max_episode_time=100.0)
    venv.reset(seed=0)
    batch = rng.uniform(-0.1, 0.1, (n, 4)).astype(np.float32)
    t0 = time.perf_counter()
    for _ in range(steps):
        venv.step(batch)
    return n * steps / (time.perf_counter() - t0)


def rotorpy_rate(n: int, steps: int) -> float:
    import torch
    from rotorpy.learning.quadrotor_environments import QuadrotorEnv
    from rotorpy.vehicles.crazyflie_params import quad_params

    torch.set_num_threads(2)
    hover = float(np.sqrt(quad_params["mass"] * 9.81 / (4 * quad_params["k_eta"])))
    init = {
        "x": np.zeros((n, 3)),
        "v": np.zeros((n, 3)),
        "q": np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)),
        "w": np.zeros((n, 3)),
        "wind": np.zeros((n, 3)),
        "rotor_speeds": np.full((n, 4), hover),
    }
    init_t = {k: torch.from_numpy(v).double() for k, v in init.items()}
    env = QuadrotorEnv(n, init_t, control_mode="cmd_ctbr", quad_params=quad_params, max_time=100, sim_rate=100)
    env.reset()
    batch = np.random.default_rng(0).uniform(-0.1, 0.1, (n, 4))
    t0 = time.perf_counter()
    for _ in range(steps):
        env.step(batch)
    return n * steps / (time.perf_counter() - t0)


def one(args: argparse.Namespace) -> None:
    if args.impl == "rotorpy":
        rate = rotorpy_rate(args.n, args.steps)
    else:
        rate = ftsmc_rate(args.n, args.steps, args.impl == "ftsmc-single")
    print(json.dumps({"impl": args.impl, "n": args.n, "steps_per_s": rate}))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rotorpy-python", help="interpreter with rotorpy, torch and stable-baselines3")
    parser.add_argument("--rounds", type=int, default=3, help="alternating rounds (the median is reported)")
    parser.add_argument("--impl", choices=["ftsmc-single", "ftsmc-vector", "rotorpy"], help=argparse.SUPPRESS)
    parser.add_argument("--n", type=int, default=1, help=argparse.SUPPRESS)
    parser.add_argument("--steps", type=int, default=1000, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.impl:
        one(args)
        return
    # Environment steps per measurement: about a second of work each.
    plan = [("ftsmc-single", 1, 5000), ("ftsmc-vector", 1, 5000), ("ftsmc-vector", 64, 300), ("ftsmc-vector", 1024, 30)]
    if args.rotorpy_python:
        plan += [("rotorpy", 1, 300), ("rotorpy", 64, 100), ("rotorpy", 1024, 20)]
    rates: Dict[str, List[float]] = {}
    for _ in range(args.rounds):
        for impl, n, steps in plan:
            python = args.rotorpy_python if impl == "rotorpy" else sys.executable
            cmd = [str(python), __file__, "--impl", impl, "--n", str(n), "--steps", str(steps)]
            out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout.strip().splitlines()[-1]
            result: Dict[str, Any] = json.loads(out)
            rates.setdefault(f"{impl} N={n}", []).append(float(result["steps_per_s"]))
    medians = {k: statistics.median(v) for k, v in rates.items()}
    print(f"{'environment':<22} {'env steps/s (median)':>22}  {'vs RotorPy':>10}   all rounds")
    for key, value in medians.items():
        size = key.split("N=")[1]
        ref = medians.get(f"rotorpy N={size}")
        ratio = f"{value / ref:9.0f}x" if ref and not key.startswith("rotorpy") else ""
        print(f"{key:<22} {value:22,.0f}  {ratio:>10}   {', '.join(f'{r:,.0f}' for r in rates[key])}")


if __name__ == "__main__":
    main()
