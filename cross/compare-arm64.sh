#!/bin/sh
# Decodes the same simulated frames with the x86-64 and the arm64 build of
# stria and checks that both give the same point cloud: the same number of
# points, the same pattern edge for each, and coordinates within 1e-3 mm.
#   cross/compare-arm64.sh HOST_STRIA ARM64_STRIA
# The frames are rendered once, by the host build, so only decoding differs.
# Exit status: 0 same clouds, 1 a difference or a failed command, 2 usage.
set -eu

if [ $# -ne 2 ]; then
	echo "usage: $0 HOST_STRIA ARM64_STRIA" >&2
	exit 2
fi
host=$1
arm64=$2
for program in "$host" "$arm64"; do
	if [ ! -x "$program" ]; then
		echo "$0: $program: no such executable (build it first)" >&2
		exit 1
	fi
done
# A hung emulator ignores SIGTERM (docs/cross.md), hence SIGKILL.
emulator="timeout -s KILL 600 ${STRIA_EMULATOR:-qemu-aarch64}"
tolerance_mm=0.001

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# Scenes chosen to reach every decoder stage: coloured albedo and depth
# steps (relief), sensor noise on a curved surface (sphere), and the
# fingerprint rig's own geometry (fingertip); the relief again with the
# segmentation on row pairs (decode options after a '|').
status=0
for case in "relief" "sphere --noise 3 --seed 7" "fingertip --noise 2" "relief|--row-pairs"; do
	render=${case%%|*}
	options=
	[ "$render" != "$case" ] && options=${case#*|}
	name=${render%% *}${options:+-rowpairs}
	dir=$work/$name
	mkdir "$dir"
	# shellcheck disable=SC2086 # $render holds the scene and its options
	"$host" render --scene $render --out "$dir/frame.png" \
		--calib-out "$dir/calib.yaml" --pattern-out "$dir/pattern.yaml" >/dev/null
	decode="decode --calib $dir/calib.yaml --pattern $dir/pattern.yaml --image $dir/frame.png --ascii $options"
	"$host" $decode --ply "$dir/host.ply" >/dev/null
	$emulator "$arm64" $decode --ply "$dir/arm64.ply" >/dev/null

	if ! awk -v tolerance="$tolerance_mm" -v scene="$name" '
		function abs(v) { return v < 0 ? -v : v }
		FNR == 1 { inBody = 0 }
		/^element vertex/ { count[FILENAME == ARGV[1]] = $3 }
		!inBody { if ($0 == "end_header") inBody = 1; next }
		FILENAME == ARGV[1] { x[FNR] = $1; y[FNR] = $2; z[FNR] = $3; edge[FNR] = $6; next }
		{
			if (!(FNR in x)) { extra++; next }
			d = abs($1 - x[FNR]); if (abs($2 - y[FNR]) > d) d = abs($2 - y[FNR])
			if (abs($3 - z[FNR]) > d) d = abs($3 - z[FNR])
			if (d > worst) worst = d
			if (d > tolerance || $6 != edge[FNR]) bad++
		}
		END {
			printf "%s: x86-64 %d points, arm64 %d points, %d differ, max |dx,dy,dz| %.3g mm\n",
				scene, count[1], count[0], bad + extra, worst
			exit !(count[1] == count[0] && count[1] > 0 && bad + extra == 0)
		}' "$dir/host.ply" "$dir/arm64.ply"; then
		status=1
	fi
done
[ $status -eq 0 ] && echo "x86-64 and arm64 point clouds agree within $tolerance_mm mm" ||
	echo "$0: x86-64 and arm64 point clouds differ" >&2
exit $status
