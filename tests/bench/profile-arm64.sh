#!/bin/sh
# Instructions per decode() and stage of the arm64 build, counted under
# qemu-aarch64: the ARM column of docs/performance.md ("ARM (arm64)").
# valgrind does not run arm64 code on an x86-64 machine; qemu-user can log
# every translation block it translates (-d in_asm) and every time one runs
# (-d exec,nochain), and count_tb_instructions.py sums the two: the guest
# (AArch64) instructions executed, exactly, with the NEON kernels the board
# runs. Not a time: qemu's speed says nothing about a Cortex core's.
#
#   tests/bench/profile-arm64.sh [ARM64_BUILD_DIR] [HOST_STRIA]
#       (defaults: build/arm64, the arm64 preset; build/host/firmware/stria)
#
# PROFILE_DECODE_OPTIONS adds options to the decodes, e.g. --row-pairs for
# the fast mode (docs/algorithm.md "Row pairs").
#
# The same count for an x86-64 build, to check the method against callgrind
# (tests/bench/profile-stages.sh):
#   PROFILE_EMULATOR='qemu-x86_64 -cpu max' PROFILE_NM=nm tests/bench/profile-arm64.sh build/host
#
# Renders the benchmark's frames with the host build (relief, coloured
# albedo, noise 4, seed 1, desktop and desktop-large rigs: 780x580 and
# 1388x1038), decodes each with the arm64 build under qemu once and three
# times (--repeat), and takes half the difference: the instructions of one
# decode, without start-up, image reading and output. Stages are split in
# the order the code ran: from the entry of a stage's function to the entry
# of the next (so "depth" also holds decode()'s few instructions after
# computePoints). Prints one markdown table row per stage. The log passes
# through a FIFO, not the disk (about 1 GB per run); about 5 minutes in all.
set -eu

build=${1:-build/arm64}
host=${2:-build/host/firmware/stria}
stria=$build/firmware/stria
here=$(cd "$(dirname "$0")" && pwd)
for program in "$stria" "$host"; do
    if [ ! -x "$program" ]; then
        echo "profile-arm64: no $program; build it first (cmake --preset arm64 && cmake --build --preset arm64 --target stria; the same for host)" >&2
        exit 1
    fi
done
emulator=${PROFILE_EMULATOR:-qemu-aarch64}
nm=${PROFILE_NM:-aarch64-linux-gnu-nm}
for tool in ${emulator%% *} $nm; do
    command -v "$tool" >/dev/null || { echo "profile-arm64: $tool is missing (cross/install-deps.sh arm64)" >&2; exit 1; }
done
python=/usr/bin/python3
[ -x "$python" ] || python=python3

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# Stage label, function (demangled name up to its parameters). Decoder::decode
# marks the start of each decode: its own work before the gradient (the frame
# checks) is "decode".
$nm -C "$stria" | awk '
    $3 == "_start" { print "_start", $1 }
    / [Tt] / {
        name = $0; sub(/^[0-9a-f]+ [Tt] /, "", name); sub(/\(.*/, "", name)
        if (name == "stria::pipeline::Decoder::decode") print "decode", $1
        else if (name == "stria::pipeline::computeGradient") print "gradient", $1
        else if (name == "stria::pipeline::computeWatershed") print "watershed", $1
        else if (name == "stria::pipeline::computeRegions") print "regions", $1
        else if (name == "stria::pipeline::buildGraph") print "graph", $1
        else if (name == "stria::pipeline::computeEdgeFeatures") print "edges", $1
        else if (name == "stria::pipeline::decodeStripes") print "traversal", $1
        else if (name == "stria::pipeline::computePoints") print "depth", $1
    }' >"$work/stages"
for label in _start decode gradient watershed regions graph edges traversal depth; do
    grep -q "^$label " "$work/stages" || { echo "profile-arm64: no symbol for $label in $stria (stripped?)" >&2; exit 1; }
done

for rig in desktop desktop-large; do
    dir=$work/$rig
    mkdir -p "$dir"
    "$host" render --scene relief --rig "$rig" --albedo coloured --noise 4 --seed 1 --out "$dir/frame.png" \
        --calib-out "$dir/calib.yaml" --pattern-out "$dir/pattern.yaml" >/dev/null
    set -- $(od -An -tu1 -j16 -N8 "$dir/frame.png")
    echo $((($1 << 24) | ($2 << 16) | ($3 << 8) | $4)) $((($5 << 24) | ($6 << 16) | ($7 << 8) | $8)) >"$dir/size"
    for repeat in 1 3; do
        echo "profile-arm64: $rig frame, $repeat decode(s) under $emulator..." >&2
        mkfifo "$dir/log"
        "$python" "$here/count_tb_instructions.py" "$dir/log" --stages "$work/stages" >"$dir/count$repeat" &
        counter=$!
        # shellcheck disable=SC2086 # $emulator may hold options
        $emulator -d in_asm,exec,nochain -D "$dir/log" "$stria" decode --calib "$dir/calib.yaml" \
            --pattern "$dir/pattern.yaml" --image "$dir/frame.png" --ply "$dir/out.ply" --repeat $repeat ${PROFILE_DECODE_OPTIONS:-} \
            >/dev/null 2>"$dir/qemu.log" || { cat "$dir/qemu.log" >&2; exit 1; }
        wait $counter
        rm "$dir/log"
    done
done

# Per decode: (3 decodes - 1 decode) / 2, in millions, and per pixel.
read w1 h1 <"$work/desktop/size"
read w2 h2 <"$work/desktop-large/size"
awk -v w1="$w1" -v h1="$h1" -v w2="$w2" -v h2="$h2" '
    $1 == "stage" { n[FILENAME, $2] = $3 }
    END {
        f1 = ARGV[1]; f3 = ARGV[2]; g1 = ARGV[3]; g3 = ARGV[4]
        printf "| stage | %dx%d | per pixel | %dx%d | per pixel |\n|---|---|---|---|---|\n", w1, h1, w2, h2
        split("gradient watershed regions graph edges traversal depth decode", labels, " ")
        for (i = 1; i <= 8; ++i) {
            a = (n[f3, labels[i]] - n[f1, labels[i]]) / 2; b = (n[g3, labels[i]] - n[g1, labels[i]]) / 2
            ta += a; tb += b
            name = labels[i] == "decode" ? "decode() before the gradient" : labels[i]
            printf "| %s | %.1f M | %.0f | %.1f M | %.0f |\n", name, a / 1e6, a / (w1 * h1), b / 1e6, b / (w2 * h2)
        }
        printf "| **decode total** | **%.1f M** | **%.0f** | **%.1f M** | **%.0f** |\n", ta / 1e6, ta / (w1 * h1), tb / 1e6, tb / (w2 * h2)
    }' "$work/desktop/count1" "$work/desktop/count3" "$work/desktop-large/count1" "$work/desktop-large/count3"
