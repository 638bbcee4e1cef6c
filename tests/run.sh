#!/usr/bin/env bash
# Installs what the tests need (Debian packages), builds stria for the host
# and for arm64, runs the whole test suite on both (arm64 under qemu-user),
# and compiles the pipeline for 32-bit ARM (cross/check-armhf.sh).
# Idempotent; quick when nothing changed.
#
#   tests/run.sh              host + arm64 (what CI runs)
#   tests/run.sh --host-only  host only
#
# Runs as root, or as a user with sudo for the package installation.
set -euo pipefail
cd "$(dirname "$0")/.."

host_only=0
for arg in "$@"; do
  case "$arg" in
    --host-only) host_only=1 ;;
    -h|--help) sed -n '2,10p' "$0"; exit 0 ;;
    *) echo "tests/run.sh: unknown option '$arg'" >&2; exit 2 ;;
  esac
done

step() { printf '\n==> %s\n' "$*"; }
start=$(date +%s)

step "installing Debian packages"
if [ "$host_only" = 1 ]; then cross/install-deps.sh host; else cross/install-deps.sh all; fi

step "host build (preset 'host')"
cmake --preset host
cmake --build --preset host

step "host tests"
ctest --preset host

if [ "$host_only" = 0 ]; then
  step "arm64 build and tests under qemu-aarch64"
  cross/test-arm64.sh
  step "32-bit ARM (armv7-a NEON): the pipeline compiles"
  cross/check-armhf.sh
fi

step "all tests passed in $(( $(date +%s) - start )) s"
