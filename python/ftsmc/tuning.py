"""``ftsmc.tune``: robust gains for a controller on a scenario (``ftsmc tune`` from Python).

The search, its cost and the held-out validation are ftsmc's Rust code, the
same as the ``ftsmc tune`` command's (docs/tuning.md); the same scenario,
controller, budget and seed give the same result whatever ``threads`` is.
"""

from __future__ import annotations

import json
from typing import Any, Dict, NamedTuple, Optional

from . import _ftsmc
from ._ftsmc import Scenario


class Tuned(NamedTuple):
    """The result of :func:`tune`."""

    scenario: Scenario
    """The input scenario with the tuned gains applied (``controllers`` = the tuned one)."""
    toml: str
    """The tuned scenario file: ``extends`` the input, sets only the tuned gains, records the cost and statistics."""
    summary: Dict[str, Any]
    """Parameters, best candidate, every candidate (``history``), training and held-out statistics (NaN as None)."""


def tune(
    scenario: Scenario,
    controller: str,
    budget: int = 2000,
    seed: Optional[int] = None,
    threads: Optional[int] = None,
    extends: Optional[str] = None,
) -> Tuned:
    """Tune ``controller``'s declared gains on ``scenario`` by CMA-ES (``ftsmc tune``).

    ``budget`` training flights (the start's included), ``seed`` for the
    search and the Monte Carlo draws (default: the scenario's ``seed``),
    ``threads`` workers (default: all cores), the GIL released. The
    scenario's ``[tune]`` section narrows the parameters and sets the cost
    weights. ``extends`` is what the returned TOML extends (default: the
    scenario's name, right for a built-in scenario). Raises ``ValueError``
    for an unknown controller, a budget below one generation, or a bad
    ``[tune]`` value.
    """
    tuned, text, summary = _ftsmc.tune_native(scenario, controller, budget, seed, threads, extends)
    return Tuned(tuned, text, json.loads(summary))
