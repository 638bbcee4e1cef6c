#!/bin/sh
# Runs a command in which arm64 programs execute directly (through
# qemu-aarch64-static), as chroot, dpkg and mmdebstrap need:
#   cross/with-arm64-binfmt.sh COMMAND [ARGS...]
# If the machine has no binfmt_misc entry for arm64 (containers, CI), the
# command runs in a private user and mount namespace with its own
# binfmt_misc instance (Linux >= 6.7), so the machine's own registrations are
# never touched. Needs root (uids and gids 0-65535 map onto themselves).
set -eu
[ $# -ge 1 ] || { echo "usage: $0 COMMAND [ARGS...]" >&2; exit 2; }

qemu=/usr/bin/qemu-aarch64-static
if [ ! -x $qemu ]; then
	echo "$0: $qemu missing (cross/install-deps.sh rootfs)" >&2
	exit 1
fi
if [ -e /proc/sys/fs/binfmt_misc/qemu-aarch64 ]; then
	exec "$@"
fi
if [ "${STRIA_BINFMT_NS:-}" != 1 ]; then
	# unshare's --map-users needs newuidmap and /etc/subuid entries; as root
	# we write the identity map for uids and gids 0-65535 ourselves, then
	# let the namespace go on.
	go=$(mktemp -u)
	mkfifo "$go"
	STRIA_BINFMT_NS=1 unshare --user --mount --propagation private --pid --fork \
		sh -c 'read -r _ <"$0" && exec "$@"' "$go" "$0" "$@" &
	ns=$!
	while [ "$(readlink /proc/$ns/ns/user)" = "$(readlink /proc/$$/ns/user)" ]; do
		sleep 0.1
	done
	echo "0 0 65536" >/proc/$ns/uid_map
	echo "0 0 65536" >/proc/$ns/gid_map
	echo go >"$go"
	rm "$go"
	status=0
	wait $ns || status=$?
	exit $status
fi

# Inside the namespace: a fresh binfmt_misc instance, arm64 ELF -> qemu. The
# F flag opens qemu now, so it also runs inside chroots that lack it.
mount -t binfmt_misc binfmt_misc /proc/sys/fs/binfmt_misc
magic='\x7fELF\x02\x01\x01\x00\x00\x00\x00\x00\x00\x00\x00\x00\x02\x00\xb7\x00'
mask='\xff\xff\xff\xff\xff\xff\xff\x00\xff\xff\xff\xff\xff\xff\xff\xff\xfe\xff\xff\xff'
printf '%s' ":qemu-aarch64:M::$magic:$mask:$qemu:FP" >/proc/sys/fs/binfmt_misc/register
# A /proc of the new pid namespace, for the command's own chroots to bind.
mount -t proc proc /proc
exec "$@"
