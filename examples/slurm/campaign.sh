#!/usr/bin/env bash
# A Monte Carlo campaign as a Slurm job array, ending in `ftsmc merge`.
#
#   examples/slurm/campaign.sh SCENARIO RUNS N [OUT]
#   e.g. examples/slurm/campaign.sh realistic-scenario-2 10000 50 campaign
#
# Submits shard.sbatch as an array of N tasks (`sbatch --array=1-N`), each
# flying one contiguous block of runs (`ftsmc montecarlo --shard K/N`), and
# merge.sbatch to run once the array has ended (`--dependency=afterany`),
# which writes OUT/<scenario>/ exactly as `ftsmc montecarlo SCENARIO --runs
# RUNS` would. Environment: CONTROLLERS (a,b,c), SEED, FTSMC (the binary,
# default `ftsmc` on PATH); #SBATCH lines in the two scripts set cores and
# time per task; add your partition/account there or on this command line
# (SBATCH_PARTITION, SBATCH_ACCOUNT are read by sbatch).
#
# Without sbatch on PATH (or with FTSMC_LOCAL=1) the same scripts run here,
# one shard after another: the campaign runs as it is on a laptop.
#
# Resuming: running this again skips every shard whose folder is complete
# and flies only the others (docs/campaigns.md).
set -euo pipefail
[ $# -ge 3 ] || { sed -n '2,20p' "$0"; exit 2; }
here=$(cd "$(dirname "$0")" && pwd)
export SCENARIO=$1 RUNS=$2 N=$3 OUT=${4:-campaign}
export CONTROLLERS=${CONTROLLERS:-} SEED=${SEED:-} FTSMC=${FTSMC:-ftsmc}
if command -v sbatch >/dev/null && [ -z "${FTSMC_LOCAL:-}" ]; then
    job=$(sbatch --parsable --array=1-"$N" --export=ALL "$here/shard.sbatch")
    job=${job%%;*}
    merge=$(sbatch --parsable --dependency=afterany:"$job" --export=ALL "$here/merge.sbatch")
    echo "submitted: shards as array job $job (1-$N), merge as job $merge after them"
else
    echo "no sbatch: flying the $N shards one after another on this machine"
    for K in $(seq 1 "$N"); do
        SLURM_ARRAY_TASK_ID=$K bash "$here/shard.sbatch"
    done
    bash "$here/merge.sbatch"
fi
