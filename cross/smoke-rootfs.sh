#!/bin/sh
# Smoke test of a root file system from make-rootfs.sh: one simulated scan
# with the installed program, board files and libraries, inside the tree.
#   cross/smoke-rootfs.sh ROOTFS_DIR
# Exit status: stria's (0: the scan succeeded and its results were written).
set -eu
if [ $# -ne 1 ] || [ ! -x "$1/usr/bin/stria" ]; then
	echo "usage: $0 ROOTFS_DIR   (a tree with /usr/bin/stria, from make-rootfs.sh)" >&2
	exit 2
fi
root=$(realpath "$1")
cross=$(dirname "$(realpath "$0")")

# chroot, not qemu -L: the loader and libc must come from the same glibc
# build (docs/cross.md). The results go to a fresh folder inside the tree.
"$cross/with-arm64-binfmt.sh" sh -c '
	root=$1
	out=$(mktemp -d "$root/tmp/smoke.XXXXXX")
	status=0
	timeout -s KILL 300 chroot "$root" /usr/bin/stria scan \
		--board /usr/share/stria/board/sim/board.yaml --once --out "/tmp/${out##*/}" || status=$?
	ls "$out"/scan-*/ 2>/dev/null
	rm -rf "$out"
	exit $status' sh "$root"
