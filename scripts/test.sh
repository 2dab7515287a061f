#!/usr/bin/env bash
# Installs dependencies, builds Parallax in Release mode and runs the whole test suite.
# PARALLAX_DATA points at the shared datasets (default ../shared/data beside the repo).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
# A fresh build folder (CI's clean clone) leaves out the benchmarks (bench/), which no test
# runs: about 20 s of a from-scratch run. A folder configured before keeps its own choice.
configure=(-DCMAKE_BUILD_TYPE=Release)
[[ -f build/CMakeCache.txt ]] || configure+=(-DPARALLAX_BUILD_BENCHMARKS=OFF)
cmake -S . -B build -G Ninja "${configure[@]}" >/dev/null
cmake --build build -j2
export PARALLAX_DATA="${PARALLAX_DATA:-$(cd .. && pwd)/shared/data}"
ctest --test-dir build --output-on-failure -j2 --timeout 600
