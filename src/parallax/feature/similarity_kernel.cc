#include "parallax/feature/similarity_kernel.h"

#include <cstring>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include "parallax/util/check.h"

namespace parallax {
namespace {

// Rows of b per micro-tile: 4 rows x 2 vectors = 8 accumulators, and per step 2 loads of a
// and 4 broadcasts of b for 8 multiply-adds.
constexpr int kRowsPerTile = 4;

constexpr int kPanel = kSimilarityPanelWidth;

// Words of one panel: `dim` dimensions of kPanel columns, in groups of `group` dimensions.
inline ptrdiff_t PackedIndex(int column, int k, int group, int dim) {
  const int panel = column / kPanel, c = column % kPanel;
  return ((static_cast<ptrdiff_t>(panel) * (dim / group) + k / group) * kPanel + c) * group +
         k % group;
}

// The num_a rows of a (each value minus `offset`) in panels of num_columns columns grouped by
// `group` dimensions; the padding columns are 0.
template <typename T>
void PackGroups(const uint8_t* a, int num_a, int num_columns, int dim, int group, int offset,
                std::vector<T>* values) {
  values->assign(static_cast<size_t>(num_columns) * dim, T{0});
  for (int i = 0; i < num_a; ++i) {
    for (int k = 0; k < dim; ++k) {
      (*values)[PackedIndex(i, k, group, dim)] =
          static_cast<T>(a[static_cast<ptrdiff_t>(i) * dim + k] - offset);
    }
  }
}

// float(dot) * scale_a * scale_b, in that order in every kernel.
inline float Similarity(int32_t dot, float scale_a, float scale_b) {
  return static_cast<float>(dot) * scale_a * scale_b;
}

void SimilaritiesScalar(const SimilarityColumns& a, const uint8_t* b, const float* b_scales,
                        int num_b, float* similarities) {
  const int dim = a.dim;
  for (int j = 0; j < num_b; ++j) {
    const uint8_t* b_row = b + static_cast<ptrdiff_t>(j) * dim;
    for (int i = 0; i < a.num_columns; ++i) {
      int32_t dot = 0;
      for (int k = 0; k < dim; ++k) dot += b_row[k] * a.pairs[PackedIndex(i, k, 2, dim)];
      similarities[static_cast<ptrdiff_t>(j) * a.num_columns + i] =
          Similarity(dot, a.scales[i], b_scales[j]);
    }
  }
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define PARALLAX_SIMILARITY_SIMD 1

inline int32_t Load32(const void* bytes) {
  int32_t value;
  std::memcpy(&value, bytes, sizeof(value));
  return value;
}

// kRows rows of b (16-bit) against the 16 columns of a panel from column `half` * 16, written
// at out[r * num_columns + i0].
template <int kRows>
__attribute__((target("avx2,fma"))) inline void TileAvx2(const int16_t* panel, int half,
                                                         const int16_t* b, const float* b_scales,
                                                         int dim, const float* a_scales,
                                                         int num_columns, float* out) {
  __m256i sum[kRows][2];
  for (int r = 0; r < kRows; ++r) sum[r][0] = sum[r][1] = _mm256_setzero_si256();
  for (int kp = 0; kp < dim / 2; ++kp) {
    const int16_t* column_pairs = panel + (static_cast<ptrdiff_t>(kp) * kPanel + half * 16) * 2;
    const __m256i a0 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(column_pairs));
    const __m256i a1 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(column_pairs + 16));
    for (int r = 0; r < kRows; ++r) {
      const __m256i b_pair =
          _mm256_set1_epi32(Load32(b + static_cast<ptrdiff_t>(r) * dim + 2 * kp));
      sum[r][0] = _mm256_add_epi32(sum[r][0], _mm256_madd_epi16(b_pair, a0));
      sum[r][1] = _mm256_add_epi32(sum[r][1], _mm256_madd_epi16(b_pair, a1));
    }
  }
  const __m256 scale0 = _mm256_loadu_ps(a_scales), scale1 = _mm256_loadu_ps(a_scales + 8);
  for (int r = 0; r < kRows; ++r) {
    const __m256 b_scale = _mm256_set1_ps(b_scales[r]);
    float* row = out + static_cast<ptrdiff_t>(r) * num_columns;
    _mm256_storeu_ps(row,
                     _mm256_mul_ps(_mm256_mul_ps(_mm256_cvtepi32_ps(sum[r][0]), scale0), b_scale));
    _mm256_storeu_ps(row + 8,
                     _mm256_mul_ps(_mm256_mul_ps(_mm256_cvtepi32_ps(sum[r][1]), scale1), b_scale));
  }
}

__attribute__((target("avx2,fma"))) void SimilaritiesAvx2(const SimilarityColumns& a,
                                                          const uint8_t* b, const float* b_scales,
                                                          int num_b, float* similarities) {
  const int dim = a.dim;
  // b widened to 16 bits once, so that a broadcast carries a pair of dimensions.
  thread_local std::vector<int16_t> b_words;
  b_words.resize(static_cast<size_t>(num_b) * dim);
  for (size_t n = 0; n < b_words.size(); ++n) b_words[n] = b[n];
  for (int i0 = 0; i0 < a.num_columns; i0 += 16) {
    const int16_t* panel = a.pairs + PackedIndex(i0 - i0 % kPanel, 0, 2, dim);
    const int half = (i0 % kPanel) / 16;
    int j = 0;
    for (; j + kRowsPerTile <= num_b; j += kRowsPerTile) {
      TileAvx2<kRowsPerTile>(panel, half, b_words.data() + static_cast<ptrdiff_t>(j) * dim,
                             b_scales + j, dim, a.scales + i0, a.num_columns,
                             similarities + static_cast<ptrdiff_t>(j) * a.num_columns + i0);
    }
    for (; j < num_b; ++j) {
      TileAvx2<1>(panel, half, b_words.data() + static_cast<ptrdiff_t>(j) * dim, b_scales + j, dim,
                  a.scales + i0, a.num_columns,
                  similarities + static_cast<ptrdiff_t>(j) * a.num_columns + i0);
    }
  }
}

// The masked conversion with every lane set is the plain one, which GCC 12's header
// implements with an uninitialised value it then warns about.
__attribute__((target("avx512f"))) inline __m512 ToFloat(__m512i value) {
  return _mm512_maskz_cvtepi32_ps(0xFFFF, value);
}

// kRows rows of b (bytes) against the 32 columns of a panel. vpdpbusd multiplies unsigned by
// signed bytes, so a is stored as value - 128 and b's sum times 128 is added back.
template <int kRows>
__attribute__((target("avx512f,avx512vnni"))) inline void TileAvx512Vnni(
    const int8_t* panel, const uint8_t* b, const int32_t* b_sums, const float* b_scales, int dim,
    const float* a_scales, int num_columns, float* out) {
  __m512i sum[kRows][2];
  for (int r = 0; r < kRows; ++r) sum[r][0] = sum[r][1] = _mm512_setzero_si512();
  for (int kq = 0; kq < dim / 4; ++kq) {
    const int8_t* column_quads = panel + static_cast<ptrdiff_t>(kq) * kPanel * 4;
    const __m512i a0 = _mm512_loadu_si512(column_quads);
    const __m512i a1 = _mm512_loadu_si512(column_quads + 64);
    for (int r = 0; r < kRows; ++r) {
      const __m512i b_quad =
          _mm512_set1_epi32(Load32(b + static_cast<ptrdiff_t>(r) * dim + 4 * kq));
      sum[r][0] = _mm512_dpbusd_epi32(sum[r][0], b_quad, a0);
      sum[r][1] = _mm512_dpbusd_epi32(sum[r][1], b_quad, a1);
    }
  }
  const __m512 scale0 = _mm512_loadu_ps(a_scales), scale1 = _mm512_loadu_ps(a_scales + 16);
  for (int r = 0; r < kRows; ++r) {
    const __m512i offset = _mm512_set1_epi32(128 * b_sums[r]);
    const __m512 b_scale = _mm512_set1_ps(b_scales[r]);
    float* row = out + static_cast<ptrdiff_t>(r) * num_columns;
    const __m512 dot0 = ToFloat(_mm512_add_epi32(sum[r][0], offset));
    const __m512 dot1 = ToFloat(_mm512_add_epi32(sum[r][1], offset));
    _mm512_storeu_ps(row, _mm512_mul_ps(_mm512_mul_ps(dot0, scale0), b_scale));
    _mm512_storeu_ps(row + 16, _mm512_mul_ps(_mm512_mul_ps(dot1, scale1), b_scale));
  }
}

__attribute__((target("avx512f,avx512vnni"))) void SimilaritiesAvx512Vnni(
    const SimilarityColumns& a, const uint8_t* b, const float* b_scales, const int32_t* b_sums,
    int num_b, float* similarities) {
  const int dim = a.dim;
  for (int i0 = 0; i0 < a.num_columns; i0 += kPanel) {
    const int8_t* panel = a.quads + PackedIndex(i0, 0, 4, dim);
    int j = 0;
    for (; j + kRowsPerTile <= num_b; j += kRowsPerTile) {
      TileAvx512Vnni<kRowsPerTile>(panel, b + static_cast<ptrdiff_t>(j) * dim, b_sums + j,
                                   b_scales + j, dim, a.scales + i0, a.num_columns,
                                   similarities + static_cast<ptrdiff_t>(j) * a.num_columns + i0);
    }
    for (; j < num_b; ++j) {
      TileAvx512Vnni<1>(panel, b + static_cast<ptrdiff_t>(j) * dim, b_sums + j, b_scales + j, dim,
                        a.scales + i0, a.num_columns,
                        similarities + static_cast<ptrdiff_t>(j) * a.num_columns + i0);
    }
  }
}
#endif

}  // namespace

SimilarityColumns PackedSimilarityColumns::Panels(int first, int count) const {
  PARALLAX_CHECK_EQ(first % kPanel, 0);
  PARALLAX_CHECK_GE(count, 0);
  const int rounded = (count + kPanel - 1) / kPanel * kPanel;
  PARALLAX_CHECK_LE(first + rounded, num_columns);
  // A panel of kPanel columns holds kPanel * dim values, whatever the grouping.
  const ptrdiff_t offset = static_cast<ptrdiff_t>(first) * dim;
  SimilarityColumns view;
  view.kernel = kernel;
  view.num_columns = rounded;
  view.dim = dim;
  view.pairs = pairs.empty() ? nullptr : pairs.data() + offset;
  view.quads = quads.empty() ? nullptr : quads.data() + offset;
  view.scales = scales.data() + first;
  return view;
}

void PackSimilarityColumns(const uint8_t* a, const float* a_scales, int num_a, int dim,
                           SimilarityKernel kernel, PackedSimilarityColumns* packed) {
  PARALLAX_CHECK_GE(num_a, 0);
  PARALLAX_CHECK_EQ(dim % 4, 0);
  packed->kernel = kernel;
  packed->dim = dim;
  packed->num_columns = (num_a + kPanel - 1) / kPanel * kPanel;
  packed->scales.assign(packed->num_columns, 0.0f);
  std::copy(a_scales, a_scales + num_a, packed->scales.begin());
  if (kernel == SimilarityKernel::kAvx512Vnni) {
    packed->pairs.clear();
    PackGroups(a, num_a, packed->num_columns, dim, 4, 128, &packed->quads);
  } else {
    packed->quads.clear();
    PackGroups(a, num_a, packed->num_columns, dim, 2, 0, &packed->pairs);
  }
}

bool SimilarityKernelAvailable(SimilarityKernel kernel) {
  switch (kernel) {
    case SimilarityKernel::kScalar:
      return true;
#if defined(PARALLAX_SIMILARITY_SIMD)
    case SimilarityKernel::kAvx2:
      __builtin_cpu_init();
      return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    case SimilarityKernel::kAvx512Vnni:
      __builtin_cpu_init();
      return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vnni");
#endif
    default:
      return false;
  }
}

SimilarityKernel BestSimilarityKernel() {
  static const SimilarityKernel best = [] {
    for (const SimilarityKernel kernel : {SimilarityKernel::kAvx512Vnni, SimilarityKernel::kAvx2}) {
      if (SimilarityKernelAvailable(kernel)) return kernel;
    }
    return SimilarityKernel::kScalar;
  }();
  return best;
}

void ComputeSimilarities(const SimilarityColumns& a, const SimilarityRows& rows,
                         float* similarities) {
  const uint8_t* b = rows.bytes;
  const float* b_scales = rows.scales;
  const int num_b = rows.num_rows;
  PARALLAX_CHECK_EQ(a.num_columns % kPanel, 0);
  PARALLAX_CHECK(SimilarityKernelAvailable(a.kernel));
  switch (a.kernel) {
#if defined(PARALLAX_SIMILARITY_SIMD)
    case SimilarityKernel::kAvx512Vnni:
      return SimilaritiesAvx512Vnni(a, b, b_scales, rows.sums, num_b, similarities);
    case SimilarityKernel::kAvx2:
      return SimilaritiesAvx2(a, b, b_scales, num_b, similarities);
#endif
    default:
      return SimilaritiesScalar(a, b, b_scales, num_b, similarities);
  }
}

}  // namespace parallax
