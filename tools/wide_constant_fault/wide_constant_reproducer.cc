#include "wide_constant_reproducer.h"

namespace parallax {

bool CpuHasX86_64_V4() {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
         __builtin_cpu_supports("avx512cd") && __builtin_cpu_supports("avx512dq") &&
         __builtin_cpu_supports("avx512vl");
#else
  return false;
#endif
}

// noinline: each constant is built inside a function of this translation unit, where the
// compiler sees the whole initializer, as in the test that first showed the fault.
__attribute__((noinline)) std::vector<Eigen::Vector2d> TwoPointsFromConstants() {
  return {{1, 1}, {0, 0}};
}

__attribute__((noinline)) std::vector<Eigen::Vector2d> FourPointsFromConstants() {
  return {{1, 1}, {0, 0}, {0, 0}, {0, 0}};
}

__attribute__((noinline)) std::vector<Eigen::Vector4d> TwoVectorsFromConstants() {
  return {{2, 2, 0, 0}, {0, 0, 0, 0}};
}

}  // namespace parallax
