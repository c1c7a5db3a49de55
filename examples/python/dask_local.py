"""A Monte Carlo on a Dask LocalCluster (worker processes on this machine),
timed against the single-process call and checked equal to it row for row.

    pip install "./python[dask]"
    python examples/python/dask_local.py [--runs 1000] [--workers 2] [--shards N]
        [--scenario paper-scenario-2] [--controller ftaftsmc] [--no-local]

The same code runs on a cluster: replace the LocalCluster by a
dask-jobqueue SLURMCluster (examples/python/dask_slurm.py) or connect a
Client to a running scheduler. Each Dask task flies a contiguous block of
runs; a worker that dies mid-task has its task run again elsewhere, and the
rows come back identical (docs/campaigns.md).
"""

from __future__ import annotations

import argparse
import importlib
import logging
import resource
import time
from typing import Any

import pandas

import ftsmc


def cpu_seconds(who: int) -> float:
    """User + system CPU time of this process (``resource.RUSAGE_SELF``), s."""
    usage = resource.getrusage(who)
    return usage.ru_utime + usage.ru_stime


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--workers", type=int, default=2, help="worker processes, one thread each")
    parser.add_argument("--shards", type=int, default=None, help="Dask tasks (default: 4 per worker thread)")
    parser.add_argument("--scenario", default="paper-scenario-2")
    parser.add_argument("--controller", default="ftaftsmc")
    parser.add_argument("--no-local", action="store_true", help="skip the single-process reference run")
    args = parser.parse_args()

    # Dask's classes are untyped: reach them as Any so mypy --strict checks the rest.
    distributed: Any = importlib.import_module("dask.distributed")
    Client, LocalCluster = distributed.Client, distributed.LocalCluster

    scenario = ftsmc.Scenario.builtin(args.scenario)
    controllers = [args.controller]
    local = None
    if not args.no_local:
        # The reference: one process with as many threads as the cluster has workers.
        cpu0 = cpu_seconds(resource.RUSAGE_SELF)
        started = time.perf_counter()
        local = ftsmc.montecarlo(scenario, args.runs, controllers=controllers, threads=args.workers)
        local_s = time.perf_counter() - started
        local_cpu = cpu_seconds(resource.RUSAGE_SELF) - cpu0
        print(f"local call, {args.workers} thread(s): {args.runs} runs in {local_s:.2f} s (CPU {local_cpu:.2f} s)")

    with LocalCluster(
        n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=logging.ERROR
    ) as cluster, Client(cluster) as client:
        # Workers up and ftsmc imported (once per worker process) before the clock starts.
        started = time.perf_counter()
        client.run(importlib.import_module, "ftsmc")
        print(f"start-up: ftsmc imported on {args.workers} worker(s) in {time.perf_counter() - started:.2f} s")
        shards = args.shards or min(args.runs, 4 * args.workers)
        workers_cpu0 = sum(client.run(cpu_seconds, resource.RUSAGE_SELF).values())
        scheduler_cpu0 = client.run_on_scheduler(cpu_seconds, resource.RUSAGE_SELF)
        cpu0 = cpu_seconds(resource.RUSAGE_SELF)
        started = time.perf_counter()
        runs = ftsmc.montecarlo(scenario, args.runs, controllers=controllers, client=client, shards=shards)
        dask_s = time.perf_counter() - started
        client_cpu = cpu_seconds(resource.RUSAGE_SELF) - cpu0
        # CPU the workers and the scheduler spent: measured inside them.
        workers_cpu = sum(client.run(cpu_seconds, resource.RUSAGE_SELF).values()) - workers_cpu0
        scheduler_cpu = client.run_on_scheduler(cpu_seconds, resource.RUSAGE_SELF) - scheduler_cpu0
    print(f"Dask, {args.workers} worker process(es), {shards} tasks: {args.runs} runs in {dask_s:.2f} s")
    print(
        f"  CPU during the batch: workers {workers_cpu:.2f} s, scheduler {scheduler_cpu:.2f} s, "
        f"this process {client_cpu:.2f} s while waiting"
    )
    if local is not None:
        pandas.testing.assert_frame_equal(local, runs, check_exact=True)
        # Overhead per task: the extra wall time over the local call with as
        # many threads, spread over the tasks each worker ran; and the extra
        # CPU time over the local call's, per task (robust on a loaded machine).
        per_task = (dask_s - local_s) / (shards / args.workers)
        cpu_per_task = (workers_cpu + scheduler_cpu + client_cpu - local_cpu) / shards
        print(
            f"rows identical to the local call; overhead {dask_s - local_s:+.2f} s wall "
            f"({per_task * 1000:+.0f} ms per task per worker), {cpu_per_task * 1000:+.1f} ms CPU per task"
        )
    print(f"success rate: {runs['success'].mean():.3f}, median ISE z: {runs['ise_z'].median():.4g} m²·s")


if __name__ == "__main__":
    main()
