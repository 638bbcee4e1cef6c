#!/bin/sh
# Builds the package with CPack and installs, upgrades, removes and purges it
# with dpkg --root into a scratch tree, running the maintainer scripts
# chrootless (DPKG_ROOT set, see cross/deb/postinst). Checks after each step
# what the scripts must have done there. Exit 0 all checks passed, 1 a check
# failed (each failure is printed), 77 skipped (not root: dpkg must chown).
#   tests/package/maintainer_scripts.sh BUILD/CPackConfig.cmake
set -eu
[ $# -eq 1 ] || { echo "usage: $0 BUILD/CPackConfig.cmake" >&2; exit 2; }
if [ "$(id -u)" -ne 0 ]; then
	echo "$0: skipped: dpkg --root must run as root" >&2
	exit 77
fi
for tool in cpack dpkg systemd-sysusers systemctl; do
	command -v $tool >/dev/null || { echo "$0: $tool not installed" >&2; exit 1; }
done

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cpack --config "$1" -B "$work/package" >"$work/cpack.log" 2>&1 ||
	{ cat "$work/cpack.log" >&2; echo "$0: cpack failed" >&2; exit 1; }
deb=$(ls "$work"/package/stria_*.deb)

# An empty Debian root: dpkg's database, and the accounts base-passwd ships
# (video is a fixed group there; the package must add gpio itself).
root=$work/root
mkdir -p "$root/var/lib/dpkg/info" "$root/var/lib/dpkg/updates" "$root/etc"
touch "$root/var/lib/dpkg/status"
echo "root:x:0:0:root:/root:/bin/sh" >"$root/etc/passwd"
printf 'root:x:0:\nvideo:x:44:\n' >"$root/etc/group"

# Libraries are not installed in the scratch root, and the arm64 build's
# package is installed on this machine: only the scripts run here.
dpkg_root() {
	dpkg --root="$root" --force-script-chrootless --force-depends --force-architecture \
		--log=/dev/null "$@" >>"$work/dpkg.log" 2>&1 ||
		{ cat "$work/dpkg.log" >&2; echo "$0: dpkg $*: failed" >&2; exit 1; }
}

failures=0
check() { # DESCRIPTION COMMAND...: COMMAND must succeed
	what=$1
	shift
	if "$@"; then
		echo "ok: $what"
	else
		echo "FAILED: $what" >&2
		failures=$((failures + 1))
	fi
}
members() { # GROUP: its member list from the scratch root's /etc/group
	awk -F: -v group="$1" '$1 == group { print $4 }' "$root/etc/group"
}
in_list() { # WORD LIST: LIST (comma-separated) contains WORD
	case ",$2," in *",$1,"*) return 0 ;; *) return 1 ;; esac
}
wants=$root/etc/systemd/system/multi-user.target.wants/stria.service

dpkg_root --install "$deb"
check "user stria, home /var/lib/stria, no login shell" \
	grep -qx 'stria:x:[0-9]*:[0-9]*:stria scanner:/var/lib/stria:/usr/sbin/nologin' "$root/etc/passwd"
check "group gpio created" grep -q '^gpio:x:[0-9]*:' "$root/etc/group"
check "stria in group video" in_list stria "$(members video)"
check "stria in group gpio" in_list stria "$(members gpio)"
enabled() { # the wants link points at the installed unit (/lib is /usr/lib)
	case "$(readlink "$wants")" in
	/lib/systemd/system/stria.service | /usr/lib/systemd/system/stria.service) return 0 ;;
	*) return 1 ;;
	esac
}
check "stria.service enabled (multi-user.target.wants link)" enabled
check "/etc/stria/board.yaml is a conffile" sh -c \
	"dpkg-query --root='$root' -W -f='\${Conffiles}' stria | grep -q '^ /etc/stria/board.yaml '"
check "board.yaml reads the installed simulated board" \
	grep -qx 'pattern: /usr/share/stria/board/sim/pattern.yaml' "$root/etc/stria/board.yaml"
check "udev rules installed" test -f "$root/usr/lib/udev/rules.d/60-stria.rules"

# An administrator's "disable" survives an upgrade (postinst enables on
# first install only).
rm "$wants"
dpkg_root --install "$deb"
check "upgrade leaves a disabled service disabled" test ! -e "$wants"
systemctl --root="$root" enable stria.service >/dev/null 2>&1

mkdir -p "$root/var/lib/stria/scans"
dpkg_root --remove stria
check "remove disables stria.service" test ! -e "$wants"
check "remove keeps the conffile and the scans" \
	test -f "$root/etc/stria/board.yaml" -a -d "$root/var/lib/stria/scans"
dpkg_root --purge stria
check "purge deletes /etc/stria/board.yaml" test ! -e "$root/etc/stria/board.yaml"
check "purge deletes /var/lib/stria" test ! -e "$root/var/lib/stria"
check "purge keeps the user stria" grep -q '^stria:' "$root/etc/passwd"

if [ $failures -ne 0 ]; then
	echo "$0: $failures check(s) failed; dpkg's output:" >&2
	cat "$work/dpkg.log" >&2
	exit 1
fi
echo "$0: all checks passed ($(basename "$deb"))"
