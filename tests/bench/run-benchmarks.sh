#!/usr/bin/env bash
# Builds the host preset's benchmark suite (stria_bench), runs it with
# repetitions and rewrites the measured tables of docs/performance.md (between
# the "bench:begin" and "bench:end" markers) from the run's JSON output, with
# the machine, date and compiler. Every figure in that table comes from this
# run; the ratios use medians of the repetitions of the same run.
#
#   tests/bench/run-benchmarks.sh [REPETITIONS]       (default 10)
#
# STRIA_BENCH_BUILD_DIR=DIR builds and runs in an already configured build
# folder instead of the host preset's build/host.
set -euo pipefail
cd "$(dirname "$0")/../.."
repetitions=${1:-10}
[[ $repetitions =~ ^[1-9][0-9]*$ ]] || { echo "run-benchmarks.sh: REPETITIONS must be a positive number, not '$repetitions'" >&2; exit 2; }

if [[ -n ${STRIA_BENCH_BUILD_DIR:-} ]]; then
    build=$STRIA_BENCH_BUILD_DIR
    cmake --build "$build" --target stria_bench
else
    build=build/host
    cmake --preset host >/dev/null
    cmake --build --preset host --target stria_bench
fi
bench=$build/tests/bench/stria_bench
[[ -x $bench ]] || { echo "run-benchmarks.sh: $bench was not built (is STRIA_BUILD_BENCHMARKS on?)" >&2; exit 1; }

json=$build/bench-results.json
stage_json=$build/bench-stages.json
load=$(cut -d' ' -f1-3 /proc/loadavg)
# Random interleaving: the repetitions of all benchmarks run in a shuffled
# order, so a slow spell of a shared machine falls on the decode and on its
# Sobel reference alike instead of on whichever ran then (this VM's speed
# drifts by 30 % within minutes), and the ratios of medians compare like
# with like.
echo "run-benchmarks.sh: whole decodes, references and video mode ($repetitions repetitions)..." >&2
"$bench" --benchmark_filter='-^stage/' --benchmark_repetitions="$repetitions" \
    --benchmark_report_aggregates_only=true --benchmark_enable_random_interleaving=true \
    --benchmark_out="$json" --benchmark_out_format=json
# The stages alone in a run of their own, with the Sobel BGR reference
# interleaved again, each repetition timing 50 ms of the stage: every
# iteration first repeats the earlier stages untimed (the edge stage's 0.3
# ms follow 7 ms of them), so the default 0.5 s of timed work made this part
# alone take most of an hour at 10 repetitions.
echo "run-benchmarks.sh: each stage alone ($repetitions repetitions)..." >&2
"$bench" --benchmark_filter='^(stage/|sobel/bgr_)' --benchmark_min_time=0.05 --benchmark_repetitions="$repetitions" \
    --benchmark_report_aggregates_only=true --benchmark_enable_random_interleaving=true \
    --benchmark_out="$stage_json" --benchmark_out_format=json

compiler=$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$build/CMakeCache.txt")
export STRIA_BENCH_COMPILER="$("${compiler:-c++}" --version | head -n1)"
export STRIA_BENCH_CPU="$(lscpu | sed -n 's/^Model name: *//p' | head -n1)"
export STRIA_BENCH_CORES="$(nproc) cores available ($(lscpu | sed -n 's/^CPU(s): *//p') CPUs, $(lscpu | sed -n 's/^Thread(s) per core: *//p') threads per core)"
export STRIA_BENCH_LOAD="$load"
export STRIA_BENCH_REPETITIONS="$repetitions"
export STRIA_BENCH_SOURCE="$(git describe --always --dirty 2>/dev/null || echo unknown)"
python3 - "$json" "$stage_json" docs/performance.md <<'EOF'
import datetime, json, os, sys

json_path, stage_json_path, doc_path = sys.argv[1], sys.argv[2], sys.argv[3]

def medians(path):
    runs = json.load(open(path))["benchmarks"]
    errors = sorted({r["run_name"] + ": " + r.get("error_message", "") for r in runs if r.get("error_occurred")})
    if errors:
        sys.exit("run-benchmarks.sh: benchmarks reported errors, docs not updated:\n  " + "\n  ".join(errors))
    return {r["run_name"]: r for r in runs if r.get("aggregate_name") == "median"}, path

main_run, stage_run = medians(json_path), medians(stage_json_path)

def get(name, run=main_run):
    median, path = run
    for run_name, r in median.items():
        if run_name == name or run_name.startswith(name + "/"):
            return r
    sys.exit(f"run-benchmarks.sh: no median for benchmark '{name}' in {path}")

def ms(r, key="cpu_time"):
    scale = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}[r["time_unit"]]
    return r[key] * scale

TARGETS = {"780x580": 5.0, "1388x1038": 15.0}
source = os.environ["STRIA_BENCH_SOURCE"]
if source.endswith("-dirty"):
    source += " (the work tree had uncommitted changes)"
out = []
out.append(f"Measured {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC on {os.environ['STRIA_BENCH_CPU']}, "
           f"{os.environ['STRIA_BENCH_CORES']}; load average before the run {os.environ['STRIA_BENCH_LOAD']}; "
           f"{os.environ['STRIA_BENCH_COMPILER']}, Release; source git {source}. "
           f"Medians of {os.environ['STRIA_BENCH_REPETITIONS']} "
           "repetitions. Decode, Sobel and DP times are CPU time of the one thread that runs them (wall time "
           "in brackets: it includes time the scheduler gave to other processes).")
out.append("")
out.append("| frame | decode ms | target | decode / Sobel BGR | decode / Sobel grey | Sobel BGR ms | Sobel grey ms "
           "| DP ms | DP / decode | points | DP points | workspace B/px |")
out.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
# The camera's rows, then row pairs (DecoderParams::segmentRowPairs, the fast mode).
MODES = [("decode", ""), ("decodeRowPairs", ", row pairs")]
for (name, label), (size, target) in ((m, t) for m in MODES for t in TARGETS.items()):
    d, sb, sg, dp = get(f"{name}/{size}"), get(f"sobel/bgr_{size}"), get(f"sobel/grey_{size}"), get(f"dpBaseline/{size}")
    t = ms(d)
    verdict = "met" if t <= target else "MISSED"
    ratio = t / ms(sb)
    ratio_note = "" if size != "780x580" else (" (target <= 15: met)" if ratio <= 15 else " (target <= 15: MISSED)")
    bpp = d["bytes_per_pixel"]
    out.append(f"| {size}{label} | {t:.2f} ({ms(d, 'real_time'):.2f}) | <= {target:g} ms: {verdict} | {ratio:.1f}{ratio_note} "
               f"| {t / ms(sg):.1f} | {ms(sb):.3f} | {ms(sg):.3f} | {ms(dp):.1f} | {ms(dp) / t:.2f} "
               f"| {d['points']:.0f} | {dp['points']:.0f} | {bpp:.1f} (<= 32: {'met' if bpp <= 32 else 'MISSED'}) |")
out.append("")
out.append("Per stage (medians of the decoder's own StageTimings, wall clock, ms):")
out.append("")
stages = ["gradient", "watershed", "regions", "graph", "edges", "traversal", "depth", "total"]
out.append("| frame | " + " | ".join(stages) + " | superpixels | graph edges |")
out.append("|---|" + "---|" * (len(stages) + 2))
for (name, label), size in ((m, s) for m in MODES for s in TARGETS):
    d = get(f"{name}/{size}")
    out.append(f"| {size}{label} | " + " | ".join(f"{d['ms_' + s]:.2f}" for s in stages) +
               f" | {d['superpixels']:.0f} | {d['graph_edges']:.0f} |")
out.append("")
out.append("Each stage alone (`stage/<stage>_<size>`: Decoder::repeatStage after the earlier stages, which run "
           "with the timer paused; a run of its own, 50 ms of timed work per repetition, with the Sobel BGR "
           "reference interleaved again; CPU time, ms, and in that run's Sobel BGR passes):")
out.append("")
out.append("| frame | " + " | ".join(stages[:-1]) + " | sum |")
out.append("|---|" + "---|" * len(stages))
for size in TARGETS:
    sb = ms(get(f"sobel/bgr_{size}", stage_run))
    alone = [ms(get(f"stage/{s}_{size}", stage_run)) for s in stages[:-1]]
    out.append(f"| {size} | " + " | ".join(f"{t:.2f} ({t / sb:.1f})" for t in alone) +
               f" | {sum(alone):.2f} ({sum(alone) / sb:.1f}) |")
out.append("")
out.append("Video mode (`Streamer` over a `ReplayCamera` of 4 pre-rendered 780x580 frames, 3 frame slots, "
           "3 s per repetition; medians of 3 repetitions):")
out.append("")
out.append("| camera rate | decoded fps | dropped | missed | decode thread busy | sustained |")
out.append("|---|---|---|---|---|---|")
for fps in (30, 60):
    s = get(f"stream/780x580_{fps}fps")
    sustained = s["dropped"] == 0 and s["missed"] == 0 and s["fps"] >= 0.97 * fps
    out.append(f"| {fps} fps | {s['fps']:.1f} | {s['dropped']:.0f} of {s['captured']:.0f} | {s['missed']:.0f} "
               f"| {100 * s['decode_busy']:.0f}% | {'yes' if sustained else 'NO'} |")

begin, end = "<!-- bench:begin -->", "<!-- bench:end -->"
doc = open(doc_path).read()
if begin not in doc or end not in doc:
    sys.exit(f"run-benchmarks.sh: {doc_path} lacks the {begin} / {end} markers")
head, rest = doc.split(begin, 1)
tail = rest.split(end, 1)[1]
tmp = doc_path + ".tmp"
with open(tmp, "w") as f:
    f.write(head + begin + "\n" + "\n".join(out) + "\n" + end + tail)
os.replace(tmp, doc_path)
print(f"run-benchmarks.sh: wrote the tables of {doc_path}")
EOF
