#!/bin/sh
# Compiles the decoder (pipeline/: core, decoder, DP baseline) for 32-bit ARM
# (armv7-a, hard float, NEON): the 32-bit OS images of Cortex-A53/A72 boards.
# Compile only: Debian's armhf package index is broken on our mirror, so the
# armhf OpenCV libraries cannot be installed and nothing can be linked. The
# cross compiler (g++-arm-linux-gnueabihf) comes from the amd64 index, and
# the pipeline needs only headers that do not depend on the architecture
# (OpenCV's and Eigen's), so every source is compiled to an object, with the
# same warnings as the real builds and errors. This catches AArch64-only NEON
# intrinsics (vaddv, vuzp1q, the *_high_* forms, ...) used under __ARM_NEON,
# which 32-bit NEON lacks: such code must be under __aarch64__. Warnings
# are errors here: one only 32-bit code raises is usually a bug on those
# boards (a shift by 63 of std::ptrdiff_t, 32 bits there). -Wno-restrict:
# GCC 12 reports a false overlap in std::string's inlined memcpy on 32-bit
# targets (GCC bug 105329), not in our code.
#
#   cross/check-armhf.sh          (tests/run.sh runs it; about a minute)
set -eu
cd "$(dirname "$0")/.."

cxx=arm-linux-gnueabihf-g++
if ! command -v "$cxx" >/dev/null; then
	echo "$0: $cxx not found: run cross/install-deps.sh armhf-compile" >&2
	exit 1
fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

failed=0
count=0
for src in pipeline/*.cpp pipeline/decoder/*.cpp pipeline/dp/*.cpp; do
	count=$((count + 1))
	obj=$out/$(echo "$src" | tr / _).o
	if ! "$cxx" -std=c++20 -O3 -DNDEBUG -march=armv7-a -mfpu=neon-vfpv4 -mfloat-abi=hard -ffp-contract=off \
		-Wall -Wextra -Wpedantic -Werror -Wno-psabi -Wno-restrict -I. -isystem /usr/include/opencv4 -isystem /usr/include/eigen3 \
		-c "$src" -o "$obj"; then
		echo "$0: $src does not compile for armv7-a NEON" >&2
		failed=$((failed + 1))
	fi
done
if [ "$failed" -ne 0 ]; then
	echo "$0: $failed of $count pipeline sources failed to compile for armhf" >&2
	exit 1
fi
echo "$0: all $count pipeline sources compile for armv7-a NEON (hard float)"
