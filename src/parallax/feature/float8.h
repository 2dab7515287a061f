#pragma once

#include <cstring>

namespace parallax {

// Eight floats as one AVX2 register (GCC's and Clang's vector extension: arrays of
// accumulators the compiler kept went through the stack). Built for a target without AVX2,
// each is two SSE registers.
typedef float Float8 __attribute__((vector_size(32)));

inline Float8 Load8(const float* p) {
  Float8 v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}

inline void Store8(float* p, Float8 v) { std::memcpy(p, &v, sizeof(v)); }

}  // namespace parallax
