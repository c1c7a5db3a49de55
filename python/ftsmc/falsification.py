"""``ftsmc.falsify`` and ``ftsmc.failure_probability``: worst cases and rare
failures from Python (``ftsmc falsify`` / ``ftsmc failure-probability``).

The search and the estimate are ftsmc's Rust code, the same as the commands'
(docs/falsification.md); the same scenario, controller, budget and seed give
the same numbers whatever ``threads`` is.
"""

from __future__ import annotations

import json
from typing import Any, Dict, Optional

from . import _ftsmc
from ._ftsmc import Scenario


def falsify(
    scenario: Scenario,
    controller: str,
    budget: int = int(_ftsmc.DEFAULTS["falsify_budget"]),
    seed: Optional[int] = None,
    threads: Optional[int] = None,
) -> Dict[str, Any]:
    """Search ``scenario``'s ``[falsify]`` box for the lowest robustness margin of ``controller``.

    CMA-ES with restarts and, beside it, ``budget`` uniform random draws
    (``budget`` flights each; search seed ``seed``, default the scenario's;
    the turbulence seed is the scenario's, held fixed). Returns a dict:
    ``parameters`` (names), ``falsify`` and ``random`` (``lowest_margin``,
    ``lowest_flight``, ``first_violation_flight``, ``violations`` and every
    flight in ``history``: ``flight``, ``restart``, ``margin``, ``values``),
    and ``worst_toml``, the worst case as a scenario file (``Scenario.from_toml``
    of it, flown, gives ``lowest_margin`` bit for bit). Raises ``ValueError``
    without a ``[falsify]`` section or an ``[envelope]``, or for a budget of 0.
    """
    result: Dict[str, Any] = json.loads(_ftsmc.falsify_native(scenario, controller, budget, seed, threads))
    return result


def failure_probability(
    scenario: Scenario,
    controller: str,
    budget: int = int(_ftsmc.DEFAULTS["failure_probability_budget"]),
    confidence: float = float(_ftsmc.DEFAULTS["confidence"]),
    seed: Optional[int] = None,
    threads: Optional[int] = None,
) -> Dict[str, Any]:
    """``P(margin < 0)`` of ``controller`` on ``scenario`` by cross-entropy importance sampling.

    The ``[falsify]`` parameters at their nominal distributions, the
    ``[montecarlo]`` draws and the turbulence as ``ftsmc montecarlo`` draws
    them. Returns a dict: ``p`` with its interval ``lo``, ``hi`` at
    ``confidence``, ``flights``, ``final_flights``, ``failures``, ``ess``
    (effective sample size), ``plain_mc_equivalent`` (NaN when unreliable),
    ``one_sided`` (no failing flight: the interval is ``[0, hi]``),
    ``reliable`` (false below 30 effective failing flights: do not trust the
    interval; try a larger budget) and the CE ``levels``. The final flights
    are drawn from a defensive mixture (10 % nominal draws), so every weight
    is at most 10.
    """
    result: Dict[str, Any] = json.loads(
        _ftsmc.failure_probability_native(scenario, controller, budget, confidence, seed, threads)
    )
    return result
