"""``ftsmc.compare``: which of these controllers (or gain files) is best on
a scenario, and is the difference real? The code of ``ftsmc compare``
(docs/statistics.md): every contestant flies the same draws, each gets its
intervals, each pair a paired verdict (McNemar's exact test on success, the
Wilcoxon signed-rank test on RMS position error, Holm over all tests).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, NamedTuple, Optional, Sequence, Union

from . import _ftsmc, _progress
from ._frames import frame as _frame
from ._ftsmc import Scenario

if TYPE_CHECKING:
    import pandas


class Comparison(NamedTuple):
    """What :func:`compare` found.

    ``runs``: the rows of ``runs.csv`` (column ``controller`` holds the
    contestant's name). ``summary``: one row per contestant, indexed by
    name, with ``runs``, ``successes`` and ``<x>``, ``<x>_lo``, ``<x>_hi``
    for ``success``, ``completed``, ``crashed``, ``diverged`` (fractions)
    and ``rms_median``, ``rms_p95``, ``rms_mean`` (RMS position error, m;
    ``inf`` where the runs cannot give a bound). ``verdicts``: one row per
    pair and metric (``success``, ``rms_position_error``) with the effect
    (``p_A − p_B``, or the median of ``A − B`` in m) and its interval, the
    uncorrected ``p``, Holm's ``p_holm`` and the ``verdict``.
    """

    runs: "pandas.DataFrame"
    summary: "pandas.DataFrame"
    verdicts: "pandas.DataFrame"
    runs_flown: int
    all_decided: bool
    confidence: float


def compare(
    scenario: Scenario,
    contestants: Sequence[Union[str, Scenario]],
    runs: int = int(_ftsmc.DEFAULTS["compare_runs"]),
    *,
    until_decided: bool = False,
    max_runs: int = int(_ftsmc.DEFAULTS["compare_max_runs"]),
    batch: int = int(_ftsmc.DEFAULTS["compare_batch"]),
    confidence: float = float(_ftsmc.DEFAULTS["confidence"]),
    seed: Optional[int] = None,
    threads: Optional[int] = None,
    allow_other_vehicle: bool = False,
    progress: _progress.ProgressArg = None,
) -> Comparison:
    """Fly ``contestants`` on ``scenario``'s vehicle, wind and draws, as ``ftsmc compare``.

    A contestant is a built-in controller name (``"pid"``), the path of a
    scenario or ``*.tuned.toml`` file, or a :class:`Scenario`: only its
    controller section is taken. A file made for another vehicle is refused
    unless ``allow_other_vehicle``. ``runs`` runs per contestant, or with
    ``until_decided`` batches of ``batch`` runs until every pair is decided
    or ``max_runs`` is reached (O'Brien–Fleming alpha spending keeps the
    error rate). Intervals and verdicts at ``confidence``; master seed
    ``seed`` (default: the scenario's). ``progress`` as in
    :func:`ftsmc.montecarlo`.
    """
    import pandas

    if isinstance(contestants, (str, Scenario)):
        raise TypeError("contestants is a list of two or more (e.g. ['pid', 'se3'])")
    items: list[Any] = list(contestants)
    most = max_runs if until_decided else runs
    cb = _progress.callback(progress, most * len(items), f"{scenario.name} comparison")
    try:
        (names, columns), order, rows, verdicts, flown, decided = _ftsmc.compare_native(
            scenario, items, runs, until_decided, batch, max_runs, confidence, seed, threads, allow_other_vehicle, cb
        )
    finally:
        _progress.close(cb)
    summary = pandas.DataFrame([dict(r) for r in rows], index=pandas.Index(order, name="contestant"))
    summary = summary.astype({"runs": "int64", "successes": "int64"})
    verdict_rows = [
        {
            "a": a,
            "b": b,
            "metric": metric,
            "pairs": pairs,
            "effect": effect,
            "effect_lo": lo,
            "effect_hi": hi,
            "p": p,
            "p_holm": p_holm,
            "verdict": verdict,
        }
        for (a, b, metric, verdict), (pairs, effect, lo, hi, p, p_holm) in verdicts
    ]
    return Comparison(
        runs=_frame(names, columns),
        summary=summary,
        verdicts=pandas.DataFrame(verdict_rows),
        runs_flown=flown,
        all_decided=decided,
        confidence=confidence,
    )
