#!/bin/sh
# Install the Debian 12 packages stria needs.
#   cross/install-deps.sh host    native build, tests, benchmarks, plots, .deb packaging
#   cross/install-deps.sh arm64   arm64 cross build and its tests under qemu
#   cross/install-deps.sh rootfs  cross/make-rootfs.sh (flashable root file system)
#   cross/install-deps.sh armhf-compile  cross/check-armhf.sh (the 32-bit ARM compiler only)
#   cross/install-deps.sh all     host + arm64 + armhf-compile (what CI needs)
# Quick and silent when everything is installed: apt is only called for
# what is missing. Runs as root, or through sudo otherwise.
set -eu

# The package lists: the one place to add a dependency. Unqualified names
# are for the machine's own architecture; ":arm64" ones are cross libraries.
HOST_PACKAGES="
  cmake ninja-build g++ pkg-config
  libopencv-core-dev libopencv-imgproc-dev libeigen3-dev
  libcamera-dev libgpiod-dev linux-libc-dev libpng-dev libtiff-dev
  libgtest-dev libgmock-dev libbenchmark-dev umockdev libumockdev-dev
  python3-numpy python3-matplotlib
  dpkg-dev file systemd
"
ARM64_PACKAGES="
  crossbuild-essential-arm64 qemu-user libc6:arm64
  libopencv-core-dev:arm64 libopencv-imgproc-dev:arm64
  libcamera-dev:arm64 libgpiod-dev:arm64 libpng-dev:arm64 libtiff-dev:arm64
  libgtest-dev:arm64 libgmock-dev:arm64 libbenchmark-dev:arm64
"
# The armhf cross compiler is an amd64 package: no :armhf index needed.
ARMHF_COMPILE_PACKAGES="
  g++-arm-linux-gnueabihf
"
ROOTFS_PACKAGES="
  mmdebstrap arch-test qemu-user-static binfmt-support uidmap e2fsprogs
"

usage() {
	echo "usage: $0 host|arm64|armhf-compile|rootfs|all" >&2
	exit 2
}

[ $# -eq 1 ] || usage
case "$1" in
host) wanted=$HOST_PACKAGES ;;
arm64) wanted=$ARM64_PACKAGES ;;
armhf-compile) wanted=$ARMHF_COMPILE_PACKAGES ;;
rootfs) wanted=$ROOTFS_PACKAGES ;;
all) wanted="$HOST_PACKAGES $ARM64_PACKAGES $ARMHF_COMPILE_PACKAGES" ;;
*) usage ;;
esac

if [ "$(id -u)" -eq 0 ]; then
	as_root=""
elif command -v sudo >/dev/null; then
	as_root="sudo"
else
	echo "$0: must run as root (sudo is not installed)" >&2
	exit 1
fi

native=$(dpkg --print-architecture)
installed=$(dpkg-query -W -f='${db:Status-Abbrev} ${Package}:${Architecture}\n' |
	awk '$1 == "ii" { print $2 }')

missing=""
for package in $wanted; do
	case "$package" in
	*:*) candidates="$package" ;;
	*) candidates="$package:$native $package:all" ;;
	esac
	found=no
	for candidate in $candidates; do
		if printf '%s\n' "$installed" | grep -qxF "$candidate"; then
			found=yes
		fi
	done
	[ $found = yes ] || missing="$missing $package"
done

if [ -z "$missing" ]; then
	echo "$0 $1: all packages installed"
	exit 0
fi

case "$missing" in
*:arm64*)
	if ! dpkg --print-foreign-architectures | grep -qx arm64 && [ "$native" != arm64 ]; then
		$as_root dpkg --add-architecture arm64
	fi
	;;
esac

echo "$0 $1: installing$missing"
$as_root env DEBIAN_FRONTEND=noninteractive apt-get update -q
$as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends $missing
