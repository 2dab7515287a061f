#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

#if defined(__SSE__)
#include <immintrin.h>
#endif

namespace parallax {

// Eight floats as one AVX2 register (GCC's and Clang's vector extension: arrays of
// accumulators the compiler kept went through the stack). Built for a target without AVX2,
// each is two SSE registers.
typedef float Float8 __attribute__((vector_size(32)));
typedef int32_t Int8 __attribute__((vector_size(32)));
// And four, one SSE register.
typedef float Float4 __attribute__((vector_size(16)));
typedef int32_t Int4 __attribute__((vector_size(16)));

inline Float8 Load8(const float* p) {
  Float8 v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}

inline void Store8(float* p, Float8 v) { std::memcpy(p, &v, sizeof(v)); }

inline Float4 Load4(const float* p) {
  Float4 v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}

// |v|, by clearing the sign bits: one AND (GCC makes a negation and a blend of v < 0 ? -v : v).
inline Float8 Abs8(Float8 v) {
  return reinterpret_cast<Float8>(reinterpret_cast<Int8>(v) & 0x7fffffff);
}

// a < b ? a : b and a > b ? a : b, lane by lane: vminps and vmaxps compute exactly these
// (NaNs included), where GCC makes a comparison and a blend of the vector extension's ternary.
inline Float8 Min8(Float8 a, Float8 b) {
#if defined(__AVX__)
  return reinterpret_cast<Float8>(
      _mm256_min_ps(reinterpret_cast<__m256>(a), reinterpret_cast<__m256>(b)));
#else
  return a < b ? a : b;
#endif
}

inline Float8 Max8(Float8 a, Float8 b) {
#if defined(__AVX__)
  return reinterpret_cast<Float8>(
      _mm256_max_ps(reinterpret_cast<__m256>(a), reinterpret_cast<__m256>(b)));
#else
  return a > b ? a : b;
#endif
}

// floor(v), lane by lane.
inline Float8 Floor8(Float8 v) {
#if defined(__AVX__)
  return reinterpret_cast<Float8>(_mm256_floor_ps(reinterpret_cast<__m256>(v)));
#else
  for (int i = 0; i < 8; ++i) v[i] = std::floor(v[i]);
  return v;
#endif
}

// a * b + c, fused (one rounding) where the target has FMA whatever -ffp-contract says, and
// so rounded alike in a vector loop and in its scalar tail (MulAdd): left to contraction, GCC
// -O3 fused the one and vectorised the other's products unfused.
inline Float8 MulAdd8(Float8 a, Float8 b, Float8 c) {
#if defined(__FMA__)
  return reinterpret_cast<Float8>(_mm256_fmadd_ps(
      reinterpret_cast<__m256>(a), reinterpret_cast<__m256>(b), reinterpret_cast<__m256>(c)));
#else
  return a * b + c;
#endif
}

inline float MulAdd(float a, float b, float c) {
#if defined(__FMA__)
  return std::fma(a, b, c);
#else
  return a * b + c;
#endif
}

// Bit i set where lane i of `mask` (a comparison's result: all ones or all zeros) is set.
inline uint32_t MoveMask8(Int8 mask) {
#if defined(__AVX__)
  return static_cast<uint32_t>(_mm256_movemask_ps(reinterpret_cast<__m256>(mask)));
#else
  uint32_t bits = 0;
  for (int i = 0; i < 8; ++i) bits |= static_cast<uint32_t>(mask[i] != 0) << i;
  return bits;
#endif
}

// Bit i set where lane i of `mask` is set.
inline uint32_t MoveMask4(Int4 mask) {
#if defined(__SSE__)
  return static_cast<uint32_t>(_mm_movemask_ps(reinterpret_cast<__m128>(mask)));
#else
  uint32_t bits = 0;
  for (int i = 0; i < 4; ++i) bits |= static_cast<uint32_t>(mask[i] != 0) << i;
  return bits;
#endif
}

}  // namespace parallax
