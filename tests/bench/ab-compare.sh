#!/bin/sh
# Alternating A/B of two stria_bench binaries on a shared, noisy machine:
# PAIRS pairs of short runs (old, then new), each 3 repetitions of 0.2 s of
# timed work; per benchmark the medians and minima of the runs' CPU-time
# medians, the median of the pairs' new/old ratios and how many pairs the new
# binary won. Alternating in short runs puts a slow spell of the VM on both
# binaries alike, where one long run each would put it on one.
#
#   tests/bench/ab-compare.sh OLD_BENCH NEW_BENCH [FILTER] [PAIRS]
#       FILTER: a --benchmark_filter regex (default: both decodes and the
#       780x580 Sobel BGR reference); PAIRS: default 10 (about 2 minutes).
#
# Build the old binary from the old commit (a git worktree), copy both
# binaries somewhere stable first if a build may replace them.
set -eu
if [ $# -lt 2 ]; then
    echo "usage: $0 OLD_BENCH NEW_BENCH [FILTER] [PAIRS]" >&2
    exit 2
fi
old=$1 new=$2
filter=${3:-'^(decode/780x580|decode/1388x1038|sobel/bgr_780x580)$'}
pairs=${4:-10}
for b in "$old" "$new"; do
    [ -x "$b" ] || { echo "ab-compare: $b is not an executable" >&2; exit 1; }
done
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for r in $(seq 1 "$pairs"); do
    echo "ab-compare: pair $r of $pairs" >&2
    "$old" --benchmark_filter="$filter" --benchmark_repetitions=3 --benchmark_min_time=0.2 \
        --benchmark_format=json --benchmark_out="$out/old$r.json" >/dev/null
    "$new" --benchmark_filter="$filter" --benchmark_repetitions=3 --benchmark_min_time=0.2 \
        --benchmark_format=json --benchmark_out="$out/new$r.json" >/dev/null
done
/usr/bin/python3 - "$out" "$pairs" <<'PY'
import json, statistics, sys
out, pairs = sys.argv[1], int(sys.argv[2])
def medians(path):
    result = {}
    for b in json.load(open(path))["benchmarks"]:
        if b.get("run_type") == "aggregate" and b.get("aggregate_name") == "median":
            result[b["run_name"]] = b["cpu_time"] / {"ns": 1e6, "us": 1e3, "ms": 1.0, "s": 1e-3}[b["time_unit"]]
    return result
runs = [(medians(f"{out}/old{r}.json"), medians(f"{out}/new{r}.json")) for r in range(1, pairs + 1)]
print("| benchmark | old ms (median, min) | new ms (median, min) | new / old (median of pairs) | new faster |")
print("|---|---|---|---|---|")
for name in runs[0][0]:
    old = [o[name] for o, _ in runs]
    new = [n[name] for _, n in runs]
    ratios = [n / o for o, n in zip(old, new)]
    print(f"| {name} | {statistics.median(old):.3f}, {min(old):.3f} | {statistics.median(new):.3f}, {min(new):.3f} "
          f"| {statistics.median(ratios):.3f} | {sum(r < 1 for r in ratios)} of {pairs} |")
PY
