"""A 1000-run Monte Carlo of paper scenario 2 into pandas, with a box plot
of the ISE per channel and controller.

    python examples/python/montecarlo_boxplot.py [--runs 1000] [--out DIR]

The DataFrame holds the rows of the CLI's runs.csv
(`ftsmc montecarlo paper-scenario-2 --runs 1000`), value for value.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

import ftsmc


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--threads", type=int, default=None)
    parser.add_argument("--out", type=Path, default=Path("results/python"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    scenario = ftsmc.Scenario.builtin("paper-scenario-2")
    started = time.perf_counter()
    runs = ftsmc.montecarlo(scenario, args.runs, threads=args.threads)
    elapsed = time.perf_counter() - started
    print(f"{len(runs)} flights in {elapsed:.2f} s ({len(runs) / elapsed:.0f} flights/s)")

    completed = runs[runs["completed"]]
    print("\nsuccess rate per controller:")
    print(runs.groupby("controller", sort=False)["success"].mean().to_string())
    print("\nmedian ISE over the completed runs:")
    print(completed.groupby("controller", sort=False)[["ise_x", "ise_y", "ise_z", "ise_psi"]].median().to_string())

    fig, axes = plt.subplots(1, 4, figsize=(12, 4))
    controllers = list(dict.fromkeys(runs["controller"]))
    for ax, axis in zip(axes, ("x", "y", "z", "psi")):
        data = [completed.loc[completed["controller"] == c, f"ise_{axis}"].to_numpy() for c in controllers]
        ax.boxplot(data, whis=(5, 95), showfliers=False)
        ax.set_xticks(range(1, len(controllers) + 1))
        ax.set_xticklabels([ftsmc.label(c) for c in controllers], rotation=30, fontsize=8)
        ax.set_yscale("log")
        ax.set_title(f"ISE {axis}")
    fig.suptitle(f"Monte Carlo, {args.runs} runs of paper scenario 2 (completed runs; whiskers p5–p95)")
    fig.tight_layout()
    path = args.out / "montecarlo-ise.png"
    fig.savefig(path, dpi=120)
    print(f"\nwrote {path}")


if __name__ == "__main__":
    main()
