"""Campaigns on a Dask cluster: each task flies a shard of runs.

``ftsmc.montecarlo(scenario, runs, client=client)`` splits the batch into
contiguous blocks of run indices (the CLI's ``--shard K/N`` blocks, see
:func:`shard_ranges`) and submits one task per block to a
``dask.distributed.Client``. A run's random draws come from the master seed
and its run index only, so a task's rows are bit-identical to those rows of
the single-process call, whichever worker flies it and however often.

Tasks are pure functions of their arguments (the scenario as TOML text, the
run range, seed and controllers): when a worker dies mid-task Dask runs the
task again on another worker (up to ``distributed.scheduler.allowed-failures``
times, default 3), and the rows are gathered by task position, so nothing is
lost or counted twice; :func:`montecarlo_columns` checks every task returned
exactly its runs before joining them.

The generic layer, :func:`map_batches`, submits "a batch of work items" tasks
and gathers their results in order; tuning (a generation of candidates split
into batches) is meant to use it the same way.

Dask is an optional extra: ``pip install "./python[dask]"``. Importing
``ftsmc`` never imports Dask; this module imports it only when called.
"""

from __future__ import annotations

from typing import Any, Callable, List, Optional, Sequence, Tuple, TypeVar, Union

import numpy as np
import numpy.typing as npt

from . import _ftsmc

__all__ = ["MAX_SHARDS", "map_batches", "montecarlo_columns", "shard_ranges"]

T = TypeVar("T")
R = TypeVar("R")

Columns = Tuple[List[str], List[Union[npt.NDArray[Any], List[str]]]]
"""``runs.csv`` as ``(names, columns)`` (see ``_ftsmc.montecarlo_columns``)."""

TASKS_PER_THREAD = 4
"""Default tasks per worker thread: enough that a slow or lost worker costs a
small share of the batch, few enough that the per-task overhead (a few ms,
docs/campaigns.md) stays negligible against a shard's flights."""


MAX_SHARDS = 100_000
"""Most Dask tasks of one batch: each is a task on the scheduler and a
range held on the client, so the count is capped before any is built."""


def shard_ranges(runs: int, shards: int) -> List[Tuple[int, int]]:
    """The ``shards`` contiguous blocks ``[⌊(k−1)·runs/N⌋, ⌊k·runs/N⌋)`` of
    ``range(runs)``, k = 1 … N: the runs of ``ftsmc montecarlo --shard k/N``."""
    if runs < 1:
        raise ValueError("runs must be at least 1")
    if not 1 <= shards <= min(runs, MAX_SHARDS):
        raise ValueError(f"shards must be between 1 and runs ({runs}) and at most MAX_SHARDS ({MAX_SHARDS}), got {shards}")
    return [((k - 1) * runs // shards, k * runs // shards) for k in range(1, shards + 1)]


def map_batches(client: Any, function: Callable[..., R], batches: Sequence[T], *args: Any) -> List[R]:
    """``[function(*args, batch) for batch in batches]``, one Dask task per batch.

    ``function`` must be a pure, importable (module-level) function of its
    arguments: Dask may run a task again when its worker dies, and the
    results are gathered by position, so each batch counts exactly once.
    Raises the first task's exception (after Dask's retries) if one fails.
    """
    futures = [client.submit(function, *args, batch, pure=True) for batch in batches]
    results: List[R] = client.gather(futures)
    return results


def _fly_shard(
    scenario_toml: str,
    runs: int,
    seed: Optional[int],
    controllers: Optional[List[str]],
    threads: Optional[int],
    run_range: Tuple[int, int],
) -> Columns:
    """One task: the rows of runs ``run_range`` of the batch (on a worker)."""
    scenario = _ftsmc.Scenario.from_toml(scenario_toml, "<scenario sent to a Dask worker>")
    return _ftsmc.montecarlo_columns(scenario, runs, seed, controllers, threads, run_range)


def montecarlo_columns(
    client: Any,
    scenario: _ftsmc.Scenario,
    runs: int,
    seed: Optional[int] = None,
    controllers: Optional[List[str]] = None,
    shards: Optional[int] = None,
    threads: Optional[int] = 1,
) -> Columns:
    """``_ftsmc.montecarlo_columns`` flown as Dask tasks, one per shard of runs.

    shards: number of tasks (default: ``TASKS_PER_THREAD`` × the cluster's
        worker threads, at most ``runs``).
    threads: threads each task flies on (default 1: one task per worker
        thread keeps every core busy without oversubscribing it).
    The columns are those of the single-process call, row for row.
    """
    # Refuse bad arguments here, before any task is submitted.
    if runs < 1:
        raise ValueError("runs must be at least 1")
    if shards is None:
        total_threads = sum(int(n) for n in client.nthreads().values())
        shards = min(runs, MAX_SHARDS, TASKS_PER_THREAD * max(1, total_threads))
    ranges = shard_ranges(runs, shards)
    names = list(scenario.controllers) if controllers is None else list(controllers)
    results = map_batches(client, _fly_shard, ranges, scenario.to_toml(), runs, seed, names, threads)

    column_names = results[0][0]
    joined: List[Union[npt.NDArray[Any], List[str]]] = []
    for (start, end), (shard_names, columns) in zip(ranges, results):
        if shard_names != column_names:
            raise RuntimeError(f"task for runs {start}..{end} returned other columns than the first task")
        run = np.asarray(columns[0])
        expected = np.repeat(np.arange(start, end, dtype=np.uint64), len(names))
        if not np.array_equal(run, expected) or list(columns[2]) != names * (end - start):
            raise RuntimeError(f"task for runs {start}..{end} returned other rows than its runs")
    for i in range(len(column_names)):
        parts = [columns[i] for _, columns in results]
        first = parts[0]
        if isinstance(first, list):
            joined.append([cell for part in parts for cell in part])
        else:
            joined.append(np.concatenate(parts))
    return column_names, joined
