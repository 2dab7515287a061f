#pragma once

#include <functional>
#include <opencv2/core.hpp>
#include <vector>

#include "parallax/feature/float8.h"

namespace parallax {

// The widest vectors the blur may use. A wider vector's lanes run the same operations in the
// same order, so either gives the same floats: kWidest takes AVX-512 where the x86-64 CPU has
// it (a little less CPU time, the passes being mostly bound by their loads: docs/portable-build.md,
// "What the default build targets"), kBuild the build's vectors alone (tests compare the two).
enum class BlurVectors { kBuild, kWidest };

// True when kWidest blurs with AVX-512 here.
bool BlurHasAvx512();

// Taps of the Gaussian kernel GaussianBlur uses for `sigma`: OpenCV's for float images
// (2 round(4 sigma) + 1 taps, normalised to sum 1), centre first, then one side (the kernel
// is symmetric).
std::vector<float> GaussianHalfKernel(double sigma);

// Blurs a CV_32F image by the Gaussian of `sigma` with replicated borders, as
// cv::GaussianBlur(src, dst, Size(), sigma, sigma, BORDER_REPLICATE) does with the same kernel,
// up to float rounding; a view of a larger image is blurred as an image of its own. SIFT's scale
// space is mostly this blur; OpenCV's filter engine copies every row into a bordered buffer and
// sums the horizontal pass without the kernel's symmetry, and was slower (docs/defaults.md,
// "Parallax's own SIFT"). Four output rows at a time: their vertical pass into padded rows that
// stay in L1, then the horizontal pass from each. `dst` must not share data with `src`. `row_done`,
// when given, is called with each row of `dst` once it is written, in order, while the row is still
// in cache (and the same row of `src`, which the vertical pass has just read).
void GaussianBlur(const cv::Mat& src, double sigma, cv::Mat* dst,
                  const std::function<void(int row)>& row_done = nullptr,
                  BlurVectors vectors = BlurVectors::kWidest);

// GaussianBlur's values inside chosen windows of the image alone, the same floats, for an image
// of which only a few samples are read. Keeps a reference to `src`'s data.
class WindowedGaussianBlur {
 public:
  WindowedGaussianBlur(const cv::Mat& src, double sigma,
                       BlurVectors vectors = BlurVectors::kWidest);

  // Writes (*dst)(window) as GaussianBlur(src, sigma, dst) would, and nothing else of `dst`,
  // which has src's size and type and does not share its data. `row_done` as for GaussianBlur,
  // with the window's rows.
  void Blur(cv::Rect window, cv::Mat* dst, const std::function<void(int row)>& row_done = nullptr);
  // The same into a buffer of the window's own: sample (x, y) of the window at
  // out[(y - window.y) * out_stride + x - window.x].
  void Blur(cv::Rect window, float* out, size_t out_stride,
            const std::function<void(int row)>& row_done = nullptr);

 private:
  cv::Mat src_;
  bool avx512_ = false;  // Blur with AVX-512 (kWidest, on a CPU that has it).
  int radius_ = 0;
  std::vector<Float8> half_taps_;     // Centre first, each broadcast to a vector.
  std::vector<float> padded_kernel_;  // All taps, with zeros on either side.
  std::vector<float> vertical_;       // The vertical pass's rows.
  std::vector<const float*> inputs_;  // The input rows of one vertical step, and the next's.
};

}  // namespace parallax
