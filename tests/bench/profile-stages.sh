#!/bin/sh
# Instructions per decode() and stage, by callgrind: the profile table of
# docs/performance.md ("Where the time goes"). Instruction counts do not
# depend on the load of a shared machine, so they compare variants where
# times cannot.
#
#   tests/bench/profile-stages.sh [BUILD_DIR]    (default: build/host, the host preset)
#
# Renders the benchmark's frames (relief, coloured albedo, noise 4, seed 1, at
# 780x580 and 1388x1038), decodes each twice under valgrind's callgrind with
# collection on inside Decoder::decode only, and prints one markdown table
# row per stage: inclusive instructions per decode (a stage with its kernels)
# and per pixel. Takes about a minute.
set -eu

build=${1:-build/host}
stria=$build/firmware/stria
if [ ! -x "$stria" ]; then
    echo "profile-stages: no $stria; build it first (cmake --preset host && cmake --build --preset host)" >&2
    exit 1
fi
for tool in valgrind callgrind_annotate; do
    command -v "$tool" >/dev/null || { echo "profile-stages: $tool is missing (apt-get install valgrind)" >&2; exit 1; }
done

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# stage label, function name (inclusive counts include its kernels)
stages='gradient computeGradient
watershed computeWatershed
regions computeRegions
graph buildGraph
edges computeEdgeFeatures
traversal decodeStripes
depth computePoints
total Decoder::decode'

for rig in desktop desktop-large; do
    dir=$work/$rig
    mkdir -p "$dir"
    "$stria" render --scene relief --rig "$rig" --albedo coloured --noise 4 --seed 1 --out "$dir/frame.png" \
        --calib-out "$dir/calib.yaml" --pattern-out "$dir/pattern.yaml" >/dev/null
    echo "profile-stages: $rig frame under callgrind..." >&2
    valgrind --tool=callgrind --callgrind-out-file="$dir/callgrind.out" \
        --toggle-collect='stria::pipeline::Decoder::decode*' \
        "$stria" decode --calib "$dir/calib.yaml" --pattern "$dir/pattern.yaml" --image "$dir/frame.png" \
        --ply "$dir/out.ply" --repeat 2 >/dev/null 2>"$dir/valgrind.log" ||
        { cat "$dir/valgrind.log" >&2; exit 1; }
    callgrind_annotate --inclusive=yes --threshold=100 "$dir/callgrind.out" >"$dir/annotate.txt"
    # Frame size from the PNG header (width, height: big-endian at byte 16).
    set -- $(od -An -tu1 -j16 -N8 "$dir/frame.png")
    echo $((($1 << 24) | ($2 << 16) | ($3 << 8) | $4)) $((($5 << 24) | ($6 << 16) | ($7 << 8) | $8)) >"$dir/size"
done

size() { cat "$work/$1/size"; }
read w1 h1 <<EOF
$(size desktop)
EOF
read w2 h2 <<EOF
$(size desktop-large)
EOF

echo "| stage (function) | ${w1}x${h1} | per pixel | ${w2}x${h2} | per pixel |"
echo "|---|---|---|---|---|"
echo "$stages" | while read -r label function; do
    row="| $label (\`$function\`)"
    for rig in desktop desktop-large; do
        read w h <<EOF
$(size $rig)
EOF
        # Inclusive Ir of the function's lines (all overloads and clones),
        # over the 2 decodes.
        ir=$(grep -E "stria::pipeline::$function[ (]" "$work/$rig/annotate.txt" |
             awk '{ gsub(",", "", $1); s += $1 } END { print s + 0 }')
        row="$row | $(awk -v ir="$ir" 'BEGIN { printf "%.1f M", ir / 2 / 1e6 }') | $(awk -v ir="$ir" -v n=$((w * h)) 'BEGIN { printf "%.0f", ir / 2 / n }')"
    done
    echo "$row |"
done
