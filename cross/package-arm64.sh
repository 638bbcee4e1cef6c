#!/bin/sh
# Builds the arm64 Debian package: build/PRESET/package/stria_VERSION_arm64.deb
#   cross/package-arm64.sh [PRESET]    PRESET: arm64 (default), arm64-a53/a72/a76
# Only the program is built (not the tests). Prints the package's control
# fields and contents, so the dependencies can be checked at a glance.
set -eu
cd "$(dirname "$0")/.."
preset=${1:-arm64}
build=build/$preset

cmake --preset "$preset"
cmake --build --preset "$preset" --target stria
# dpkg-shlibdeps finds the arm64 libraries through their multiarch ld.so.conf
# entry and reads the :arm64 packages' symbols files: Depends are arm64's.
cpack --config "$build/CPackConfig.cmake" -B "$build/package"

deb=$(ls "$build"/package/stria_*_arm64.deb)
dpkg-deb --info "$deb"
dpkg-deb --contents "$deb"
echo "$deb"
