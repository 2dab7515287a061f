#!/usr/bin/env bash
# Installs dependencies, builds Parallax in Release mode and runs the whole test suite.
# PARALLAX_DATA points at the shared datasets (default ../shared/data beside the repo).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j2
export PARALLAX_DATA="${PARALLAX_DATA:-$(cd .. && pwd)/shared/data}"
ctest --test-dir build --output-on-failure -j2 --timeout 600
