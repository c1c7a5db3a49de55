#!/usr/bin/env bash
# Brings the flight-log samples into data/ from clones of their repositories,
# once, by hand (nothing downloads them at run time or in CI), and checks
# every file against data/SHA256SUMS.
#
#   data/fetch.sh PYULOG_GIT_DIR NANOBENCH_GIT_DIR
#
# PYULOG_GIT_DIR     a clone (bare or not) of https://github.com/PX4/pyulog
#                    holding commit 3cf17793f14709713ab297d3743314c658874068
# NANOBENCH_GIT_DIR  a clone of https://github.com/syediu/nanobench-iros2026
#                    holding commit 0ae7d689749db174dc779ab2f7c416cc12e14e2b
#
# ULog samples are copied unchanged. NanoBench flights are trimmed to the
# motors-on span plus 1 s (100 rows at 100 Hz) on each side: the header line,
# then the rows from 100 before the first row with motor_motor_m1 > 0 to 100
# after the last. data/README.md says what each file is and is for.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
[ $# -eq 2 ] || { sed -n '2,12p' "$0" >&2; exit 2; }
pyulog_git="$1"
nanobench_git="$2"
pyulog_commit=3cf17793f14709713ab297d3743314c658874068
nanobench_commit=0ae7d689749db174dc779ab2f7c416cc12e14e2b

show() { # git dir, commit, path -> stdout
    git --git-dir="$1" show "$2:$3" 2>/dev/null || git -C "$1" show "$2:$3"
}

mkdir -p "$here/ulog" "$here/nanobench"
for f in sample_log_small.ulg sample_appended_multiple.ulg; do
    show "$pyulog_git" "$pyulog_commit" "test/$f" > "$here/ulog/$f"
done
show "$pyulog_git" "$pyulog_commit" LICENSE.md > "$here/ulog/LICENSE.md"

for f in B2_circle_slow_rep1 B3_figure8_slow_rep1 B2_circle_fast_rep1 B3_figure8_fast_rep1; do
    full="$(mktemp)"
    show "$nanobench_git" "$nanobench_commit" "datasets/dataset/$f.csv" > "$full"
    # The untrimmed file must be the one the trimming was designed on.
    grep -q "^$(sha256sum < "$full" | cut -d' ' -f1)  $f.csv (untrimmed)\$" "$here/SHA256SUMS.untrimmed" \
        || { echo "fetch.sh: $f.csv differs from the file recorded in SHA256SUMS.untrimmed" >&2; exit 1; }
    awk -F, -v margin=100 '
        NR == 1 { header = $0; for (i = 1; i <= NF; i++) if ($i == "motor_motor_m1") m = i; next }
        { row[NR] = $0; if ($m + 0 > 0) { if (!first) first = NR; last = NR } }
        END {
            if (!m || !first) { print "no motor column or motors never on" > "/dev/stderr"; exit 1 }
            lo = first - margin; if (lo < 2) lo = 2
            hi = last + margin; if (hi > NR) hi = NR
            print header
            for (i = lo; i <= hi; i++) print row[i]
        }' "$full" > "$here/nanobench/$f.csv"
    show "$nanobench_git" "$nanobench_commit" "datasets/dataset/${f}_metadata.yaml" > "$here/nanobench/${f}_metadata.yaml"
    rm -f "$full"
done
show "$nanobench_git" "$nanobench_commit" LICENSE > "$here/nanobench/LICENSE"

cd "$here" && sha256sum -c SHA256SUMS
