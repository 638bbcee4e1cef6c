#!/bin/sh
# Builds a flashable Debian 12 arm64 root file system for a Raspberry Pi
# (3, Zero 2 W, 4, 400, CM4: Debian 12's kernel has no Pi 5 or CM5 support)
# with stria installed and its service enabled:
#   cross/make-rootfs.sh STRIA_DEB OUTDIR
# Writes OUTDIR/rootfs/ (the tree), OUTDIR/rootfs.tar, OUTDIR/rootfs.ext4 (the
# root partition, labelled RASPIROOT as in Debian's Raspberry Pi images) and
# OUTDIR/firmware/ (the FAT boot partition's files: kernel, initramfs, device
# trees, config.txt).
# Slow (downloads ~350 MB, runs dpkg under qemu; ~20 minutes): not part of
# CI. cross/smoke-rootfs.sh OUTDIR/rootfs checks the result.
# docs/flashing.md describes writing it to an SD card.
set -eu
if [ $# -ne 2 ]; then
	echo "usage: $0 STRIA_DEB OUTDIR" >&2
	exit 2
fi
deb=$(realpath "$1")
out=$2
mirror=${STRIA_DEBIAN_MIRROR:-http://deb.debian.org/debian}
cross=$(dirname "$(realpath "$0")")
[ -f "$deb" ] || { echo "$0: $1: no such package (cross/package-arm64.sh builds it)" >&2; exit 1; }
if [ -e "$out/rootfs" ]; then
	echo "$0: $out/rootfs exists: remove it first" >&2
	exit 1
fi
mkdir -p "$out"
out=$(realpath "$out")

# The stria package is installed last, by apt inside the root file system
# (dpkg cannot reach a .deb outside it), which fetches its dependencies.
# Debian's kernel and the Raspberry Pi boot firmware (raspi-firmware copies
# kernel, initramfs and device trees to /boot/firmware on every kernel
# update) and initramfs-tools' recommends, which mmdebstrap leaves out:
# zstd (its default compression) and busybox (the initramfs' rescue shell);
# e2fsprogs (fsck.ext4 for the root, not in the apt variant);
# systemd-networkd with DHCP on eth0, ssh for the first login.
packages=systemd-sysv,udev,kmod,linux-image-arm64,raspi-firmware,firmware-brcm80211
packages=$packages,busybox,zstd,e2fsprogs,openssh-server,systemd-timesyncd,iproute2,sudo

# The initramfs is generated once, by the last hook: under qemu that takes
# ~9 minutes (MODULES=most: every storage and file system driver, as the
# board's hardware cannot be detected here), and during the installation
# both the kernel's hook and initramfs-tools' trigger would generate it.
# INITRD=No makes the kernel's hook skip it; the trigger then finds no
# initramfs to update. update-initramfs -c then runs raspi-firmware's hook,
# which copies kernel, initramfs and device trees to /boot/firmware and
# writes config.txt and cmdline.txt with ROOTPART and CONSOLES from
# /etc/default/raspi-firmware: the root by label (the SD card is mmcblk0 or
# mmcblk1 depending on the model), consoles on HDMI and the serial port, as
# the hook detects them when it runs again on the board (kernel updates), and
# no cma= (the hook adds cma=64M unless it runs on a Pi 4, which that stops
# booting; the kernel's default is 64 MB anyway). FSTYPE=ext4: the root's
# type cannot be detected from fstab's label here, and without it the
# initramfs gets no fsck.ext4 and never checks the root file system.
raspi_defaults='s|^#ROOTPART=.*|ROOTPART=LABEL=RASPIROOT|; s|^#CONSOLES=.*|CONSOLES="tty0 ttyS1,115200"|; s|^#CMA=.*|CMA=0|'
INITRD=No "$cross/with-arm64-binfmt.sh" mmdebstrap --mode=root --architectures=arm64 --variant=apt \
	--components="main non-free-firmware" --include="$packages" \
	--customize-hook="copy-in $deb /tmp" \
	--customize-hook="chroot \"\$1\" apt-get install --yes --no-install-recommends /tmp/$(basename "$deb")" \
	--customize-hook='rm "$1"/tmp/stria_*.deb' \
	--customize-hook='echo stria > "$1/etc/hostname"' \
	--customize-hook='printf "LABEL=RASPIROOT / ext4 rw,noatime 0 1\nLABEL=RASPIFIRM /boot/firmware vfat rw,nofail 0 2\n" > "$1/etc/fstab"' \
	--customize-hook='printf "[Match]\nName=e*\n\n[Network]\nDHCP=yes\n" > "$1/etc/systemd/network/50-wired.network"' \
	--customize-hook='chroot "$1" systemctl enable systemd-networkd ssh stria' \
	--customize-hook='chroot "$1" systemctl is-enabled stria' \
	--customize-hook='echo "root:stria" | chroot "$1" chpasswd' \
	--customize-hook="sed -i '$raspi_defaults' \"\$1/etc/default/raspi-firmware\"" \
	--customize-hook='grep -x ROOTPART=LABEL=RASPIROOT "$1/etc/default/raspi-firmware"' \
	--customize-hook='sed -i "s/^FSTYPE=auto\$/FSTYPE=ext4/" "$1/etc/initramfs-tools/initramfs.conf"' \
	--customize-hook='grep -x FSTYPE=ext4 "$1/etc/initramfs-tools/initramfs.conf"' \
	--customize-hook='chroot "$1" update-initramfs -c -k all' \
	bookworm "$out/rootfs" \
	"deb $mirror bookworm main non-free-firmware" \
	"deb $mirror bookworm-updates main non-free-firmware" \
	"deb ${mirror%/debian}/debian-security bookworm-security main non-free-firmware"

mkdir -p "$out/firmware"
cp -a "$out/rootfs/boot/firmware/." "$out/firmware/"
tar -C "$out/rootfs" --numeric-owner -cf "$out/rootfs.tar" .
size_mb=$(( $(du -sm "$out/rootfs" | cut -f1) * 13 / 10 + 256 ))
mke2fs -q -t ext4 -L RASPIROOT -d "$out/rootfs" "$out/rootfs.ext4" "${size_mb}M"
echo "$out/rootfs.ext4: root partition (${size_mb} MB), $out/firmware: boot partition files"
