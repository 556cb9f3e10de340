#!/usr/bin/env bash
# Installs what mjtether needs from Debian 12's packages (as root, only if missing), then
# configures and builds it in ./build. Both README commands start with it.
set -euo pipefail
cd "$(dirname "$0")"
packages=(build-essential cmake libmujoco-dev libeigen3-dev libosmesa6-dev ffmpeg
          libgtest-dev libbenchmark-dev libcli11-dev libfmt-dev libpng-dev gnuplot-nox
          clang-14 libclang-rt-14-dev valgrind python3 pkg-config slurm-wlm munge
          pybind11-dev python3-dev python3-numpy python3-pytest git libglfw3-dev xvfb xauth)
if ! dpkg -s "${packages[@]}" >/dev/null 2>&1; then
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -q
  apt-get install -y -q "${packages[@]}"
fi
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
