#!/usr/bin/env bash
# Installs every Debian package Parallax needs to build and test. Idempotent: prints nothing
# and touches nothing when all are already installed.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libceres-dev libsqlite3-dev sqlite3
  libopencv-core-dev libopencv-imgcodecs-dev libopencv-imgproc-dev
  libopencv-features2d-dev libopencv-calib3d-dev
  libjpeg62-turbo-dev libpng-dev libtiff-dev
  libcli11-dev nlohmann-json3-dev libxxhash-dev libdeflate-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  chromium
  clang-format-14
  pybind11-dev python3-dev python3-numpy python3-pytest python3-matplotlib
  libopenmpi-dev openmpi-bin
)
# Extra packages for optional checks, installed when asked: PARALLAX_EXTRA_DEPS=1.
if [[ "${PARALLAX_EXTRA_DEPS:-0}" == "1" ]]; then
  packages+=(clang-14 libclang-rt-14-dev)
fi
# Packages of the end-to-end benchmark (bench/run.sh), installed when asked:
# PARALLAX_BENCH_DEPS=1. GNU time measures wall time and peak memory; COLMAP is the reference.
if [[ "${PARALLAX_BENCH_DEPS:-0}" == "1" ]]; then
  packages+=(time colmap python3)
fi

missing=()
for package in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done
[[ ${#missing[@]} -eq 0 ]] && exit 0

echo "install-deps: installing ${missing[*]}" >&2
sudo_cmd=()
[[ $(id -u) -ne 0 ]] && sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
