#include "parallax/feature/similarity_kernel.h"

#include <cmath>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include "parallax/util/check.h"

namespace parallax {
namespace {

// Rows of b per micro-tile: 4 rows x 2 vectors = 8 accumulators, and per k 2 loads of a and
// 4 broadcasts of b for 8 FMAs.
constexpr int kRowsPerTile = 4;

constexpr int kPanel = kSimilarityPanelWidth;

// Column c of panel p, dimension k.
inline ptrdiff_t PackedIndex(int p, int k, int c, int dim) {
  return (static_cast<ptrdiff_t>(p) * dim + k) * kPanel + c;
}

void SimilaritiesScalar(const float* a_packed, int padded_a, const float* b, int num_b, int dim,
                        float* similarities) {
  for (int j = 0; j < num_b; ++j) {
    const float* b_row = b + static_cast<ptrdiff_t>(j) * dim;
    for (int i = 0; i < padded_a; ++i) {
      float sum = 0.0f;
      for (int k = 0; k < dim; ++k) {
        sum = std::fma(b_row[k], a_packed[PackedIndex(i / kPanel, k, i % kPanel, dim)], sum);
      }
      similarities[static_cast<ptrdiff_t>(j) * padded_a + i] = sum;
    }
  }
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define PARALLAX_SIMILARITY_SIMD 1

// kRows rows of b against 16 columns of a (two 8-lane vectors) starting at column i0.
// kRows rows of b against the 16 columns of a panel from column `half` * 16, written at
// out[r * padded_a + i0].
template <int kRows>
__attribute__((target("avx2,fma"))) inline void TileAvx2(const float* panel, int half, int padded_a,
                                                         const float* b, int dim, int i0,
                                                         float* out) {
  __m256 sum[kRows][2];
  for (int r = 0; r < kRows; ++r) sum[r][0] = sum[r][1] = _mm256_setzero_ps();
  for (int k = 0; k < dim; ++k) {
    const float* a = panel + static_cast<ptrdiff_t>(k) * kPanel + half * 16;
    const __m256 a0 = _mm256_loadu_ps(a);
    const __m256 a1 = _mm256_loadu_ps(a + 8);
    for (int r = 0; r < kRows; ++r) {
      const __m256 b_rk = _mm256_broadcast_ss(b + static_cast<ptrdiff_t>(r) * dim + k);
      sum[r][0] = _mm256_fmadd_ps(b_rk, a0, sum[r][0]);
      sum[r][1] = _mm256_fmadd_ps(b_rk, a1, sum[r][1]);
    }
  }
  for (int r = 0; r < kRows; ++r) {
    _mm256_storeu_ps(out + static_cast<ptrdiff_t>(r) * padded_a + i0, sum[r][0]);
    _mm256_storeu_ps(out + static_cast<ptrdiff_t>(r) * padded_a + i0 + 8, sum[r][1]);
  }
}

__attribute__((target("avx2,fma"))) void SimilaritiesAvx2(const float* a_packed, int padded_a,
                                                          const float* b, int num_b, int dim,
                                                          float* similarities) {
  for (int i0 = 0; i0 < padded_a; i0 += 16) {
    const float* panel = a_packed + PackedIndex(i0 / kPanel, 0, 0, dim);
    const int half = (i0 % kPanel) / 16;
    int j = 0;
    for (; j + kRowsPerTile <= num_b; j += kRowsPerTile) {
      TileAvx2<kRowsPerTile>(panel, half, padded_a, b + static_cast<ptrdiff_t>(j) * dim, dim, i0,
                             similarities + static_cast<ptrdiff_t>(j) * padded_a);
    }
    for (; j < num_b; ++j) {
      TileAvx2<1>(panel, half, padded_a, b + static_cast<ptrdiff_t>(j) * dim, dim, i0,
                  similarities + static_cast<ptrdiff_t>(j) * padded_a);
    }
  }
}

// The same with 16-lane vectors: kRows rows of b against the 32 columns of a panel.
template <int kRows>
__attribute__((target("avx512f"))) inline void TileAvx512(const float* panel, int padded_a,
                                                          const float* b, int dim, int i0,
                                                          float* out) {
  __m512 sum[kRows][2];
  for (int r = 0; r < kRows; ++r) sum[r][0] = sum[r][1] = _mm512_setzero_ps();
  for (int k = 0; k < dim; ++k) {
    const float* a = panel + static_cast<ptrdiff_t>(k) * kPanel;
    const __m512 a0 = _mm512_loadu_ps(a);
    const __m512 a1 = _mm512_loadu_ps(a + 16);
    for (int r = 0; r < kRows; ++r) {
      const __m512 b_rk = _mm512_set1_ps(b[static_cast<ptrdiff_t>(r) * dim + k]);
      sum[r][0] = _mm512_fmadd_ps(b_rk, a0, sum[r][0]);
      sum[r][1] = _mm512_fmadd_ps(b_rk, a1, sum[r][1]);
    }
  }
  for (int r = 0; r < kRows; ++r) {
    _mm512_storeu_ps(out + static_cast<ptrdiff_t>(r) * padded_a + i0, sum[r][0]);
    _mm512_storeu_ps(out + static_cast<ptrdiff_t>(r) * padded_a + i0 + 16, sum[r][1]);
  }
}

__attribute__((target("avx512f"))) void SimilaritiesAvx512(const float* a_packed, int padded_a,
                                                           const float* b, int num_b, int dim,
                                                           float* similarities) {
  for (int i0 = 0; i0 < padded_a; i0 += kPanel) {
    const float* panel = a_packed + PackedIndex(i0 / kPanel, 0, 0, dim);
    int j = 0;
    for (; j + kRowsPerTile <= num_b; j += kRowsPerTile) {
      TileAvx512<kRowsPerTile>(panel, padded_a, b + static_cast<ptrdiff_t>(j) * dim, dim, i0,
                               similarities + static_cast<ptrdiff_t>(j) * padded_a);
    }
    for (; j < num_b; ++j) {
      TileAvx512<1>(panel, padded_a, b + static_cast<ptrdiff_t>(j) * dim, dim, i0,
                    similarities + static_cast<ptrdiff_t>(j) * padded_a);
    }
  }
}
#endif

}  // namespace

int PackSimilarityColumns(const float* a, int num_a, int dim, std::vector<float>* packed) {
  const int padded_a = (num_a + kPanel - 1) / kPanel * kPanel;
  packed->assign(static_cast<size_t>(padded_a) * dim, 0.0f);
  for (int i = 0; i < num_a; ++i) {
    for (int k = 0; k < dim; ++k) {
      (*packed)[PackedIndex(i / kPanel, k, i % kPanel, dim)] =
          a[static_cast<ptrdiff_t>(i) * dim + k];
    }
  }
  return padded_a;
}

bool SimilarityKernelAvailable(SimilarityKernel kernel) {
  switch (kernel) {
    case SimilarityKernel::kScalar:
      return true;
#if defined(PARALLAX_SIMILARITY_SIMD)
    case SimilarityKernel::kAvx2:
      __builtin_cpu_init();
      return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    case SimilarityKernel::kAvx512:
      __builtin_cpu_init();
      return __builtin_cpu_supports("avx512f");
#endif
    default:
      return false;
  }
}

SimilarityKernel BestSimilarityKernel() {
  static const SimilarityKernel best = [] {
    for (const SimilarityKernel kernel : {SimilarityKernel::kAvx512, SimilarityKernel::kAvx2}) {
      if (SimilarityKernelAvailable(kernel)) return kernel;
    }
    return SimilarityKernel::kScalar;
  }();
  return best;
}

void ComputeSimilarities(const float* a_packed, int padded_a, const float* b, int num_b, int dim,
                         float* similarities, SimilarityKernel kernel) {
  PARALLAX_CHECK_EQ(padded_a % kPanel, 0);
  PARALLAX_CHECK(SimilarityKernelAvailable(kernel));
  switch (kernel) {
#if defined(PARALLAX_SIMILARITY_SIMD)
    case SimilarityKernel::kAvx512:
      return SimilaritiesAvx512(a_packed, padded_a, b, num_b, dim, similarities);
    case SimilarityKernel::kAvx2:
      return SimilaritiesAvx2(a_packed, padded_a, b, num_b, dim, similarities);
#endif
    default:
      return SimilaritiesScalar(a_packed, padded_a, b, num_b, dim, similarities);
  }
}

}  // namespace parallax
