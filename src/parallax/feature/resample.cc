#include "parallax/feature/resample.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "parallax/util/check.h"

// Compiled with -ffp-contract=off (CMakeLists.txt): each product is rounded before the sum, as
// in OpenCV's resize, which a fused multiply-add would not match.

namespace parallax {
namespace {

constexpr float kNear = 0.75f, kFar = 0.25f;

// One input row upsampled along x: output 2 i + 1 lies between inputs i and i + 1 at a
// quarter from i, output 2 i + 2 at three quarters; the first and last outputs are the edge
// inputs.
void UpsampleRow(const float* __restrict in, int width, float* __restrict out) {
  out[0] = in[0];
  for (int i = 0; i + 1 < width; ++i) {
    out[2 * i + 1] = in[i] * kNear + in[i + 1] * kFar;
    out[2 * i + 2] = in[i] * kFar + in[i + 1] * kNear;
  }
  out[2 * width - 1] = in[width - 1];
}

void BlendRows(const float* __restrict upper, float upper_weight, const float* __restrict lower,
               float lower_weight, int width, float* __restrict out) {
  for (int x = 0; x < width; ++x) out[x] = upper[x] * upper_weight + lower[x] * lower_weight;
}

}  // namespace

void UpsampleTwice(const cv::Mat& src, cv::Mat* dst) {
  PARALLAX_CHECK(dst != nullptr);
  PARALLAX_CHECK_EQ(src.type(), CV_32F);
  PARALLAX_CHECK(dst->data == nullptr || dst->data != src.data);
  dst->create(2 * src.rows, 2 * src.cols, CV_32F);
  if (src.empty()) return;
  const int width = 2 * src.cols;
  // The last two input rows upsampled along x, and which they are.
  std::array<std::vector<float>, 2> rows = {std::vector<float>(width), std::vector<float>(width)};
  std::array<int, 2> row_of = {-1, -1};
  const auto upsampled = [&](int y) -> const float* {
    for (int k = 0; k < 2; ++k) {
      if (row_of[k] == y) return rows[k].data();
    }
    const int k = row_of[0] < row_of[1] ? 0 : 1;  // The older.
    UpsampleRow(src.ptr<float>(y), src.cols, rows[k].data());
    row_of[k] = y;
    return rows[k].data();
  };
  for (int y = 0; y < dst->rows; ++y) {
    // OpenCV's rows and weights: below the first row's centre both rows are row 0 (weights
    // 1 and 0); past the last both are the last row, at the weights of the position.
    float position = (y + 0.5f) * 0.5f - 0.5f;
    int upper = static_cast<int>(std::floor(position));
    float fraction = position - upper;
    if (upper < 0) {
      upper = 0;
      fraction = 0;
    }
    const int lower = std::min(upper + 1, src.rows - 1);
    upper = std::min(upper, src.rows - 1);
    const float* upper_row = upsampled(upper);
    const float* lower_row = upsampled(lower);
    BlendRows(upper_row, 1.0f - fraction, lower_row, fraction, width, dst->ptr<float>(y));
  }
}

void SampleEveryOther(const cv::Mat& src, cv::Mat* dst) {
  PARALLAX_CHECK(dst != nullptr);
  PARALLAX_CHECK_EQ(src.type(), CV_32F);
  PARALLAX_CHECK(dst->data == nullptr || dst->data != src.data);
  dst->create(src.rows / 2, src.cols / 2, CV_32F);
  for (int y = 0; y < dst->rows; ++y) {
    const float* __restrict in = src.ptr<float>(2 * y);
    float* __restrict out = dst->ptr<float>(y);
    for (int x = 0; x < dst->cols; ++x) out[x] = in[2 * x];
  }
}

}  // namespace parallax
