#!/usr/bin/env bash
# The main job on a laptop: installs what stria needs (Debian packages),
# builds it, and runs one scan with the simulated head (simulated camera,
# projector LED and button press). Prints where the point cloud, depth map
# and colour-coded depth picture are. Idempotent; quick when nothing changed.
#
#   firmware/demo.sh [BOARD.yaml] [OUTPUT_DIR]
#
# Runs as root, or as a user with sudo for the package installation.
set -euo pipefail
cd "$(dirname "$0")/.."
board=${1:-board/sim/board.yaml}
out=${2:-out/demo}

cross/install-deps.sh host
cmake --preset host >/dev/null
cmake --build --preset host --target stria
mkdir -p "$out"
echo
exec build/host/firmware/stria scan --board "$board" --once --out "$out"
