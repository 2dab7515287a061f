// The reproducer of a GCC 12 code-generation fault (docs/portable-build.md, README.md here).
// This file's .cc is compiled with -march=x86-64-v4 into its regression test and
// show-wide-constant-fault.sh only, never into a Parallax library: call these functions only
// where the CPU has AVX-512 (CpuHasX86_64_V4()).
#pragma once

#include <Eigen/Core>
#include <vector>

namespace parallax {

// True when the CPU runs x86-64-v4 code (AVX-512 F, BW, CD, DQ and VL).
bool CpuHasX86_64_V4();

// {{1, 1}, {0, 0}}: 32 bytes of constant data whose upper half is zero. GCC 12 with 256-bit
// by-pieces moves stores it as four 1.0s.
std::vector<Eigen::Vector2d> TwoPointsFromConstants();

// {{1, 1}, {0, 0}, {0, 0}, {0, 0}}: the same fault on a 64-byte constant.
std::vector<Eigen::Vector2d> FourPointsFromConstants();

// {{2, 2, 0, 0}, {0, 0, 0, 0}}: the same fault on vectors of four.
std::vector<Eigen::Vector4d> TwoVectorsFromConstants();

}  // namespace parallax
