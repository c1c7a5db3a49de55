"""``ftsmc.tune``: robust gains for a controller on a scenario (``ftsmc tune`` from Python).

The search, its cost and the held-out validation are ftsmc's Rust code, the
same as the ``ftsmc tune`` command's (docs/tuning.md); the same scenario,
controller, budget and seed give the same result whatever ``threads`` is.
"""

from __future__ import annotations

import json
from typing import Any, Dict, List, NamedTuple, Optional

from . import _ftsmc
from ._ftsmc import Scenario


class Tuned(NamedTuple):
    """The result of :func:`tune`."""

    scenario: Scenario
    """The input scenario with the tuned gains applied (``controllers`` = the tuned one)."""
    toml: str
    """The tuned scenario file: the complete scenario tuned on (its vehicle and every override) with the tuned
    gains, as the keys that differ from the built-in scenario it extends (or every key); records the cost,
    the headline verdict and the statistics."""
    summary: Dict[str, Any]
    """Parameters, chosen candidate, ``improved`` (the held-out headline: success by McNemar, then RMS position
    error by Wilcoxon) with ``improved_reason``, every candidate (``history``), the
    generations and the race, training and held-out statistics (NaN as None)."""


def tune(
    scenario: Scenario,
    controller: str,
    budget: int = int(_ftsmc.DEFAULTS["tune_budget"]),
    seed: Optional[int] = None,
    threads: Optional[int] = None,
    extends: Optional[str] = None,
    client: Any = None,
    batch: Optional[int] = None,
    mission: Optional[str] = None,
) -> Tuned:
    """Tune ``controller``'s declared gains on ``scenario`` by CMA-ES (``ftsmc tune``).

    ``budget`` training flights (the start's included), ``seed`` for the
    search and the Monte Carlo draws (default: the scenario's ``seed``),
    ``threads`` workers (default: all cores), the GIL released. The
    scenario's ``[tune]`` section narrows the parameters and sets the cost
    weights. ``extends`` names the built-in scenario the returned TOML
    extends (default: the scenario's name, when it is a built-in one); the
    TOML holds only the keys that differ from it when that loads back to the
    tuned scenario exactly, and every key otherwise, so it never depends on
    a path and keeps a vehicle changed by ``with_overrides``. Raises ``ValueError``
    for an unknown controller, a budget below one generation, a bad
    ``[tune]`` value, or start gains that fail every first training draw.

    ``client``: a ``dask.distributed.Client``. The CMA-ES search stays in
    this process; each generation's candidates (and the held-out flights)
    are flown as Dask tasks of ``batch`` candidates each (default: one
    candidate per task), each task the pure module-level objective
    ``_ftsmc.tune_evaluate`` on ``threads`` worker threads (default 1),
    gathered in order by :func:`ftsmc.dask.map_batches`. The result equals
    the local call's: every candidate flies the same draws either way.

    ``mission``: ``"steps"`` (default: the scenario's own reference),
    ``"hover"``, ``"figure-eight"`` or ``"waypoints"``, flown as ``ftsmc tune
    --mission`` flies it; the tuned TOML states it (``[tune] mission``) and
    ``Tuned.scenario.tune_mission`` reads it back.
    """
    if client is None:
        tuned, text, summary = _ftsmc.tune_native(scenario, controller, budget, seed, threads, extends, None, mission)
        return Tuned(tuned, text, json.loads(summary))
    if batch is not None and batch < 1:
        raise ValueError(f"batch must be at least 1, got {batch}")
    from .dask import map_batches

    master = scenario.seed if seed is None else seed
    per_task = 1 if batch is None else batch
    task_threads = 1 if threads is None else threads

    def evaluator(tomls: List[str], indices: List[int]) -> List[List[float]]:
        batches = [tomls[k : k + per_task] for k in range(0, len(tomls), per_task)]
        results = map_batches(client, _evaluate_batch, batches, controller, master, indices, task_threads)
        return [stats for result in results for stats in result]

    tuned, text, summary = _ftsmc.tune_native(scenario, controller, budget, seed, threads, extends, evaluator, mission)
    return Tuned(tuned, text, json.loads(summary))


def _evaluate_batch(
    controller: str, master: int, indices: List[int], threads: int, tomls: List[str]
) -> List[List[float]]:
    """One Dask task: the statistics of a batch of candidates (on a worker)."""
    return _ftsmc.tune_evaluate(tomls, controller, master, indices, threads)
