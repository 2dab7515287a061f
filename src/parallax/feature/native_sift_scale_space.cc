// The Gaussian scale space of the native SIFT and the gradients of its layers.

#include <bit>
#include <cfloat>
#include <utility>

#include "parallax/feature/gaussian_blur.h"
#include "parallax/feature/native_sift_internal.h"
#include "parallax/feature/resample.h"

namespace parallax {
namespace native_sift_detail {
namespace {

// Magnitude and angle (radians in [0, 2 pi)) of the gradients (gx, gy) of one row's samples,
// the angle by the polynomial of OpenCV's fastAtan2 that cv::cartToPolar used here before (its
// largest error is about 0.01 degree), in one pass that the compiler vectorises: cartToPolar
// took the differences from buffers of their own, a band of rows at a time.
void PolarRow(const float* __restrict gx, const float* __restrict gy, int count,
              float* __restrict magnitude, float* __restrict angle) {
  constexpr float kDegrees = static_cast<float>(180 / CV_PI);
  constexpr float p1 = 0.9997878412794807f * kDegrees, p3 = -0.3258083974640975f * kDegrees,
                  p5 = 0.1555786518463281f * kDegrees, p7 = -0.04432655554792128f * kDegrees;
  constexpr float kEpsilon = static_cast<float>(DBL_EPSILON);
  constexpr float kRadians = static_cast<float>(CV_PI / 180);
  for (int i = 0; i < count; ++i) {
    const float x = gx[i], y = gy[i];
    magnitude[i] = std::sqrt(x * x + y * y);
    const float ax = std::abs(x), ay = std::abs(y);
    const float c = (ax < ay ? ax : ay) / ((ax > ay ? ax : ay) + kEpsilon);
    const float cc = c * c;
    float a = (((p7 * cc + p5) * cc + p3) * cc + p1) * c;
    a = ax >= ay ? a : 90.0f - a;
    a = x < 0 ? 180.0f - a : a;
    a = y < 0 ? 360.0f - a : a;
    angle[i] = a * kRadians;
  }
}

// Rows of the gradient's rings: a frame reads at most 2 R + 1 rows, R the largest radius
// (a frame of layer S + 1, the largest scale RefineExtremum keeps), and the band that
// LayerGradient computes last for it may end R + kGradientBandRows - 1 rows below its centre,
// while a later frame (further down) may read from R rows above its own.
int GradientRingRows(const NativeSiftOptions& options, cv::Size base_size) {
  const int layers = options.num_octave_layers;
  const float largest_scale =
      static_cast<float>(options.sigma * std::pow(2.0, (layers + 1.0f) / layers));
  const int radius = GradientRadius(largest_scale, base_size);
  return 2 * radius + kGradientBandRows + 1;
}

// Points every float image of the scale space (input, doubled input, each octave's
// Gaussian layers, the gradient's rings) into one huge-page block, laid out the same way for
// every image of a size, so that the same pages serve image after image. The first image of
// each thread pays to fault them in, so images used in different phases share memory: the
// input and its doubled copy are read only by the first octave's first blur, before layers

void LayOutBuffers(cv::Size input_size, cv::Size base_size, const NativeSiftOptions& options,
                   ScaleSpace* space) {
  const int layers = options.num_octave_layers;
  std::vector<std::pair<cv::Mat*, cv::Size>> layout;
  for (size_t o = 0; o < space->octaves.size(); ++o) {
    const cv::Size size(base_size.width >> o, base_size.height >> o);
    std::vector<cv::Mat>& gaussians = space->octaves[o].gaussians;
    gaussians.assign(layers + 3, cv::Mat());
    for (int k = 0; k <= layers + 1; ++k) layout.emplace_back(&gaussians[k], size);
  }
  const int ring_rows =
      static_cast<int>(std::bit_ceil(static_cast<unsigned>(GradientRingRows(options, base_size))));
  space->ring_mask = ring_rows - 1;
  // A layer of fewer rows has each in a row of its own (r & ring_mask == r). Padded by a
  // block of samples, which DescriptorSamples and OrientationSamples may read past a row's
  // last column.
  const cv::Size ring_size(base_size.width + kSampleLanes, std::min(ring_rows, base_size.height));
  layout.emplace_back(&space->magnitude_ring, ring_size);
  layout.emplace_back(&space->angle_ring, ring_size);
  // An image too small for one octave has no layers to share.
  const bool shared = !space->octaves.empty();
  if (!shared) {
    layout.emplace_back(&space->input, input_size);
    layout.emplace_back(&space->doubled, base_size);
  }

  constexpr size_t kAlignment = 64;
  const auto padded_bytes = [](cv::Size size) {
    const size_t bytes = sizeof(float) * static_cast<size_t>(size.area());
    return (bytes + kAlignment - 1) / kAlignment * kAlignment;
  };
  size_t total = 0;
  for (const auto& [mat, size] : layout) total += padded_bytes(size);
  auto* next = static_cast<unsigned char*>(space->memory.Reserve(total));
  for (const auto& [mat, size] : layout) {
    // A header over the block: create() with this size and type keeps it.
    *mat = cv::Mat(size, CV_32F, next);
    next += padded_bytes(size);
  }
  if (!shared) return;
  const std::vector<cv::Mat>& first = space->octaves.front().gaussians;
  space->input = cv::Mat(input_size, CV_32F, first[layers].data);
  space->doubled = cv::Mat(base_size, CV_32F, first[layers + 1].data);
}

}  // namespace

void LayerGradient::ComputeBand(int b) {
  const int col_begin = region_.ColumnBegin(b), col_end = region_.ColumnEnd(b);
  if (col_begin >= col_end) return;
  float* gx = space_->dx_row.data();
  float* gy = space_->dy_row.data();
  const int band = b * kGradientBandRows;
  const int band_rows = std::min(kGradientBandRows, image_.rows - band);
  for (int r = band; r < band + band_rows; ++r) {
    if (r == 0 || r + 1 == image_.rows) {
      std::fill(gx + col_begin, gx + col_end, 0.0f);
      std::fill(gy + col_begin, gy + col_end, 0.0f);
    } else {
      const float* above = image_.ptr<float>(r - 1);
      const float* row = image_.ptr<float>(r);
      const float* below = image_.ptr<float>(r + 1);
      // The layer was written before every octave's extrema were found, so its rows come
      // from memory, and each row's segment is too short for the hardware prefetcher to
      // get going: the next row's is asked for now (docs/performance.md,
      // "Gradients: the row after next prefetched").
      if (r + 2 < image_.rows) {
        const float* next = image_.ptr<float>(r + 2);
        for (int c = col_begin; c < col_end; c += 16) __builtin_prefetch(next + c);
      }
      for (int c = std::max(col_begin, 1); c < std::min(col_end, image_.cols - 1); ++c) {
        gx[c] = 0.5f * (row[c + 1] - row[c - 1]);
        gy[c] = 0.5f * (below[c] - above[c]);
      }
      if (col_begin == 0) gx[0] = gy[0] = 0;
      if (col_end == image_.cols) gx[image_.cols - 1] = gy[image_.cols - 1] = 0;
    }
    PolarRow(gx + col_begin, gy + col_begin, col_end - col_begin,
             gradient_.MutableMagnitude(r) + col_begin, gradient_.MutableAngle(r) + col_begin);
  }
}

// The base image of the scale space (the input as floats in [0, 1], doubled for octave -1)
// and the octaves' layout, with buffers sized for the first octave.
void PrepareScaleSpace(const cv::Mat& gray, const NativeSiftOptions& options, ScaleSpace* space) {
  const cv::Size base_size =
      options.double_first_octave ? cv::Size(2 * gray.cols, 2 * gray.rows) : gray.size();
  int num_octaves = 0;
  for (int rows = base_size.height, cols = base_size.width;
       std::min(rows, cols) >= kSmallestOctaveSide; rows /= 2, cols /= 2) {
    ++num_octaves;
  }
  const int layers = options.num_octave_layers;
  space->octaves.resize(num_octaves);
  LayOutBuffers(gray.size(), base_size, options, space);

  gray.convertTo(space->input, CV_32F, 1.0 / 255.0);
  space->base = space->input;
  // A camera image is taken to carry a blur of half a pixel already (Lowe's assumption).
  double input_blur = 0.5;
  space->first_octave = 0;
  if (options.double_first_octave) {
    UpsampleTwice(space->input, &space->doubled);
    space->base = space->doubled;
    input_blur = 1.0;
    space->first_octave = -1;
  }
  space->increments.assign(layers + 3, 0.0);
  for (int k = 1; k < layers + 3; ++k) {
    const double previous = options.sigma * std::pow(2.0, (k - 1.0) / layers);
    const double current = options.sigma * std::pow(2.0, static_cast<double>(k) / layers);
    space->increments[k] = std::sqrt(current * current - previous * previous);
  }
  space->first_blur =
      std::sqrt(std::max(options.sigma * options.sigma - input_blur * input_blur, 0.01));
}

// Builds octave o (after o - 1): layer k has sigma * 2^(k / S) in the octave's pixels, each
// layer blurred from the one below it, and the octave starts from the previous one's layer S
// (twice its first layer's blur) sampled at every other pixel. Calls layer_row_done(k, r) as
// row r of layer k >= 1 is written. The last layer, S + 2, is left to LastLayer.
void BuildOctave(int o, ScaleSpace* space,
                 const std::function<void(int layer, int row)>& layer_row_done) {
  Octave& octave = space->octaves[o];
  const int num_layers = static_cast<int>(space->increments.size());
  octave.index = space->first_octave + o;
  octave.gaussians.resize(num_layers);
  if (o == 0) {
    GaussianBlur(space->base, space->first_blur, &octave.gaussians[0]);
  } else {
    const cv::Mat& previous = space->octaves[o - 1].gaussians[num_layers - 3];
    SampleEveryOther(previous, &octave.gaussians[0]);
  }
  for (int k = 1; k + 1 < num_layers; ++k) {
    GaussianBlur(octave.gaussians[k - 1], space->increments[k], &octave.gaussians[k],
                 [&](int row) { layer_row_done(k, row); });
  }
}

}  // namespace native_sift_detail
}  // namespace parallax
