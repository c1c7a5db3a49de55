"""Reproduce the paper's Table 3 (ISE per channel, both scenarios, three
controllers) and plot Fig. 4 (scenario 1 position tracking) with matplotlib.

    python examples/python/table3_fig4.py [--out DIR]

Same numbers as `ftsmc reproduce` (the same simulator and scenarios).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Dict

import matplotlib

matplotlib.use("Agg")  # headless; set MPLBACKEND to override
import matplotlib.pyplot as plt

import ftsmc


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", type=Path, default=Path("results/python"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    runs: Dict[str, Dict[str, ftsmc.Run]] = {}
    for name in ("paper-scenario-1", "paper-scenario-2"):
        scenario = ftsmc.Scenario.builtin(name)
        runs[name] = {c: ftsmc.simulate(scenario, c) for c in scenario.controllers}

    print("Table 3 — ISE ∫e² dt (m²·s; ψ rad²·s)\n")
    print(f"{'scenario':<18}{'channel':<9}" + "".join(f"{ftsmc.label(c):>16}" for c in runs["paper-scenario-1"]))
    for name, by_controller in runs.items():
        for axis in ("x", "y", "z", "psi"):
            cells = "".join(f"{run.metrics['ise'][axis]:>16.5f}" for run in by_controller.values())
            print(f"{name:<18}{axis:<9}{cells}")

    fig, axes = plt.subplots(3, 1, figsize=(7, 7), sharex=True)
    s1 = runs["paper-scenario-1"]
    first = next(iter(s1.values()))
    for ax, axis in zip(axes, ("x", "y", "z")):
        ax.plot(first.columns["t"], first.columns[f"{axis}_ref"], "k--", label="reference")
        for controller, run in s1.items():
            ax.plot(run.columns["t"], run.columns[axis], label=ftsmc.label(controller))
        ax.set_ylabel(f"{axis} (m)")
        ax.grid(True, alpha=0.3)
    axes[0].legend(loc="lower right", fontsize=8)
    axes[-1].set_xlabel("t (s)")
    fig.suptitle("Fig. 4 — scenario 1, position tracking")
    fig.tight_layout()
    path = args.out / "fig4.png"
    fig.savefig(path, dpi=120)
    print(f"\nwrote {path}")


if __name__ == "__main__":
    main()
