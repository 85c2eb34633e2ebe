#!/usr/bin/env bash
# Installs the Debian packages shutterlab needs (safe to run again), then configures Release into
# build/ and builds the `shutterlab` command (the libraries it links and nothing else: the tests and
# benchmarks are built by scripts/test.sh). Usage: scripts/setup.sh [extra cmake args...]
set -euo pipefail
cd "$(dirname "$0")/.."

# What building the command needs, no more (scripts/test.sh, format.sh and fuzz.sh install their
# own). openimageio-tools: Debian's OpenImageIOConfig.cmake refers to /usr/bin/iconvert and fails
# without it.
packages=(cmake g++ make pkg-config libeigen3-dev libopencv-dev libopenimageio-dev
          openimageio-tools libjpeg-dev libpng-dev libexiv2-dev nlohmann-json3-dev libcli11-dev
          libgpiod-dev libtomlplusplus-dev libxxhash-dev
          lld  # LLVM's linker: links in under half GNU ld's time (CMakeLists.txt)
          ninja-build)  # Ninja: compiles a target's files while the libraries it links still build
SECONDS=0
scripts/install_packages.sh setup "${packages[@]}"
install_s=$SECONDS

build_dir="${SHUTTERLAB_BUILD_DIR:-build}"
# A new build folder is made for Ninja where it is installed (a folder made for make keeps make:
# CMake reads CMAKE_GENERATOR only when it makes the cache).
command -v ninja >/dev/null && export CMAKE_GENERATOR="${CMAKE_GENERATOR:-Ninja}"
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$build_dir" -j"$(nproc)" --target shutterlab
echo "setup: built $build_dir/bin/shutterlab (packages ${install_s} s, build $((SECONDS - install_s)) s)"
