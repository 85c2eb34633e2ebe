#!/usr/bin/env bash
# Times the README's first command on a bare Debian 12 on this machine: debootstrap's minbase (no
# compiler, no libraries) in ROOT, a clean clone of this repository's HEAD copied into it, and
# `scripts/setup.sh && build/bin/shutterlab demo` run there under chroot, the package install
# included. Needs root, debootstrap (installed when missing) and Debian's mirror. Prints setup's
# own line (its install and build times), then the demo's and the whole command's time.
# Usage: scripts/bare_setup_time.sh [ROOT] (default /tmp/shutterlab_bare, made afresh).
set -euo pipefail
root=${1:-/tmp/shutterlab_bare}
repo=$(cd "$(dirname "$0")/.." && pwd)
command -v debootstrap >/dev/null || "$repo/scripts/install_packages.sh" bare debootstrap
unmount() { umount -R "$root/proc" "$root/dev" 2>/dev/null || true; }
trap unmount EXIT
unmount
rm -rf "$root"
debootstrap --variant=minbase bookworm "$root" http://deb.debian.org/debian >/dev/null
cp /etc/resolv.conf "$root/etc/"
if [ -f /etc/apt/sources.list.d/debian.sources ]; then  # this machine's suites (updates, security)
  rm -f "$root/etc/apt/sources.list"
  cp /etc/apt/sources.list.d/debian.sources "$root/etc/apt/sources.list.d/"
fi
git clone -q "$repo" "$root/root/shutterlab"
mount -t proc proc "$root/proc"
mount --rbind /dev "$root/dev"
mount --make-rslave "$root/dev"
chroot "$root" env -i HOME=/root PATH=/usr/sbin:/usr/bin:/sbin:/bin bash -c '
  cd /root/shutterlab
  SECONDS=0
  scripts/setup.sh > /root/setup.log 2>&1 || { tail -5 /root/setup.log; exit 1; }
  setup_s=$SECONDS
  tail -1 /root/setup.log
  build/bin/shutterlab demo > /root/demo.log 2>&1 || { tail -5 /root/demo.log; exit 1; }
  echo "demo $((SECONDS - setup_s)) s; the first README command $SECONDS s"'
