"""A Monte Carlo on a Slurm cluster through dask-jobqueue: Dask starts its
workers as Slurm jobs, ftsmc sends them shards of runs, the rows come back
into one DataFrame and are written as runs.csv.

    pip install "./python[dask]" dask-jobqueue     # on the cluster's login node
    python examples/python/dask_slurm.py --runs 10000 --jobs 4 --cores 32 \
        --queue normal --walltime 01:00:00 --out campaign-runs.csv

Each Slurm job is one Dask worker host with `--cores` worker processes of
one thread each (ftsmc flies a task on one thread). Adapt `--queue`,
`--account`, `--memory` and `--walltime` to your site. The result equals
`ftsmc.montecarlo(scenario, runs)` on one machine, row for row.
"""

from __future__ import annotations

import argparse
import importlib
import time
from pathlib import Path
from typing import Any, List, Optional

import ftsmc


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scenario", default="realistic-scenario-2", help="built-in name or TOML file")
    parser.add_argument("--runs", type=int, default=10000)
    parser.add_argument("--controllers", default=None, help="comma-separated (default: the scenario's list)")
    parser.add_argument("--jobs", type=int, default=2, help="Slurm jobs (worker hosts)")
    parser.add_argument("--cores", type=int, default=32, help="cores per job")
    parser.add_argument("--memory", default="16GB", help="memory per job")
    parser.add_argument("--queue", default=None, help="Slurm partition")
    parser.add_argument("--account", default=None)
    parser.add_argument("--walltime", default="01:00:00")
    parser.add_argument("--out", type=Path, default=Path("campaign-runs.csv"))
    args = parser.parse_args()

    # Dask's classes are untyped: reach them as Any so mypy --strict checks the rest.
    Client: Any = importlib.import_module("dask.distributed").Client
    SLURMCluster: Any = importlib.import_module("dask_jobqueue").SLURMCluster

    path = Path(args.scenario)
    scenario = ftsmc.Scenario.from_file(path) if path.is_file() else ftsmc.Scenario.builtin(args.scenario)
    controllers: Optional[List[str]] = args.controllers.split(",") if args.controllers else None

    cluster = SLURMCluster(
        cores=args.cores,
        processes=args.cores,  # one single-threaded worker process per core
        memory=args.memory,
        queue=args.queue,
        account=args.account,
        walltime=args.walltime,
    )
    cluster.scale(jobs=args.jobs)
    with Client(cluster) as client:
        client.wait_for_workers(1)
        started = time.perf_counter()
        runs = ftsmc.montecarlo(scenario, args.runs, controllers=controllers, client=client)
        elapsed = time.perf_counter() - started
    cluster.close()
    # The CLI's runs.csv columns; pandas writes numbers in its own format
    # (use `ftsmc montecarlo --shard` + `ftsmc merge` for the CLI's bytes).
    runs.to_csv(args.out, index=False)
    print(f"{len(runs)} flights in {elapsed:.1f} s; wrote {args.out}")
    print(runs.groupby("controller", sort=False)["success"].mean().to_string())


if __name__ == "__main__":
    main()
