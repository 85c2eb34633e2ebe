#!/usr/bin/env bash
# Builds (if needed) and runs the whole test suite with ctest.
# SHUTTERLAB_BUILD_DIR picks the build folder (default build/); extra args go to ctest.
# Installs what the tests need beyond scripts/setup.sh's (Debian packages, safe to run again):
# GoogleTest and Google Benchmark; universal-ctags (the layout check reads each function's length);
# the outside programs some tests run: COLMAP (reads
# the exported cameras) and Python's YAML (reads Kalibr's file), second implementations; Chromium,
# which opens every page the tool writes (scripts/check_report.sh); Slurm and munge, whose
# one-node cluster on the loopback address runs `batch --slurm` (scripts/slurm_cluster.sh); ffmpeg,
# which writes the FPV clip `import --gyro` reads (its own encoder and muxer).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_packages.sh test libgtest-dev libgmock-dev libbenchmark-dev universal-ctags \
  colmap python3-yaml chromium slurm-wlm munge ffmpeg
# Ninja for a new build folder, as scripts/setup.sh says.
command -v ninja >/dev/null && export CMAKE_GENERATOR="${CMAKE_GENERATOR:-Ninja}"
build_dir="${SHUTTERLAB_BUILD_DIR:-build}"
if [ ! -f "$build_dir/CMakeCache.txt" ]; then
  cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release >/dev/null
else
  cmake -S . -B "$build_dir" >/dev/null  # finds GoogleTest, installed after setup's configure
fi
cmake --build "$build_dir" -j"$(nproc)"
cd "$build_dir"
ctest --output-on-failure -j"$(nproc)" "$@"
