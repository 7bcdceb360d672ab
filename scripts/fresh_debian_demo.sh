#!/usr/bin/env bash
# The README's set-up time, measured as a new user meets it: a fresh Debian 12 (a minimal
# debootstrap chroot, nothing installed beyond the base system), this checkout's HEAD cloned into
# it, then `time bash scripts/bootstrap.sh demo` as root. Needs root, network access to
# deb.debian.org and about 2 GB in DIR; installs debootstrap on the host if missing.
#
#   bash scripts/fresh_debian_demo.sh [DIR]     (default DIR: a new directory under /var/tmp)
#
# Prints the wall and CPU time of the set-up and when the package installation ended; the chroot
# is unmounted and left in DIR for inspection (`rm -rf DIR` removes it).
set -euo pipefail
cd "$(dirname "$0")/.."
[ "$(id -u)" = 0 ] || { echo "fresh_debian_demo.sh: run as root (debootstrap and chroot)" >&2; exit 2; }
DIR=${1:-$(mktemp -d /var/tmp/budjam-fresh-debian.XXXXXX)}
command -v debootstrap >/dev/null || { apt-get update -qq && apt-get install -y -qq debootstrap >/dev/null; }

debootstrap --variant=minbase bookworm "$DIR" http://deb.debian.org/debian >"$DIR.debootstrap.log" 2>&1 ||
  { echo "fresh_debian_demo.sh: debootstrap failed (log: $DIR.debootstrap.log)" >&2; exit 1; }
# The sources of Debian's own bookworm image, so that the set-up sees the updates a user would.
cat >"$DIR/etc/apt/sources.list" <<'LIST'
deb http://deb.debian.org/debian bookworm main
deb http://deb.debian.org/debian bookworm-updates main
deb http://deb.debian.org/debian-security bookworm-security main
LIST
cp /etc/resolv.conf "$DIR/etc/"
git clone -q . "$DIR/root/budjam"

unmount() { umount "$DIR/proc" "$DIR/dev/pts" "$DIR/dev" "$DIR/sys" 2>/dev/null || true; }
trap unmount EXIT
mount -t proc proc "$DIR/proc"
mount --bind /dev "$DIR/dev"
mount --bind /dev/pts "$DIR/dev/pts"
mount --bind /sys "$DIR/sys"
echo "fresh_debian_demo.sh: $(git rev-parse --short HEAD) in $DIR, set-up starts $(date +%T); load: $(cut -d' ' -f1-3 /proc/loadavg)" >&2
chroot "$DIR" /usr/bin/env -i PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin HOME=/root \
  bash -c 'cd /root/budjam && time bash scripts/bootstrap.sh demo'
echo "fresh_debian_demo.sh: packages installed by $(grep 'status installed' "$DIR/var/log/dpkg.log" | tail -1 | cut -d' ' -f2);" \
  "load: $(cut -d' ' -f1-3 /proc/loadavg)" >&2
