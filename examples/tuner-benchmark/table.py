"""The Markdown table of docs/tuning.md's tuner benchmark, from the
`ftsmc compare` outputs `run.sh` leaves in WORKDIR/cmp/<rung>-<controller>/.

    python table.py WORKDIR RUNG [RUNG ...]
    python table.py --completion WORKDIR RUNG [RUNG ...]

One row per cell: each tuner's held-out success with its 95 % Wilson
interval, the paired success difference (new − first) with its interval
and Holm-adjusted McNemar p, which tuner the success verdict favours, the
RMS position error medians and the Wilcoxon verdict on it; then the count
of cells where the new tuner is better, not shown to differ, or worse.

With ``--completion``: per cell, the flights each tuner's gains complete
(no divergence, no crash) on the same draws, the discordant pairs and the
exact McNemar test on them, Holm-adjusted over the listed cells.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
from pathlib import Path

NAMES = {"ftaftsmc": "FTAFTSMC", "ranftsmc": "RANFTSMC", "tsm-sta": "TSM-STA", "pid": "PID", "se3": "SE(3)"}
# Scenarios without random draws: 200 flights are one flight flown 200 times.
DETERMINISTIC = {"paper-scenario-1"}


def wilson(k: int, n: int, z: float = 1.959963984540054) -> tuple[float, float]:
    """The 95 % Wilson score interval of k successes in n, in percent."""
    p = k / n
    d = 1 + z * z / n
    c = p + z * z / (2 * n)
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    return (c - h) / d * 100, (c + h) / d * 100


def signed(x: float) -> str:
    """A difference in percentage points, signed, with a true minus."""
    v = round(x * 100, 1) + 0.0
    return f"{v:+.1f}".replace("-", "−")


def side(verdict: dict[str, object]) -> str:
    """Which gain set a verdict favours: `first`, `new` or `=`."""
    return {"A better": "first", "B better": "new"}.get(str(verdict["verdict"]), "=")


def mcnemar_exact(b: int, c: int) -> float:
    """Two-sided exact McNemar p of b and c discordant pairs: the binomial
    test of min(b, c) in b + c at 1/2."""
    n = b + c
    if n == 0:
        return 1.0
    tail = sum(math.comb(n, i) for i in range(min(b, c) + 1)) / (1 << n)
    return min(1.0, 2 * tail)


def holm(ps: list[float]) -> list[float]:
    """Holm's step-down adjustment of ps, in their order."""
    order = sorted(range(len(ps)), key=lambda i: ps[i])
    adjusted = [0.0] * len(ps)
    running = 0.0
    for rank, i in enumerate(order):
        running = max(running, min(1.0, (len(ps) - rank) * ps[i]))
        adjusted[i] = running
    return adjusted


def contestants(runs: list[dict[str, str]]) -> tuple[str, str]:
    """The labels of first.toml and current.toml in runs.csv: compare
    labels a file by what it holds (`pid (tuned, …)`, the path added when
    two files share a label), in the order given, first.toml first."""
    names = list(dict.fromkeys(r["controller"] for r in runs))
    if len(names) != 2:
        raise SystemExit(f"expected the two contestants first.toml and current.toml, found {names}")
    return names[0], names[1]


def completion(work: Path, rung: str, controller: str) -> tuple[int, int, int, int, int]:
    """Flights completed by the first and the new gains of a cell, its
    draws, and the pairs only the new (b) or only the first (c) completed."""
    with open(work / "cmp" / f"{rung}-{controller}" / "out" / rung / "runs.csv", newline="") as f:
        runs = list(csv.DictReader(f))
    first_name, new_name = contestants(runs)
    done = {
        name: {r["run"]: r["exit"] == "completed" for r in runs if r["controller"] == name}
        for name in (first_name, new_name)
    }
    first, new = done[first_name], done[new_name]
    b = sum(new[k] and not first[k] for k in first)
    c = sum(first[k] and not new[k] for k in first)
    return sum(first.values()), sum(new.values()), len(first), b, c


def completion_table(work: Path, rungs: list[str]) -> list[str]:
    cells = [(rung, c, completion(work, rung, c)) for rung in rungs for c in NAMES]
    adjusted = holm([mcnemar_exact(b, c) for _, _, (_, _, _, b, c) in cells])
    lines = ["| rung | controller | completed, first | completed, new | only new / only first | Holm p |", "|---|---|---|---|---|---|"]
    for (rung, controller, (k0, k1, n, b, c)), p in zip(cells, adjusted):
        lines.append(
            f"| {rung.replace('realistic-', '')} | {NAMES[controller]} | {k0}/{n} | {k1}/{n} | {b} / {c} | {p:.2g} |"
        )
    return lines


def row(work: Path, rung: str, controller: str) -> tuple[str, str]:
    folder = work / "cmp" / f"{rung}-{controller}"
    out = folder / "out" / rung
    summary = json.loads((out / "summary.json").read_text())
    with open(out / "runs.csv", newline="") as f:
        runs = list(csv.DictReader(f))
    first_name, new_name = contestants(runs)
    counts: dict[str, tuple[int, int]] = {}
    for name in (first_name, new_name):
        mine = [r for r in runs if r["controller"] == name]
        counts[name] = (sum(r["success"] == "true" for r in mine), len(mine))
    verdicts = {v["metric"]: v for v in summary["verdicts"]}
    success, error = verdicts["success"], verdicts["error"]
    effect = success["effect"]  # first − new
    medians = {k: v["intervals"]["rms_median"]["estimate"] for k, v in summary["contestants"].items()}
    kept = "# Improved: false" in (folder / "current.toml").read_text()
    (k0, n0), (k1, n1) = counts[first_name], counts[new_name]
    lo0, hi0 = wilson(k0, n0)
    lo1, hi1 = wilson(k1, n1)
    verdict = side(success)
    p = format(success["p_holm"], ".2g").replace("-", "−")
    cells = [
        rung.replace("realistic-", ""),
        NAMES[controller],
        f"{k0}/{n0} [{lo0:.1f}, {hi0:.1f}]",
        f"{k1}/{n1} [{lo1:.1f}, {hi1:.1f}]" + (" (start)" if kept else ""),
        f"{signed(-effect['estimate'])} [{signed(-effect['hi'])}, {signed(-effect['lo'])}], p = {p}",
        "**new**" if verdict == "new" else verdict,
        f"{medians[first_name]:.3g} / {medians[new_name]:.3g}",
        "one flight" if rung in DETERMINISTIC else side(error),
    ]
    return "| " + " | ".join(cells) + " |", verdict


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--completion", action="store_true", help="the completion table instead")
    parser.add_argument("work", type=Path)
    parser.add_argument("rungs", nargs="+")
    args = parser.parse_args()
    if args.completion:
        print("\n".join(completion_table(args.work, args.rungs)))
        return
    tally = {"new": 0, "=": 0, "first": 0}
    for rung in args.rungs:
        for controller in NAMES:
            line, verdict = row(args.work, rung, controller)
            tally[verdict] += 1
            print(line)
    print(
        f"new better in {tally['new']}, no difference shown in {tally['=']}, first better in {tally['first']}: "
        f"at least as good in {tally['new'] + tally['=']} of {sum(tally.values())}"
    )


if __name__ == "__main__":
    main()
