#!/usr/bin/env bash
# Builds (if needed) and runs the whole test suite with ctest.
# SHUTTERLAB_BUILD_DIR picks the build folder (default build/); extra args go to ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir="${SHUTTERLAB_BUILD_DIR:-build}"
if [ ! -f "$build_dir/CMakeCache.txt" ]; then
  cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release >/dev/null
fi
cmake --build "$build_dir" -j"$(nproc)"
cd "$build_dir"
ctest --output-on-failure -j"$(nproc)" "$@"
