#!/bin/sh
# Smoke test of a root file system from make-rootfs.sh, run inside the tree
# under qemu (chroot: its own loader, libraries and tools):
#   cross/smoke-rootfs.sh ROOTFS_DIR
# Checks what the package's maintainer scripts must have done (user stria in
# groups video and gpio, conffile, service enabled, udev rules), the boot
# partition's files (kernel, initramfs with the SD card and ext4 drivers,
# config.txt, cmdline.txt), and scans once with the installed program and
# /etc/stria/board.yaml as the service does: as user stria, its groups only.
# Exit status: 0 all checks passed, 1 a check failed (each one is printed),
# 2 usage.
set -eu
if [ $# -ne 1 ] || [ ! -x "$1/usr/bin/stria" ]; then
	echo "usage: $0 ROOTFS_DIR   (a tree with /usr/bin/stria, from make-rootfs.sh)" >&2
	exit 2
fi
root=$(realpath "$1")
if [ "${STRIA_SMOKE_INSIDE:-}" != 1 ]; then
	# chroot, not qemu -L: the loader and libc must come from the same glibc
	# build (docs/cross.md).
	STRIA_SMOKE_INSIDE=1 exec "$(dirname "$(realpath "$0")")/with-arm64-binfmt.sh" "$0" "$root"
fi

# Our own mount namespace (with-arm64-binfmt.sh, or unshared here when the
# machine registers arm64 itself): the binds vanish with the test.
if [ "${STRIA_SMOKE_UNSHARED:-}" != 1 ] && [ -z "${STRIA_BINFMT_NS:-}" ]; then
	STRIA_SMOKE_UNSHARED=1 exec unshare --mount --propagation private "$0" "$root"
fi
mount --rbind /dev "$root/dev"
mount --bind /proc "$root/proc"
# A hung emulator ignores SIGTERM (docs/cross.md), hence SIGKILL.
in_root() { timeout -s KILL 300 chroot "$root" "$@"; }

failures=0
check() { # DESCRIPTION COMMAND...: COMMAND must succeed (its output is not shown)
	what=$1
	shift
	if "$@" >/dev/null 2>&1; then
		echo "ok: $what"
	else
		echo "FAILED: $what" >&2
		failures=$((failures + 1))
	fi
}
has_word() { # WORD TEXT: TEXT (words) contains WORD
	case " $2 " in *" $1 "*) return 0 ;; *) return 1 ;; esac
}

# What the maintainer scripts (cross/deb/postinst) did in the chroot.
groups=$(in_root id -nG stria 2>&1) || true
check "user stria exists" in_root id -u stria
check "stria in group video" has_word video "$groups"
check "stria in group gpio" has_word gpio "$groups"
check "/etc/stria/board.yaml present" test -f "$root/etc/stria/board.yaml"
conffiles=$(in_root dpkg-query -W -f='${Conffiles}' stria 2>&1) || true
check "/etc/stria/board.yaml is a conffile" has_word /etc/stria/board.yaml "$conffiles"
enabled=$(in_root systemctl is-enabled stria.service 2>&1) || true
check "systemctl is-enabled stria: $enabled" test "$enabled" = enabled
check "udev rules /usr/lib/udev/rules.d/60-stria.rules" \
	test -f "$root/usr/lib/udev/rules.d/60-stria.rules"

# The boot partition's files (raspi-firmware's kernel hook copies them).
firmware=$root/boot/firmware
kernel=$(cd "$root/boot" && ls vmlinuz-* | sort -V | tail -1) || true
initrd=initrd.img-${kernel#vmlinuz-}
check "$kernel and $initrd in /boot/firmware, same as in /boot" \
	sh -c "cmp -s '$root/boot/$kernel' '$firmware/$kernel' && cmp -s '$root/boot/$initrd' '$firmware/$initrd'"
check "config.txt boots $kernel with $initrd" sh -c \
	"grep -qx 'kernel=$kernel' '$firmware/config.txt' && grep -qx 'initramfs $initrd' '$firmware/config.txt'"
check "cmdline.txt: root=LABEL=RASPIROOT" grep -q 'root=LABEL=RASPIROOT ' "$firmware/cmdline.txt"
check "cmdline.txt: no cma= (raspi-firmware omits it on a Pi 4)" sh -c "! grep -q cma= '$firmware/cmdline.txt'"
check "device trees of Pi 3 and Pi 4, GPU firmware" sh -c \
	"cd '$firmware' && test -f bcm2837-rpi-3-b.dtb -a -f bcm2711-rpi-4-b.dtb -a -f start4.elf -a -f start.elf"
# The initramfs must check and mount the root partition: the SD card
# drivers (Pi 3, Pi 4), ext4 and fsck.ext4 inside, busybox for a rescue
# shell, and it must unpack (lsinitramfs reads it all).
listing=$(in_root lsinitramfs "/boot/$initrd" 2>&1) || true
for file in kernel/drivers/mmc/host/bcm2835.ko kernel/drivers/mmc/host/sdhci-iproc.ko \
	kernel/fs/ext4/ext4.ko sbin/fsck.ext4 bin/busybox; do
	check "initramfs has .../$file" sh -c 'printf "%s\n" "$1" | grep -q "/$2\$"' sh "$listing" "$file"
done

# One scan with the service's board file, user and groups.
out=$(mktemp -d "$root/tmp/smoke.XXXXXX")
in_root chown stria:stria "/tmp/${out##*/}" || true # no user stria: reported above
status=0
in_root setpriv --reuid=stria --regid=stria --init-groups --reset-env \
	/usr/bin/stria scan --board /etc/stria/board.yaml --once --out "/tmp/${out##*/}" || status=$?
check "stria scan --once exit status $status" test $status -eq 0
scan=$(ls -d "$out"/scan-*/ 2>/dev/null | head -1) || true
scan=${scan:-$out/no-scan-folder/}
check "scan folder with points.ply, depth.tiff, preview.png, scan.json" \
	test -f "${scan}points.ply" -a -f "${scan}depth.tiff" -a -f "${scan}preview.png" -a -f "${scan}scan.json"
check "scan.json: status ok" grep -q '"status": "ok"' "${scan}scan.json"
# The simulated fingertip frame decodes to about 63000 points (and arm64
# decodes what x86-64 does, cross/compare-arm64.sh); far fewer means the
# decoder or its pattern and calibration files are broken.
points=$(sed -n 's/^element vertex //p;/^end_header/q' "${scan}points.ply" 2>/dev/null) || true
check "point cloud of ${points:-no} points (at least 50000)" test "${points:-0}" -ge 50000
rm -rf "$out"

if [ $failures -ne 0 ]; then
	echo "$0: $failures check(s) failed in $root" >&2
	exit 1
fi
echo "$0: all checks passed in $root"
