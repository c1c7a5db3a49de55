"""FTAFTSMC (and, for comparison, TSM-STA) flying RotorPy's Hummingbird
through a hover in gusting wind followed by a step.

    pip install rotorpy
    python examples/python/rotorpy_ftaftsmc.py [--controllers ftaftsmc,tsm-sta] [--out DIR]

The controller's nominal model ([plant]) is built from RotorPy's vehicle
parameters (ftsmc.rotorpy.plant_from_rotorpy); the gains are the paper's
(paper-scenario-1). RotorPy flies its own rigid body with motor lag, rotor
drag and frame drag, commanded by collective thrust and body moments
(control_abstraction="cmd_ctbm"). Wind: RotorPy's SinusoidWind (its
Dryden model needs torch).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any, Dict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from rotorpy.environments import Environment
from rotorpy.vehicles.hummingbird_params import quad_params
from rotorpy.vehicles.multirotor import Multirotor
from rotorpy.wind.default_winds import SinusoidWind

import ftsmc
import ftsmc.rotorpy


class HoverThenStep:
    """RotorPy trajectory: hover at the origin, then a step to `target` at `t_step`."""

    def __init__(self, target: np.ndarray, t_step: float) -> None:
        self.target, self.t_step = target, t_step

    def update(self, t: float) -> Dict[str, Any]:
        x = self.target if t >= self.t_step else np.zeros(3)
        zero = np.zeros(3)
        return {"x": x, "x_dot": zero, "x_ddot": zero, "x_dddot": zero, "x_ddddot": zero, "yaw": 0.0, "yaw_dot": 0.0, "yaw_ddot": 0.0}


def fly(controller: str, duration: float, rate: float, target: np.ndarray, t_step: float) -> Dict[str, Any]:
    hover_speed = np.sqrt(quad_params["mass"] * 9.81 / (4 * quad_params["k_eta"]))
    initial = {
        "x": np.zeros(3), "v": np.zeros(3), "q": np.array([0.0, 0.0, 0.0, 1.0]), "w": np.zeros(3),
        "wind": np.zeros(3), "rotor_speeds": np.full(4, hover_speed),
    }  # fmt: skip
    vehicle = Multirotor(quad_params, initial_state=initial, control_abstraction="cmd_ctbm")
    wind = SinusoidWind(amplitudes=np.array([1.0, 1.0, 0.3]), frequencies=np.array([0.5, 0.3, 0.7]))
    env = Environment(
        vehicle=vehicle,
        controller=ftsmc.rotorpy.Controller(controller, quad_params),
        trajectory=HoverThenStep(target, t_step),
        wind_profile=wind,
        sim_rate=rate,
    )
    result: Dict[str, Any] = env.run(t_final=duration, terminate=False)
    return result


def tracking(result: Dict[str, Any], target: np.ndarray, t_step: float) -> Dict[str, float]:
    """Hover: max |position error| over [1 s, t_step); step: max |error| over the last second."""
    t, x = result["time"], result["state"]["x"]
    hover = (t >= 1.0) & (t < t_step)
    last = t >= t[-1] - 1.0
    return {
        "hover_max_error_m": float(np.abs(x[hover]).max()) if hover.any() else float("nan"),
        "step_max_error_m": float(np.abs(x[last] - target).max()) if t[-1] > t_step else float("nan"),
        "flown_s": float(t[-1]),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--controllers", default="ftaftsmc,tsm-sta")
    parser.add_argument("--duration", type=float, default=6.0)
    parser.add_argument("--rate", type=float, default=500.0, help="RotorPy simulation and control rate, Hz")
    parser.add_argument("--out", type=Path, default=Path("results/python"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    target, t_step = np.array([0.5, 0.0, 0.3]), 3.0

    fig, axes = plt.subplots(3, 1, figsize=(7, 7), sharex=True)
    for controller in args.controllers.split(","):
        result = fly(controller, args.duration, args.rate, target, t_step)
        numbers = tracking(result, target, t_step)
        print(f"{ftsmc.label(controller):>12}: exit {result['exit'].value}; " + ", ".join(f"{k} {v:.4f}" for k, v in numbers.items()))
        for i, ax in enumerate(axes):
            ax.plot(result["time"], result["state"]["x"][:, i], label=ftsmc.label(controller))
    for i, ax in enumerate(axes):
        ax.set_ylabel("xyz"[i] + " (m)")
        ax.set_ylim(-1.5, 1.5)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[-1].set_xlabel("t (s)")
    fig.suptitle("RotorPy Hummingbird in sinusoidal wind: hover, then a step at 3 s")
    fig.tight_layout()
    path = args.out / "rotorpy.png"
    fig.savefig(path, dpi=120)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
