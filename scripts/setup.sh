#!/usr/bin/env bash
# Installs the Debian packages shutterlab needs (safe to run again), then configures Release into
# build/ and builds the `shutterlab` command (the libraries it links and nothing else: the tests and
# benchmarks are built by scripts/test.sh). Usage: scripts/setup.sh [extra cmake args...]
set -euo pipefail
cd "$(dirname "$0")/.."

# openimageio-tools: Debian's OpenImageIOConfig.cmake refers to /usr/bin/iconvert and fails without it.
packages=(cmake g++ make pkg-config libeigen3-dev libopencv-dev libopenimageio-dev
          openimageio-tools libjpeg-dev libpng-dev libexiv2-dev nlohmann-json3-dev libcli11-dev libgtest-dev libgmock-dev
          libbenchmark-dev clang-format libgpiod-dev libtomlplusplus-dev libxxhash-dev universal-ctags
          clang libclang-rt-14-dev  # clang + its libFuzzer: scripts/fuzz.sh
          lld  # LLVM's linker: links in under half GNU ld's time (CMakeLists.txt)
          ninja-build)  # Ninja: compiles a target's files while the libraries it links still build
scripts/install_packages.sh setup "${packages[@]}"

build_dir="${SHUTTERLAB_BUILD_DIR:-build}"
# A new build folder is made for Ninja where it is installed (a folder made for make keeps make:
# CMake reads CMAKE_GENERATOR only when it makes the cache).
command -v ninja >/dev/null && export CMAKE_GENERATOR="${CMAKE_GENERATOR:-Ninja}"
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$build_dir" -j"$(nproc)" --target shutterlab
echo "setup: built $build_dir/bin/shutterlab"
