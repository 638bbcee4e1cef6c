#!/bin/sh
# Cross-builds stria for arm64 and runs the test suite under qemu-aarch64,
# then checks that x86-64 and arm64 decode the same point clouds.
#   cross/test-arm64.sh [--all] [PRESET]    PRESET: arm64 (default), arm64-a53/a72/a76
# Tests labelled quality or soak (whole-scene decoder metrics, 1000-scan
# soak) are left out unless --all: under qemu they take most of an hour,
# and the comparison below already proves arm64 decodes exactly like x86-64,
# whose run checks those metrics.
# Uses the presets' build directories (build/PRESET, build/host). Exit status:
# ctest's, or 1 if stria does not start under qemu or the clouds differ.
set -eu
cd "$(dirname "$0")/.."
skip_labels="-LE quality|soak"
if [ "${1:-}" = --all ]; then
	skip_labels=""
	shift
fi
preset=${1:-arm64}
jobs=${CTEST_PARALLEL_LEVEL:-$(nproc)}

cmake --preset "$preset"
cmake --build --preset "$preset"
# The host program for the comparison, built now from the same sources:
# reuses CI's host build, or builds just the program.
if [ ! -x build/host/firmware/stria ]; then
	cmake --preset host >/dev/null
fi
cmake --build --preset host --target stria

# Start-up check first: a binary that hangs in qemu would otherwise cost
# every test its whole timeout. SIGKILL because a hung qemu ignores SIGTERM.
if ! timeout -s KILL 60 qemu-aarch64 "build/$preset/firmware/stria" --version; then
	echo "$0: build/$preset/firmware/stria does not start under qemu-aarch64 (see docs/cross.md)" >&2
	exit 1
fi

status=0
# shellcheck disable=SC2086 # $skip_labels is two words or none
ctest --preset "$preset" --parallel "$jobs" $skip_labels || status=$?
cross/compare-arm64.sh build/host/firmware/stria "build/$preset/firmware/stria" ||
	{ [ $status -ne 0 ] || status=1; }
exit $status
