#!/usr/bin/env bash
# The tuner benchmark of docs/tuning.md ("The tuner against the first"):
# tune every cell (rung x controller) with two builds of ftsmc on the same
# budget and seed, then fly each cell's two tuned files on the same 200
# fresh draws with `ftsmc compare` (paired verdicts); `table.py` prints
# the Markdown table from the compare outputs.
#
#   run.sh FIRST_FTSMC NEW_FTSMC WORKDIR [RUNG ...]
#
# FIRST_FTSMC is the baseline build (docs/tuning.md: commit 2cc479c,
# which tunes one controller per command), NEW_FTSMC the build under test.
# About 80 minutes on two cores for the ten rungs (both tuners, then the
# 50 comparisons); each tune writes into WORKDIR/{first,new}/out-<rung>/.
set -euo pipefail
first=$(readlink -f "${1:?usage: run.sh FIRST_FTSMC NEW_FTSMC WORKDIR [RUNG ...]}")
new=$(readlink -f "${2:?usage: run.sh FIRST_FTSMC NEW_FTSMC WORKDIR [RUNG ...]}")
work=${3:?usage: run.sh FIRST_FTSMC NEW_FTSMC WORKDIR [RUNG ...]}
shift 3
rungs=("$@")
if [ ${#rungs[@]} -eq 0 ]; then
    rungs=(paper-scenario-1 paper-scenario-2)
    for r in calm breeze light moderate; do rungs+=("realistic-$r-1" "realistic-$r-2"); done
fi
controllers=(ftaftsmc ranftsmc tsm-sta pid se3)
mkdir -p "$work"
cd "$work"
for rung in "${rungs[@]}"; do
    for c in "${controllers[@]}"; do
        "$first" tune "$rung" -c "$c" --threads 2 --out "first/out-$rung" --no-figures > "first-$rung-$c.log" 2>&1
    done
    "$new" tune "$rung" -c "$(IFS=,; echo "${controllers[*]}")" --threads 2 --out "new/out-$rung" --no-figures > "new-$rung.log" 2>&1
    for c in "${controllers[@]}"; do
        d="cmp/$rung-$c"
        mkdir -p "$d"
        cp "first/out-$rung/$rung/$c.tuned.toml" "$d/first.toml"
        cp "new/out-$rung/$rung/$c.tuned.toml" "$d/current.toml"
        (cd "$d" && "$new" compare "$rung" -c first.toml,current.toml --runs 200 --seed 2026 --threads 2 --out out --no-figures > log.txt 2>&1)
    done
    echo "$rung done"
done
