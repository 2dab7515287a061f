#include "parallax/feature/gaussian_blur.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "parallax/feature/float8.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

// Outputs per block: four registers of accumulators.
constexpr int kBlock = 32;

// out[j] = k[0] centre[j] + sum_i k[i] (before[i][offset + j] + after[i][offset + j]) for the
// first n < kBlock samples, where before[i] and after[i] point i taps away on either side;
// the same sums in the same order as the full blocks'.
void SymmetricTapsTail(const float* const* before, const float* const* after, int offset,
                       const float* centre, const Float8* taps, int radius, int n, float* out) {
  for (int j = 0; j < n; ++j) {
    float acc = taps[0][0] * centre[j];
    for (int i = 1; i <= radius; ++i) {
      acc += taps[i][0] * (before[i][offset + j] + after[i][offset + j]);
    }
    out[j] = acc;
  }
}

void SymmetricTapsBlock(const float* const* before, const float* const* after, int offset,
                        const float* centre, const Float8* taps, int radius, float* out) {
  Float8 acc0 = taps[0] * Load8(centre), acc1 = taps[0] * Load8(centre + 8),
         acc2 = taps[0] * Load8(centre + 16), acc3 = taps[0] * Load8(centre + 24);
  for (int i = 1; i <= radius; ++i) {
    const Float8 k = taps[i];
    const float* a = before[i] + offset;
    const float* b = after[i] + offset;
    acc0 += k * (Load8(a) + Load8(b));
    acc1 += k * (Load8(a + 8) + Load8(b + 8));
    acc2 += k * (Load8(a + 16) + Load8(b + 16));
    acc3 += k * (Load8(a + 24) + Load8(b + 24));
  }
  Store8(out, acc0);
  Store8(out + 8, acc1);
  Store8(out + 16, acc2);
  Store8(out + 24, acc3);
}

// One row of `width` outputs, from the kernel's taps each broadcast to a register.
void FilterRow(const float* const* before, const float* const* after, const float* centre,
               const std::vector<Float8>& taps, int width, float* out) {
  const int radius = static_cast<int>(taps.size()) - 1;
  int x = 0;
  for (; x + kBlock <= width; x += kBlock) {
    SymmetricTapsBlock(before, after, x, centre + x, taps.data(), radius, out + x);
  }
  SymmetricTapsTail(before, after, x, centre + x, taps.data(), radius, width - x, out + x);
}

}  // namespace

std::vector<float> GaussianHalfKernel(double sigma) {
  PARALLAX_CHECK_GT(sigma, 0.0);
  const int size = cvRound(sigma * 4 * 2 + 1) | 1;
  const cv::Mat kernel = cv::getGaussianKernel(size, sigma, CV_32F);
  const int radius = size / 2;
  std::vector<float> half(radius + 1);
  for (int i = 0; i <= radius; ++i) half[i] = kernel.at<float>(radius + i);
  return half;
}

void GaussianBlur(const cv::Mat& src, double sigma, cv::Mat* dst) {
  PARALLAX_CHECK(dst != nullptr);
  PARALLAX_CHECK_EQ(src.type(), CV_32F);
  PARALLAX_CHECK(dst->data == nullptr || dst->data != src.data);
  const std::vector<float> kernel = GaussianHalfKernel(sigma);
  const int radius = static_cast<int>(kernel.size()) - 1;
  std::vector<Float8> taps(kernel.size());
  for (size_t i = 0; i < kernel.size(); ++i) taps[i] = Float8{} + kernel[i];
  const int rows = src.rows, cols = src.cols;
  dst->create(src.size(), CV_32F);
  if (src.empty()) return;

  // The vertical pass's row, padded by `radius` replicated samples on each side.
  std::vector<float> padded(cols + 2 * radius);
  float* column_pass = padded.data() + radius;
  std::vector<const float*> up(radius + 1), down(radius + 1), left(radius + 1), right(radius + 1);
  for (int i = 1; i <= radius; ++i) {
    left[i] = column_pass - i;
    right[i] = column_pass + i;
  }
  for (int r = 0; r < rows; ++r) {
    for (int i = 1; i <= radius; ++i) {
      up[i] = src.ptr<float>(std::max(r - i, 0));
      down[i] = src.ptr<float>(std::min(r + i, rows - 1));
    }
    FilterRow(up.data(), down.data(), src.ptr<float>(r), taps, cols, column_pass);
    std::fill(padded.begin(), padded.begin() + radius, column_pass[0]);
    std::fill(padded.end() - radius, padded.end(), column_pass[cols - 1]);
    FilterRow(left.data(), right.data(), column_pass, taps, cols, dst->ptr<float>(r));
  }
}

}  // namespace parallax
