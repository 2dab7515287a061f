#!/usr/bin/env bash
# Shows the GCC 12 wide-constant fault (docs/portable-build.md) outside the build: compiles
# wide_constant_reproducer.cc (beside this script) for x86-64-v4 with and without the
# workaround that cmake/ParallaxArch.cmake adds, and prints what each build stores. Needs an
# AVX-512 CPU to run the x86-64-v4 code and Eigen's headers (/usr/include/eigen3).
# Usage: tools/wide_constant_fault/show-wide-constant-fault.sh [CXX]
set -euo pipefail
cd "$(dirname "$0")"
cxx=${1:-g++}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cat >"$work/main.cc" <<'MAIN'
#include <cstdio>
#include "wide_constant_reproducer.h"
int main() {
  if (!parallax::CpuHasX86_64_V4()) { std::puts("this CPU has no AVX-512"); return 2; }
  std::printf("{{1, 1}, {0, 0}} stored as");
  for (const auto& p : parallax::TwoPointsFromConstants()) std::printf(" (%g, %g)", p.x(), p.y());
  std::printf("\n");
}
MAIN
includes=(-I"$PWD" -I/usr/include/eigen3)
"$cxx" --version | head -1
"$cxx" -std=c++20 -O2 "${includes[@]}" -c "$work/main.cc" -o "$work/main.o"
for flags in "-O2 -march=x86-64-v4" "-O2 -march=x86-64-v4 -mmove-max=128 -mstore-max=128" \
             "-O2 -march=x86-64-v3" "-O2 -march=x86-64-v3 -mtune=icelake-server"; do
  # shellcheck disable=SC2086
  "$cxx" -std=c++20 $flags "${includes[@]}" -c wide_constant_reproducer.cc \
    -o "$work/reproducer.o"
  "$cxx" "$work/main.o" "$work/reproducer.o" -o "$work/show"
  printf '%-52s %s\n' "$flags:" "$("$work/show")"
done
