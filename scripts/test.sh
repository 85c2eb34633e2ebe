#!/usr/bin/env bash
# Builds (if needed) and runs the whole test suite with ctest.
# SHUTTERLAB_BUILD_DIR picks the build folder (default build/); extra args go to ctest.
# Installs the outside programs some tests run as second implementations (Debian packages, safe
# to run again): COLMAP (reads the exported cameras) and Python's YAML (reads Kalibr's file).
set -euo pipefail
cd "$(dirname "$0")/.."
missing=()
for p in colmap python3-yaml; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  echo "test: installing ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
build_dir="${SHUTTERLAB_BUILD_DIR:-build}"
if [ ! -f "$build_dir/CMakeCache.txt" ]; then
  cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release >/dev/null
fi
cmake --build "$build_dir" -j"$(nproc)"
cd "$build_dir"
ctest --output-on-failure -j"$(nproc)" "$@"
