#include "parallax/feature/gaussian_blur.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <utility>

#include "parallax/feature/float8.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

// The vertical pass makes this many output rows at once, loading each input row once for all
// of them: one row at a time, its symmetric sums loaded two rows per tap, and the loads bound
// it (docs/performance.md, "Blur: four output rows per vertical step"). Four rows of two vectors
// are eight accumulators, enough to hide the FMA's latency, in AVX2's sixteen registers.
constexpr int kRowsPerStep = 4;
constexpr int kVerticalBlock = 16;

// A vertical step's `rows` are its taps + kRowsPerStep - 1 input rows, then the kRowsPerStep
// rows the next step adds: each block asks for those rows' same columns, a step ahead. The
// input comes from memory (a layer of the first octave is 4.9 MB), and with a stream per input
// row the hardware prefetcher kept up with too few of them (docs/performance.md,
// "Blur: the next vertical step's rows prefetched").
inline void PrefetchNextStep(const float* const* rows, int taps, int x, int floats) {
  const float* const* next = rows + taps + kRowsPerStep - 1;
  for (int q = 0; q < kRowsPerStep; ++q) {
    for (int f = 0; f < floats; f += 16) __builtin_prefetch(next[q] + x + f);
  }
}

// Adds input row j's samples x to x + 15, times kernel[j - q], to output rows q = kFirst to
// kLast: the rows of a step whose kernel reaches row j.
template <int kFirst, int kLast>
inline void AddRow(const float* row, const float* kernel, int j, int x,
                   Float8 (&acc)[kRowsPerStep][2]) {
  const Float8 low = Load8(row + x), high = Load8(row + x + 8);
#pragma GCC unroll 4
  for (int q = kFirst; q <= kLast; ++q) {
    const Float8 k = Float8{} + kernel[j - q];
    acc[q][0] = MulAdd8(k, low, acc[q][0]);
    acc[q][1] = MulAdd8(k, high, acc[q][1]);
  }
}

// Calls add.operator()<first, last>(j) for each input row j of a step, first to last being
// the output rows that j reaches: the first three and last three rows apart, for a kernel of
// three taps on. Its callers are flattened, so that the calls and AddRow are inlined.
template <typename AddRowFn>
void ForEachStepRow(int taps, const AddRowFn& add) {
  static_assert(kRowsPerStep == 4);
  const int last = taps + kRowsPerStep - 2;
  add.template operator()<0, 0>(0);
  add.template operator()<0, 1>(1);
  add.template operator()<0, 2>(2);
  for (int j = 3; j <= last - 3; ++j) add.template operator()<0, 3>(j);
  add.template operator()<1, 3>(last - 2);
  add.template operator()<2, 3>(last - 1);
  add.template operator()<3, 3>(last);
}

// out[q][x] = sum_j kernel[j - q] rows[j][x] for q < kRowsPerStep, j < taps + kRowsPerStep
// - 1 and the columns from x on, where `kernel` reads zero for the kRowsPerStep - 1 taps
// before and after its own (the first and last rows, which only some outputs reach, skip
// most of those zeros).
__attribute__((flatten)) void VerticalStep(const float* const* rows, const float* kernel, int taps,
                                           int width, float* const* out, int x = 0) {
  const int last = taps + kRowsPerStep - 2;
  for (; taps >= kRowsPerStep - 1 && x + kVerticalBlock <= width; x += kVerticalBlock) {
    PrefetchNextStep(rows, taps, x, kVerticalBlock);
    Float8 acc[kRowsPerStep][2] = {};
    ForEachStepRow(taps, [&]<int kFirst, int kLast>(int j) {
      AddRow<kFirst, kLast>(rows[j], kernel, j, x, acc);
    });
    for (int q = 0; q < kRowsPerStep; ++q) {
      Store8(out[q] + x, acc[q][0]);
      Store8(out[q] + x + 8, acc[q][1]);
    }
  }
  for (; x < width; ++x) {
    std::array<float, kRowsPerStep> acc{};
    for (int j = 0; j <= last; ++j) {
      for (int q = 0; q < kRowsPerStep; ++q) acc[q] = MulAdd(kernel[j - q], rows[j][x], acc[q]);
    }
    for (int q = 0; q < kRowsPerStep; ++q) out[q][x] = acc[q];
  }
}

// Outputs per horizontal block: four registers of accumulators.
constexpr int kHorizontalBlock = 32;

// out[x] = k[0] row[x] + sum_i k[i] (row[x - i] + row[x + i]) from x to width, where `row`
// is padded by radius samples on each side: the kernel's symmetry halves the products, and
// the row is in L1.
void HorizontalRow(const float* row, const Float8* taps, int radius, int width, float* out,
                   int x = 0) {
  for (; x + kHorizontalBlock <= width; x += kHorizontalBlock) {
    const float* centre = row + x;
    Float8 acc0 = taps[0] * Load8(centre), acc1 = taps[0] * Load8(centre + 8),
           acc2 = taps[0] * Load8(centre + 16), acc3 = taps[0] * Load8(centre + 24);
    for (int i = 1; i <= radius; ++i) {
      const Float8 k = taps[i];
      const float* a = centre - i;
      const float* b = centre + i;
      acc0 = MulAdd8(k, Load8(a) + Load8(b), acc0);
      acc1 = MulAdd8(k, Load8(a + 8) + Load8(b + 8), acc1);
      acc2 = MulAdd8(k, Load8(a + 16) + Load8(b + 16), acc2);
      acc3 = MulAdd8(k, Load8(a + 24) + Load8(b + 24), acc3);
    }
    Store8(out + x, acc0);
    Store8(out + x + 8, acc1);
    Store8(out + x + 16, acc2);
    Store8(out + x + 24, acc3);
  }
  // The same sums in the same order as the full blocks', rounded alike (MulAdd).
  for (; x < width; ++x) {
    float acc = taps[0][0] * row[x];
    for (int i = 1; i <= radius; ++i) acc = MulAdd(taps[i][0], row[x - i] + row[x + i], acc);
    out[x] = acc;
  }
}

#if defined(__x86_64__) && defined(__FMA__) && (defined(__GNUC__) || defined(__clang__))
#define PARALLAX_BLUR_AVX512 1

// The two passes in AVX-512 registers, for the blocks of twice the columns that fit: each
// lane runs the operations of the passes above in their order (so the floats are theirs),
// and each returns the first column it left to them.
constexpr int kVerticalBlock512 = 2 * kVerticalBlock;
constexpr int kHorizontalBlock512 = 2 * kHorizontalBlock;
// Columns the AVX-512 horizontal pass reads on either side of a block (its largest radius).
constexpr int kHorizontalPadding = 16;

template <int kFirst, int kLast>
__attribute__((target("avx512f"), always_inline)) inline void AddRow512(
    const float* row, const float* kernel, int j, int x, __m512 (&acc)[kRowsPerStep][2]) {
  const __m512 low = _mm512_loadu_ps(row + x), high = _mm512_loadu_ps(row + x + 16);
#pragma GCC unroll 4
  for (int q = kFirst; q <= kLast; ++q) {
    const __m512 k = _mm512_set1_ps(kernel[j - q]);
    acc[q][0] = _mm512_fmadd_ps(k, low, acc[q][0]);
    acc[q][1] = _mm512_fmadd_ps(k, high, acc[q][1]);
  }
}

__attribute__((target("avx512f"), flatten)) int VerticalStepAvx512(const float* const* rows,
                                                                   const float* kernel, int taps,
                                                                   int width, float* const* out) {
  int x = 0;
  for (; taps >= kRowsPerStep - 1 && x + kVerticalBlock512 <= width; x += kVerticalBlock512) {
    PrefetchNextStep(rows, taps, x, kVerticalBlock512);
    __m512 acc[kRowsPerStep][2];
    for (auto& row : acc) row[0] = row[1] = _mm512_setzero_ps();
    // A lambda does not take its function's target: it is given it.
    ForEachStepRow(
        taps, [&]<int kFirst, int kLast>(int j) __attribute__((target("avx512f"))) {
          AddRow512<kFirst, kLast>(rows[j], kernel, j, x, acc);
        });
    for (int q = 0; q < kRowsPerStep; ++q) {
      _mm512_storeu_ps(out[q] + x, acc[q][0]);
      _mm512_storeu_ps(out[q] + x + 16, acc[q][1]);
    }
  }
  return x;
}

// Columns kShift .. kShift + 15 of the 32 in (low, high), kShift in [0, 16].
template <int kShift>
__attribute__((target("avx512f"), always_inline)) inline __m512 Shifted(__m512 low, __m512 high) {
  if constexpr (kShift == 0) {
    return low;
  } else if constexpr (kShift == 16) {
    return high;
  } else {
    // The masked form with every lane: GCC 12's unmasked one warns of an uninitialised
    // operand it makes itself.
    return _mm512_castsi512_ps(_mm512_maskz_alignr_epi32(0xffff, _mm512_castps_si512(high),
                                                         _mm512_castps_si512(low), kShift));
  }
}

// Tap i of the horizontal pass for 4 vectors of columns, from their `columns` and one vector
// on either side.
template <int i>
__attribute__((target("avx512f"), always_inline)) inline void AddShiftedTap(
    const Float8* taps, const __m512 (&columns)[6], __m512 (&acc)[4]) {
  const __m512 k = _mm512_set1_ps(taps[i][0]);
  for (int v = 0; v < 4; ++v) {
    const __m512 left = Shifted<16 - i>(columns[v], columns[v + 1]);
    const __m512 right = Shifted<i>(columns[v + 1], columns[v + 2]);
    acc[v] = _mm512_fmadd_ps(k, _mm512_add_ps(left, right), acc[v]);
  }
}

// The horizontal pass of a block with the radius a constant: its 4 vectors of columns and
// one on either side are loaded once, and each tap's columns are shifted out of them
// (valignd); loaded at each tap's offset, 15 loads in 16 split a cache line, and those loads
// bound the pass (docs/performance.md, "Blur: columns shifted out of registers"). Summed as
// HorizontalRow sums.
template <int kRadius>
__attribute__((target("avx512f"), flatten)) int HorizontalRowAvx512(const float* row,
                                                                    const Float8* taps, int width,
                                                                    float* out) {
  static_assert(kRadius >= 1 && kRadius <= kHorizontalPadding);
  int x = 0;
  for (; x + kHorizontalBlock512 <= width; x += kHorizontalBlock512) {
    const float* centre = row + x;
    __m512 columns[6];  // Columns 16 j - 16 .. 16 j - 1 from the centre.
    for (int j = 0; j < 6; ++j) columns[j] = _mm512_loadu_ps(centre + 16 * j - 16);
    __m512 acc[4];
    const __m512 k0 = _mm512_set1_ps(taps[0][0]);
    for (int v = 0; v < 4; ++v) acc[v] = _mm512_mul_ps(k0, columns[v + 1]);
    [&]<int... kTapsAfterFirst>(std::integer_sequence<int, kTapsAfterFirst...>)
        __attribute__((target("avx512f"))) {
      (AddShiftedTap<kTapsAfterFirst + 1>(taps, columns, acc), ...);
    }
    (std::make_integer_sequence<int, kRadius>{});
    for (int v = 0; v < 4; ++v) _mm512_storeu_ps(out + x + 16 * v, acc[v]);
  }
  return x;
}

// The horizontal pass for any radius: each tap's columns loaded at its offset.
__attribute__((target("avx512f"))) int HorizontalRowAvx512Loads(const float* row,
                                                                const Float8* taps, int radius,
                                                                int width, float* out) {
  int x = 0;
  for (; x + kHorizontalBlock512 <= width; x += kHorizontalBlock512) {
    const float* centre = row + x;
    const __m512 k0 = _mm512_set1_ps(taps[0][0]);
    __m512 acc[4];
    for (int v = 0; v < 4; ++v) acc[v] = _mm512_mul_ps(k0, _mm512_loadu_ps(centre + 16 * v));
    for (int i = 1; i <= radius; ++i) {
      const __m512 k = _mm512_set1_ps(taps[i][0]);
      const float* a = centre - i;
      const float* b = centre + i;
#pragma GCC unroll 4
      for (int v = 0; v < 4; ++v) {
        const __m512 sum = _mm512_add_ps(_mm512_loadu_ps(a + 16 * v), _mm512_loadu_ps(b + 16 * v));
        acc[v] = _mm512_fmadd_ps(k, sum, acc[v]);
      }
    }
    for (int v = 0; v < 4; ++v) _mm512_storeu_ps(out + x + 16 * v, acc[v]);
  }
  return x;
}

// The horizontal pass in AVX-512 registers: by shifts where the radius allows.
int HorizontalRowAvx512(const float* row, const Float8* taps, int radius, int width, float* out) {
  using Pass = int (*)(const float*, const Float8*, int, float*);
  static constexpr auto kPasses =
      []<int... kRadiusLess1>(std::integer_sequence<int, kRadiusLess1...>) {
    return std::array<Pass, sizeof...(kRadiusLess1)>{&HorizontalRowAvx512<kRadiusLess1 + 1>...};
  }
  (std::make_integer_sequence<int, kHorizontalPadding>{});
  if (radius < 1 || radius > kHorizontalPadding) {
    return HorizontalRowAvx512Loads(row, taps, radius, width, out);
  }
  return kPasses[radius - 1](row, taps, width, out);
}
#else
// No AVX-512 code in this build (BlurHasAvx512() is false): every column is the passes' above.
int VerticalStepAvx512(const float* const*, const float*, int, int, float* const*) { return 0; }
int HorizontalRowAvx512(const float*, const Float8*, int, int, float*) { return 0; }
#endif

}  // namespace

bool BlurHasAvx512() {
#if defined(PARALLAX_BLUR_AVX512)
  static const bool available = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx512f");
  }();
  return available;
#else
  return false;
#endif
}

std::vector<float> GaussianHalfKernel(double sigma) {
  PARALLAX_CHECK_GT(sigma, 0.0);
  const int size = cvRound(sigma * 4 * 2 + 1) | 1;
  const cv::Mat kernel = cv::getGaussianKernel(size, sigma, CV_32F);
  const int radius = size / 2;
  std::vector<float> half(radius + 1);
  for (int i = 0; i <= radius; ++i) half[i] = kernel.at<float>(radius + i);
  return half;
}

WindowedGaussianBlur::WindowedGaussianBlur(const cv::Mat& src, double sigma, BlurVectors vectors)
    : src_(src), avx512_(vectors == BlurVectors::kWidest && BlurHasAvx512()) {
  PARALLAX_CHECK_EQ(src.type(), CV_32F);
  const std::vector<float> half = GaussianHalfKernel(sigma);
  radius_ = static_cast<int>(half.size()) - 1;
  const int taps = 2 * radius_ + 1;
  half_taps_.resize(half.size());
  for (size_t i = 0; i < half.size(); ++i) half_taps_[i] = Float8{} + half[i];
  // The whole kernel, with the zeros VerticalStep reads on either side.
  padded_kernel_.assign(taps + 2 * (kRowsPerStep - 1), 0.0f);
  float* kernel = padded_kernel_.data() + kRowsPerStep - 1;
  for (int j = 0; j < taps; ++j) kernel[j] = half[std::abs(j - radius_)];
  inputs_.resize(taps + 2 * kRowsPerStep - 1);  // With the next step's (PrefetchNextStep).
}

void WindowedGaussianBlur::Blur(cv::Rect window, cv::Mat* dst,
                                const std::function<void(int row)>& row_done) {
  PARALLAX_CHECK(dst != nullptr);
  PARALLAX_CHECK((window & cv::Rect(cv::Point(0, 0), src_.size())) == window);
  if (window.empty()) return;
  PARALLAX_CHECK(dst->size() == src_.size() && dst->type() == CV_32F);
  // The overload below refuses a `dst` that shares src's data.
  Blur(window, dst->ptr<float>(window.y) + window.x, dst->step1(), row_done);
}

void WindowedGaussianBlur::Blur(cv::Rect window, float* out, size_t out_stride,
                                const std::function<void(int row)>& row_done) {
  PARALLAX_CHECK((window & cv::Rect(cv::Point(0, 0), src_.size())) == window);
  if (window.empty()) return;
  PARALLAX_CHECK(out != nullptr && out_stride >= static_cast<size_t>(window.width));
  const auto* out_bytes = reinterpret_cast<const uchar*>(out);
  PARALLAX_CHECK(out_bytes < src_.datastart || out_bytes >= src_.dataend);
  const int rows = src_.rows, cols = src_.cols, radius = radius_;
  const int taps = 2 * radius + 1;
  const float* kernel = padded_kernel_.data() + kRowsPerStep - 1;

  // The vertical pass covers the columns the window's horizontal pass reads, widened to
  // whole blocks of VerticalStep where the image allows (the extra columns are never read,
  // and a narrow window's columns would otherwise go one by one); each of its rows is padded
  // by replicated samples where those columns leave the image. Past the last row, a step's
  // rows are made from clamped inputs and dropped.
  const int needed_begin = std::max(0, window.x - radius);
  const int needed_end = std::min(cols, window.x + window.width + radius);
  const int width = std::min(
      cols, (needed_end - needed_begin + kVerticalBlock - 1) / kVerticalBlock * kVerticalBlock);
  const int vertical_begin = std::min(needed_begin, cols - width);
  // A padded row holds columns [low, high): the window's, `radius` more on each side, and
  // any more the vertical pass makes.
  const int window_end_col = window.x + window.width;
  const int low = std::min(window.x - radius, vertical_begin);
  const int high = std::max(window_end_col + radius, vertical_begin + width);
  const int stride = high - low;
  // With kHorizontalPadding floats before the first row and after the last, which the
  // AVX-512 horizontal pass loads (and leaves out of its sums).
  vertical_.resize(kRowsPerStep * static_cast<size_t>(stride) + 2 * kHorizontalPadding);
  float* const vertical = vertical_.data() + kHorizontalPadding;
  std::array<float*, kRowsPerStep> vertical_rows;
  for (int q = 0; q < kRowsPerStep; ++q) {
    vertical_rows[q] = vertical + q * stride + (vertical_begin - low);
  }
  const int window_end = window.y + window.height;
  for (int r = window.y; r < window_end; r += kRowsPerStep) {
    for (int j = 0; j < static_cast<int>(inputs_.size()); ++j) {
      inputs_[j] = src_.ptr<float>(std::clamp(r - radius + j, 0, rows - 1)) + vertical_begin;
    }
    const int vertical_done =
        avx512_ ? VerticalStepAvx512(inputs_.data(), kernel, taps, width, vertical_rows.data()) : 0;
    VerticalStep(inputs_.data(), kernel, taps, width, vertical_rows.data(), vertical_done);
    for (int q = 0; q < kRowsPerStep && r + q < window_end; ++q) {
      float* row = vertical + q * stride;  // row[x - low] is column x.
      for (int x = window.x - radius; x < 0; ++x) row[x - low] = row[-low];
      for (int x = cols; x < window_end_col + radius; ++x) row[x - low] = row[cols - 1 - low];
      const float* centre = row + (window.x - low);
      float* out_row = out + (r + q - window.y) * out_stride;
      const int horizontal_done =
          avx512_ ? HorizontalRowAvx512(centre, half_taps_.data(), radius, window.width, out_row)
                  : 0;
      HorizontalRow(centre, half_taps_.data(), radius, window.width, out_row, horizontal_done);
      if (row_done) row_done(r + q);
    }
  }
}

void GaussianBlur(const cv::Mat& src, double sigma, cv::Mat* dst,
                  const std::function<void(int row)>& row_done, BlurVectors vectors) {
  PARALLAX_CHECK(dst != nullptr);
  PARALLAX_CHECK_EQ(src.type(), CV_32F);
  PARALLAX_CHECK(dst->data == nullptr || dst->data != src.data);
  WindowedGaussianBlur blur(src, sigma, vectors);
  dst->create(src.size(), CV_32F);
  blur.Blur(cv::Rect(cv::Point(0, 0), src.size()), dst, row_done);
}

}  // namespace parallax
