#!/usr/bin/env bash
# Installs those of the Debian packages named that are not installed yet (apt-get; sudo when not
# root), saying which. Safe to run again. Usage: scripts/install_packages.sh WHO PACKAGE...
# (WHO starts the line that names them: "setup", "test").
set -euo pipefail
who=$1
shift
missing=()
for p in "$@"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  echo "$who: installing ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
