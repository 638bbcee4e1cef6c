#!/bin/sh
# Cross-builds stria for arm64 and runs the test suite under qemu-aarch64,
# then checks that x86-64 and arm64 decode the same point clouds.
#   cross/test-arm64.sh [PRESET]    PRESET: arm64 (default), arm64-a53/a72/a76
# The whole suite runs, the decoder quality targets and the 1000-scan soak
# included (measured under qemu: the quality tests ~28x their native time,
# the soak 30 s).
# Uses the presets' build directories (build/PRESET, build/host). Exit status:
# ctest's, or 1 if stria does not start under qemu or the clouds differ.
set -eu
cd "$(dirname "$0")/.."
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
ctest --preset "$preset" --parallel "$jobs" || status=$?
cross/compare-arm64.sh build/host/firmware/stria "build/$preset/firmware/stria" ||
	{ [ $status -ne 0 ] || status=1; }
exit $status
