#include "parallax/feature/native_sift.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <utility>
#include <vector>

#include "parallax/feature/float8.h"
#include "parallax/feature/gaussian_blur.h"
#include "parallax/feature/resample.h"
#include "parallax/util/check.h"
#include "parallax/util/huge_page_buffer.h"

namespace parallax {
namespace {

constexpr float kTwoPi = 6.283185307179586f;
// Extrema are searched up to one sample from an octave's edge, as VLFeat does (OpenCV keeps
// five away, which costs a coarse octave a wide frame of its image).
constexpr int kImageBorder = 1;
constexpr int kSmallestOctaveSide = 8;
constexpr int kMaxRefinementFits = 5;  // Samples an extremum's quadratic fit may try.
// The fit moves to a neighbouring sample when its extremum is this far off; after the last
// move it must lie within kMaxFinalOffset of the sample it settled on.
constexpr float kMoveOffset = 0.6f;
constexpr float kMaxFinalOffset = 1.5f;
constexpr int kOrientationBins = 36;
// Orientation histograms are padded by a bin on each side (FrameOrientations), and
// successive samples of a row take turns adding to kOrientationCopies copies of them.
constexpr int kPaddedOrientationBins = kOrientationBins + 2;
constexpr int kOrientationCopies = 4;
constexpr float kOrientationWindow = 1.5f;  // Window sigma, in units of the frame's scale.
constexpr int kOrientationSmoothing = 6;    // Passes of a circular [1 1 1] / 3 box filter.
constexpr float kOrientationPeakRatio = 0.8f;
constexpr int kDescriptorGrid = 4;  // Spatial bins per side.
constexpr int kDescriptorOrientations = 8;
constexpr int kDescriptorSize = kDescriptorGrid * kDescriptorGrid * kDescriptorOrientations;
constexpr float kDescriptorMagnification = 3.0f;  // Bin side, in units of the frame's scale.
constexpr float kDescriptorClamp = 0.2f;
// A descriptor's histogram is padded by one cell on every side, so that each sample's adds
// need no bounds checks; a cell's eight orientations are one Float8.
constexpr int kPaddedGrid = kDescriptorGrid + 2;
constexpr int kDescriptorHistogramSize = kPaddedGrid * kPaddedGrid * kDescriptorOrientations;
// Copies of the histogram that successive samples of a row take turns adding to (sample i to
// copy i % kDescriptorCopies): a row's samples stay in one cell for five to ten steps, and
// each add waits for the last add to its copy's cell to land (a store forwarded to a load,
// then a multiply-add). Four beat two, and eight beat four once the adds ran in one loop over
// many rows (AddDescriptorSamples; docs/performance.md, "Descriptor: histogram copies").
constexpr int kDescriptorCopies = 8;
static_assert((kDescriptorCopies & (kDescriptorCopies - 1)) == 0, "a power of two");
// A descriptor's samples are computed a Float8 at a time (DescriptorSamples), and sample
// i's copy is i % kDescriptorCopies, the same in every block.
constexpr int kSampleLanes = 8;
static_assert(kSampleLanes % kDescriptorCopies == 0 && kSampleLanes % kOrientationCopies == 0);
static_assert(kDescriptorSize == 128);
static_assert(kDescriptorOrientations == 8);

// One octave of the scale space: S + 3 Gaussian layers.
struct Octave {
  int index = 0;  // Pixel size of this octave is 2^index input pixels (-1: doubled image).
  std::vector<cv::Mat> gaussians;
};

// Gradient magnitude and angle (radians in [0, 2 pi)) of one Gaussian layer of rows x cols:
// row r in row r & ring_mask of two rings of rows, which hold the rows that the frames being
// described read (LayerGradient).
struct Gradient {
  int rows = 0, cols = 0;
  cv::Mat magnitude_ring, angle_ring;
  int ring_mask = 0;

  cv::Size size() const { return {cols, rows}; }
  const float* Magnitude(int r) const { return magnitude_ring.ptr<float>(r & ring_mask); }
  const float* Angle(int r) const { return angle_ring.ptr<float>(r & ring_mask); }
  float* MutableMagnitude(int r) { return magnitude_ring.ptr<float>(r & ring_mask); }
  float* MutableAngle(int r) { return angle_ring.ptr<float>(r & ring_mask); }
};

// One row of a descriptor's samples (FrameDescriptor): the bin its first sample falls in,
// where its columns start in the gradient and the window, and its first sample's index.
struct DescriptorRow {
  float bin_x, bin_y;
  const float* angle;
  const float* magnitude;
  const float* window_x;
  float window_y;
  int first_sample;
};

// Eight samples of a row, from its column `column` on.
struct DescriptorBlock {
  int row, column;
};

// The buffers that each frame's orientations and descriptor are computed in, kept from frame
// to frame: allocating them for each frame was a percent of extraction. Grown, never shrunk
// (Reserve): a vector's resize up from a smaller frame's size would zero what it adds.
struct FrameScratch {
  std::vector<float> weights_x, weights_y;  // The Gaussian window (GaussianWeights).
  std::vector<float> samples;               // Samples' bins and weights, array by array.
  std::vector<int32_t> offsets;             // Their histogram cells (FrameDescriptor).
  std::vector<DescriptorRow> rows;          // FrameDescriptor's.
  std::vector<DescriptorBlock> blocks;

  template <typename T>
  static T* Reserve(size_t size, std::vector<T>* buffer) {
    if (buffer->size() < size) buffer->resize(size);
    return buffer->data();
  }
};

}  // namespace

// The Gaussian scale space of one image, and the buffers it is built in (NativeSiftBuffers
// keeps one between images).
struct NativeSiftScaleSpace {
  cv::Mat input, doubled;
  cv::Mat base;  // input or doubled.
  int first_octave = 0;
  std::vector<double> increments;  // Blur from layer k - 1 to layer k.
  double first_blur = 0;           // Blur from the base image to the first layer.
  std::vector<Octave> octaves;
  // Three rows of one difference of Gaussians and of their RowExtremes, where the extrema
  // screen reads them.
  std::vector<float> dog_rows;
  // The gradient's rings (Gradient), as wide as the first octave, of a power of two rows
  // (fewer where the first octave has fewer rows).
  cv::Mat magnitude_ring, angle_ring;
  int ring_mask = 0;
  std::vector<float> dx_row, dy_row;  // One row of differences, before PolarRow.
  FrameScratch frame_scratch;         // FrameOrientations' and FrameDescriptor's.
  HugePageBuffer memory;              // Holds every cv::Mat above.
};

namespace {

using ScaleSpace = NativeSiftScaleSpace;

constexpr int kGradientBandRows = 16;

// The columns of each band of kGradientBandRows rows of a layer that some frame reads
// (empty where none does): on a photo whose texture fills part of the frame, most of a
// layer's gradient is never read.
class GradientRegion {
 public:
  explicit GradientRegion(cv::Size layer_size)
      : layer_size_(layer_size),
        begin_((layer_size.height + kGradientBandRows - 1) / kGradientBandRows, layer_size.width),
        end_(begin_.size(), 0) {}

  // The square of half-side `radius` around (xi, yi).
  void AddSquare(int xi, int yi, int radius) {
    const int row_begin = std::max(0, yi - radius);
    const int row_end = std::min(layer_size_.height - 1, yi + radius);
    const int col_begin = std::max(0, xi - radius);
    const int col_end = std::min(layer_size_.width - 1, xi + radius) + 1;
    if (row_begin > row_end || col_begin >= col_end) return;
    for (int band = row_begin / kGradientBandRows; band <= row_end / kGradientBandRows; ++band) {
      begin_[band] = std::min(begin_[band], col_begin);
      end_[band] = std::max(end_[band], col_end);
    }
  }
  int NumBands() const { return static_cast<int>(begin_.size()); }
  int ColumnBegin(int band) const { return begin_[band]; }
  int ColumnEnd(int band) const { return end_[band]; }

 private:
  cv::Size layer_size_;
  std::vector<int> begin_, end_;
};

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

// The gradient of one Gaussian layer, by central differences (zero on the one-pixel border),
// in the shared rings, computed only in `region` (elsewhere the rings hold whatever they
// held), band by band as the layer's frames reach them in scan order: each band is read while
// it is still in cache, where a gradient computed for the whole layer first came back from
// memory for every frame. The rings hold the rows of the frames at hand, where whole images
// of magnitude and angle were two more layers to fault in.
class LayerGradient {
 public:
  LayerGradient(const cv::Mat& image, const GradientRegion& region, ScaleSpace* space)
      : image_(image),
        region_(region),
        gradient_{image.rows, image.cols, space->magnitude_ring, space->angle_ring,
                  space->ring_mask},
        space_(space) {
    space->dx_row.resize(space->magnitude_ring.cols);
    space->dy_row.resize(space->magnitude_ring.cols);
  }

  // The gradient, computed at least through row `last_row` of the region, for a frame that
  // reads rows `first_row` to `last_row` (frames come in the order of their rows).
  const Gradient& Through(int first_row, int last_row) {
    const int last_band = std::min(last_row / kGradientBandRows, region_.NumBands() - 1);
    for (; next_band_ <= last_band; ++next_band_) ComputeBand(next_band_);
    // The ring still holds the frame's first row (GradientRingRows).
    PARALLAX_CHECK_LE(
        std::min(next_band_ * kGradientBandRows, image_.rows) - std::max(first_row, 0),
        gradient_.magnitude_ring.rows);
    return gradient_;
  }

 private:
  void ComputeBand(int b) {
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

  const cv::Mat& image_;
  const GradientRegion& region_;
  Gradient gradient_;
  ScaleSpace* space_;
  int next_band_ = 0;
};

// Half-sides of the square of gradient samples around (round(x), round(y)) that a frame's
// orientation histogram and its descriptor read.
int OrientationRadius(float octave_scale) {
  return std::max(1, static_cast<int>(std::lround(3.0f * kOrientationWindow * octave_scale)));
}

int DescriptorRadius(float octave_scale, cv::Size layer_size) {
  const float bin_side = kDescriptorMagnification * octave_scale;
  const int max_radius = static_cast<int>(std::sqrt(static_cast<float>(
      layer_size.height * layer_size.height + layer_size.width * layer_size.width)));
  return std::min(max_radius, static_cast<int>(std::lround(bin_side * std::sqrt(2.0f) *
                                                           (kDescriptorGrid + 1) * 0.5f)));
}

// Half-side of the square of gradient samples a frame reads, for both.
int GradientRadius(float octave_scale, cv::Size layer_size) {
  return std::max(OrientationRadius(octave_scale), DescriptorRadius(octave_scale, layer_size));
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
// S and S + 1 are written over them. Layer S + 2 has no memory (LastLayer).
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

// The last Gaussian layer of an octave, S + 2, enters only difference S + 1, which is read only
// around the samples of difference S that pass the screen: by the test across scales and by
// the extremum's refinement, 3 x 3 samples at a time. It is blurred there alone, into a window
// of its own, the floats a blur of the whole layer writes: that blur, the widest of the
// octave's, was a quarter of them, and the layer another image to fault in.
class LastLayer {
 public:
  LastLayer(const std::vector<cv::Mat>& gaussians, double increment)
      : blur_(gaussians[gaussians.size() - 2], increment),
        last_difference_(static_cast<int>(gaussians.size()) - 2) {}

  int last_difference() const { return last_difference_; }

  // Before difference `layer` is read in the 3 x 3 samples around (r, c), one sample or more
  // inside the octave's edges.
  void PrepareAround(int layer, int r, int c) {
    if (layer != last_difference_ || (r == row_ && c == col_)) return;
    blur_.Blur(cv::Rect(c - 1, r - 1, kSide, kSide), window_.data(), kStride);
    row_ = r;
    col_ = c;
  }

  // The layer from (r, c) on along the row, within a sample of where it was last prepared
  // (four floats may be read from it).
  const float* Samples(int r, int c) const {
    return window_.data() + (r - row_ + 1) * kStride + (c - col_ + 1);
  }

 private:
  static constexpr int kSide = 3, kStride = 4;
  WindowedGaussianBlur blur_;
  const int last_difference_;
  std::array<float, kSide * kStride> window_{};
  int row_ = -1, col_ = -1;  // Where it was prepared last.
};

// The differences of Gaussians of one octave, read from its layers where they are needed:
// difference k is layer k + 1 minus layer k, the float a blur storing it would have stored.
// Kept in buffers of their own, they were five more images per thread to fault in and five
// more streams of stores per octave.
class Differences {
 public:
  // Difference S + 1 is read through `last_layer`, and only where it was prepared; without
  // one, only differences 0 to S are read.
  explicit Differences(const std::vector<cv::Mat>& gaussians, const LastLayer* last_layer = nullptr)
      : gaussians_(gaussians), last_layer_(last_layer) {}
  int rows() const { return gaussians_[0].rows; }
  int cols() const { return gaussians_[0].cols; }
  float At(int layer, int r, int c) const { return *Upper(layer, r, c) - Lower(layer, r, c)[0]; }
  // Samples c to c + 2 of row r in lanes 0 to 2; lane 3 holds whatever follows (the layers
  // lie in one block with the gradient's rings after them, so it is always there to read).
  Float4 ThreeAt(int layer, int r, int c) const {
    return Load4(Upper(layer, r, c)) - Load4(Lower(layer, r, c));
  }
  void Row(int layer, int r, float* __restrict out) const {
    const float* __restrict upper = gaussians_[layer + 1].ptr<float>(r);
    const float* __restrict lower = gaussians_[layer].ptr<float>(r);
    for (int c = 0; c < cols(); ++c) out[c] = upper[c] - lower[c];
  }

 private:
  const float* Upper(int layer, int r, int c) const {
    return last_layer_ != nullptr && layer == last_layer_->last_difference()
               ? last_layer_->Samples(r, c)
               : gaussians_[layer + 1].ptr<float>(r) + c;
  }
  const float* Lower(int layer, int r, int c) const { return gaussians_[layer].ptr<float>(r) + c; }

  const std::vector<cv::Mat>& gaussians_;
  const LastLayer* const last_layer_;
};

// An extremum refined to sub-sample precision in (column, row, layer).
struct Extremum {
  int layer = 0, row = 0, col = 0;
  float offset_col = 0, offset_row = 0, offset_layer = 0;
  float value = 0;  // Interpolated DoG at the refined position.
};

// Whether the sample is at least as large (positive) or as small (negative) as its 18
// neighbours in the layers above and below. ScreenRow has already compared it with the 8 in
// its own layer: together, Lowe's 26-neighbour test.
bool IsExtremumAcrossScales(const Differences& dogs, int layer, int r, int c,
                            LastLayer* last_layer) {
  const float value = dogs.At(layer, r, c);
  // Three neighbours at a time, without a branch each (taken or not at random, they were
  // most of this test's time).
  const auto beaten_in = [&](int other) {
    Int4 beaten = {};
    for (int rr = r - 1; rr <= r + 1; ++rr) {
      const Float4 neighbours = dogs.ThreeAt(other, rr, c - 1);
      beaten |= value > 0 ? neighbours > value : neighbours < value;
    }
    return (MoveMask4(beaten) & 0b111) != 0;
  };
  if (beaten_in(layer - 1)) return false;
  last_layer->PrepareAround(layer + 1, r, c);
  return !beaten_in(layer + 1);
}

// Ternaries, not std::max/min, which the compiler does not turn into vector max/min.
inline float Max2(float a, float b) { return a > b ? a : b; }
inline float Min2(float a, float b) { return a < b ? a : b; }

// The largest and smallest of each sample and its two neighbours along a row of a difference
// (columns 1 to cols - 2): the screens of the row above, the row itself and the row below
// share them.
void RowExtremes(const float* __restrict row, int cols, float* __restrict largest,
                 float* __restrict smallest) {
  for (int c = 1; c + 1 < cols; ++c) {
    largest[c] = Max2(Max2(row[c - 1], row[c]), row[c + 1]);
    smallest[c] = Min2(Min2(row[c - 1], row[c]), row[c + 1]);
  }
}

// A sample of a difference of Gaussians that passed ScreenRow.
struct ScreenedSample {
  int layer = 0, row = 0, col = 0;
};

// Appends to `samples` the samples (layer, r, c) of row r of a difference, columns 1 to
// cols - 2, that pass the contrast screen and are extrema of the 3 x 3 samples around them in
// their own layer: the cheap tests, eight samples at a time, so that IsExtremumAcrossScales
// sees a few samples of each row instead of all. Takes row r and the RowExtremes of rows
// r - 1, r and r + 1: a sample is at least its eight neighbours exactly when it is at least
// the largest of those three (its own row's include itself), two comparisons where the eight
// took seven. Most rows have no candidate: a bit per sample (MoveMask8) skips eight at once,
// where a byte per sample took another pass to write and one to scan.
static_assert(kImageBorder == 1, "ScreenRow screens columns 1 to cols - 2");
void ScreenRow(const float* __restrict row, const float* __restrict largest_above,
               const float* __restrict largest_at, const float* __restrict largest_below,
               const float* __restrict smallest_above, const float* __restrict smallest_at,
               const float* __restrict smallest_below, int cols, float screen, int layer, int r,
               std::vector<ScreenedSample>* samples) {
  const Float8 above_screen = Float8{} + screen, below_screen = Float8{} - screen;
  int c = 1;
  for (; c + 8 <= cols - 1; c += 8) {
    const Float8 v = Load8(row + c);
    const Int8 above = v > above_screen, below = v < below_screen;
    // Most samples are below the screen (the whole of a plain background): their neighbours
    // are not loaded.
    if (MoveMask8(above | below) == 0) continue;
    const Float8 around_max =
        Max8(Max8(Load8(largest_above + c), Load8(largest_at + c)), Load8(largest_below + c));
    const Float8 around_min =
        Min8(Min8(Load8(smallest_above + c), Load8(smallest_at + c)), Load8(smallest_below + c));
    const Int8 hits = (above & (v >= around_max)) | (below & (v <= around_min));
    for (uint32_t mask = MoveMask8(hits); mask != 0; mask &= mask - 1) {
      samples->push_back({layer, r, c + std::countr_zero(mask)});
    }
  }
  for (; c < cols - 1; ++c) {
    const float v = row[c];
    const float around_max = Max2(Max2(largest_above[c], largest_at[c]), largest_below[c]);
    const float around_min = Min2(Min2(smallest_above[c], smallest_at[c]), smallest_below[c]);
    if ((v > screen && v >= around_max) || (v < -screen && v <= around_min)) {
      samples->push_back({layer, r, c});
    }
  }
}

// Screens differences 1 to S of an octave while BuildOctave blurs it: row r - 1 of difference
// k - 1 as soon as row r of layer k is written, while that row and the same row of layer k - 1
// (which the blur has just read) are in cache. Screened after the octave was built, the two
// rows of every difference came back from memory, which was slower (docs/defaults.md,
// "Parallax's own SIFT"). The test across scales also reads difference k, not yet made, so it waits
// for the whole octave.
class DogScreen {
 public:
  DogScreen(const std::vector<cv::Mat>& gaussians, int num_octave_layers, float screen,
            ScaleSpace* space)
      : dogs_(gaussians), num_octave_layers_(num_octave_layers), screen_(screen), space_(space) {
    space_->dog_rows.resize(3 * kRingRows * static_cast<size_t>(dogs_.cols()));
  }

  void LayerRowDone(int layer, int r) {
    const int dog = layer - 1;
    if (dog < 1 || dog > num_octave_layers_) return;
    const int rows = dogs_.rows(), cols = dogs_.cols();
    dogs_.Row(dog, r, RingRow(kDifference, r));
    RowExtremes(RingRow(kDifference, r), cols, RingRow(kLargest, r), RingRow(kSmallest, r));
    const int centre = r - 1;
    if (centre < kImageBorder || centre >= rows - kImageBorder) return;
    ScreenRow(RingRow(kDifference, centre), RingRow(kLargest, centre - 1),
              RingRow(kLargest, centre), RingRow(kLargest, centre + 1),
              RingRow(kSmallest, centre - 1), RingRow(kSmallest, centre),
              RingRow(kSmallest, centre + 1), cols, screen_, dog, centre, &samples_);
  }

  // In the order of a scan by difference, row and column.
  const std::vector<ScreenedSample>& samples() const { return samples_; }

 private:
  // Row r of the difference, or of its RowExtremes, each in a ring of three rows.
  enum Ring { kDifference = 0, kLargest = 1, kSmallest = 2 };
  static constexpr int kRingRows = 3;
  float* RingRow(Ring ring, int r) {
    return space_->dog_rows.data() + (ring * kRingRows + r % kRingRows) * dogs_.cols();
  }

  const Differences dogs_;
  const int num_octave_layers_;
  const float screen_;
  ScaleSpace* const space_;
  std::vector<ScreenedSample> samples_;
};

// First and second derivatives of the DoG at a sample, by central differences in (column,
// row, layer).
struct DogDerivatives {
  float value = 0;
  float gradient[3] = {0, 0, 0};
  float dxx = 0, dyy = 0, dss = 0, dxy = 0, dxs = 0, dys = 0;
};

DogDerivatives DerivativesAt(const Differences& dogs, int layer, int r, int c) {
  const auto at = [&](int dl, int dr, int dc) { return dogs.At(layer + dl, r + dr, c + dc); };
  DogDerivatives d;
  d.value = at(0, 0, 0);
  const float v2 = 2.0f * d.value;
  d.gradient[0] = 0.5f * (at(0, 0, 1) - at(0, 0, -1));
  d.gradient[1] = 0.5f * (at(0, 1, 0) - at(0, -1, 0));
  d.gradient[2] = 0.5f * (at(1, 0, 0) - at(-1, 0, 0));
  d.dxx = at(0, 0, 1) + at(0, 0, -1) - v2;
  d.dyy = at(0, 1, 0) + at(0, -1, 0) - v2;
  d.dss = at(1, 0, 0) + at(-1, 0, 0) - v2;
  d.dxy = 0.25f * (at(0, 1, 1) - at(0, 1, -1) - at(0, -1, 1) + at(0, -1, -1));
  d.dxs = 0.25f * (at(1, 0, 1) - at(1, 0, -1) - at(-1, 0, 1) + at(-1, 0, -1));
  d.dys = 0.25f * (at(1, 1, 0) - at(1, -1, 0) - at(-1, 1, 0) + at(-1, -1, 0));
  return d;
}

// Fits a quadratic to the DoG around the sample (Lowe 2004, section 4) and moves to the
// neighbouring sample in x and y when the fit's extremum lies more than 0.6 samples towards
// it (VLFeat's rule: the layer stays), fitting up to five samples; the last fit is always
// at the sample it ends on. False when that fit is 1.5 samples or more away, outside the
// octave's scales, of low contrast, or on an edge.
bool RefineExtremum(const Differences& dogs, const NativeSiftOptions& options,
                    LastLayer* last_layer, Extremum* extremum) {
  const int layers = options.num_octave_layers;
  const int rows = dogs.rows(), cols = dogs.cols();
  const int layer = extremum->layer;
  int r = extremum->row, c = extremum->col;
  DogDerivatives d;
  float offset[3] = {0, 0, 0};
  for (int fit = 1;; ++fit) {
    last_layer->PrepareAround(layer + 1, r, c);
    d = DerivativesAt(dogs, layer, r, c);
    // Solve H offset = -gradient by Cramer's rule (H is 3x3 symmetric).
    const float c00 = d.dyy * d.dss - d.dys * d.dys, c01 = d.dxs * d.dys - d.dxy * d.dss,
                c02 = d.dxy * d.dys - d.dxs * d.dyy;
    const float det = d.dxx * c00 + d.dxy * c01 + d.dxs * c02;
    if (std::abs(det) < 1e-12f) return false;
    const float c11 = d.dxx * d.dss - d.dxs * d.dxs, c12 = d.dxy * d.dxs - d.dxx * d.dys,
                c22 = d.dxx * d.dyy - d.dxy * d.dxy;
    const float inv = -1.0f / det;
    const float* g = d.gradient;
    offset[0] = inv * (c00 * g[0] + c01 * g[1] + c02 * g[2]);
    offset[1] = inv * (c01 * g[0] + c11 * g[1] + c12 * g[2]);
    offset[2] = inv * (c02 * g[0] + c12 * g[1] + c22 * g[2]);
    const int move_col = offset[0] > kMoveOffset ? 1 : (offset[0] < -kMoveOffset ? -1 : 0);
    const int move_row = offset[1] > kMoveOffset ? 1 : (offset[1] < -kMoveOffset ? -1 : 0);
    if ((move_col == 0 && move_row == 0) || fit == kMaxRefinementFits) break;
    if (c + move_col < kImageBorder || c + move_col >= cols - kImageBorder ||
        r + move_row < kImageBorder || r + move_row >= rows - kImageBorder) {
      break;
    }
    c += move_col;
    r += move_row;
  }
  if (std::abs(offset[0]) >= kMaxFinalOffset || std::abs(offset[1]) >= kMaxFinalOffset ||
      std::abs(offset[2]) >= kMaxFinalOffset) {
    return false;
  }
  const float layer_position = layer + offset[2];
  if (layer_position < 0.0f || layer_position > layers + 1.0f) return false;

  const float value = d.value + 0.5f * (d.gradient[0] * offset[0] + d.gradient[1] * offset[1] +
                                        d.gradient[2] * offset[2]);
  if (std::abs(value) * layers < options.contrast_threshold) return false;

  // Edge test on the 2x2 spatial Hessian: tr^2 / det < (r + 1)^2 / r.
  const float trace = d.dxx + d.dyy, det = d.dxx * d.dyy - d.dxy * d.dxy;
  const float edge = static_cast<float>(options.edge_threshold);
  if (det <= 0 || trace * trace * edge >= (edge + 1) * (edge + 1) * det) return false;

  *extremum = {layer, r, c, offset[0], offset[1], offset[2], value};
  return true;
}

// Gaussian weights exp(-d^2 / (2 sigma^2)) for d = i - fraction, i = -radius..radius: a 2D
// Gaussian window is the product of two of these. Three exponentials instead of 2 radius + 1:
// neighbouring weights differ by the factor exp(-(2 d + 1) / (2 sigma^2)), which itself
// changes by exp(-1 / sigma^2) from one to the next; in double, so that the products lose
// nothing a float keeps (docs/performance.md, "Gaussian window weights from three exponentials").
const float* GaussianWeights(int radius, float fraction, float sigma, std::vector<float>* weights) {
  // Zeros after the last weight, for the last block of a row in DescriptorSamples and
  // OrientationSamples.
  float* w = FrameScratch::Reserve(2 * radius + kSampleLanes, weights);
  const double scale = -0.5 / (static_cast<double>(sigma) * sigma);
  const double first = -radius - static_cast<double>(fraction);
  double weight = std::exp(scale * first * first);
  double ratio = std::exp(scale * (2 * first + 1));
  const double ratio_step = std::exp(2 * scale);
  for (int i = 0; i <= 2 * radius; ++i) {
    w[i] = static_cast<float>(weight);
    weight *= ratio;
    ratio *= ratio_step;
  }
  std::fill(w + 2 * radius + 1, w + 2 * radius + kSampleLanes, 0.0f);
  return w;
}

// The orientation-histogram entries of `count` samples along a row, eight at a time (reading
// and writing past `count` as DescriptorSamples does): for each, the offset in the padded
// histograms of the bin below its angle (bin k of 36 centred on (k + 0.5) 10 degrees is at
// k + 1; index 0 is bin 35 and index 37 bin 0, folded in afterwards; in copy
// i % kOrientationCopies), and its weight's parts for that bin and the one above.
void OrientationSamples(int count, const float* angle, const float* magnitude,
                        const float* window_x, float window_y, int32_t* sample_offset,
                        float* sample_lower, float* sample_upper) {
  const Float8 zero = {};
  const Int8 copy_offset =
      (Int8{0, 1, 2, 3, 4, 5, 6, 7} & (kOrientationCopies - 1)) * kPaddedOrientationBins;
  for (int i = 0; i < count; i += kSampleLanes) {
    const Float8 bin = kOrientationBins * Load8(angle + i) / kTwoPi - 0.5f;
    const Float8 lower = Floor8(bin);
    const Float8 share = bin - lower;
    // lower + 1 is an exact integer in [0, 36].
    const Int8 offset = __builtin_convertvector(lower + 1.0f, Int8) + copy_offset;
    std::memcpy(sample_offset + i, &offset, sizeof(offset));
    const Float8 weight = (Load8(magnitude + i) * Load8(window_x + i)) * (zero + window_y);
    const Float8 upper = share * weight;
    Store8(sample_upper + i, upper);
    Store8(sample_lower + i, weight - upper);
  }
}

// Dominant gradient orientations around a frame: a 36-bin histogram of gradient directions
// weighted by magnitude and a Gaussian window, smoothed, whose peaks within 80 % of the
// highest become orientations (interpolated by a parabola), strongest first.
std::vector<float> FrameOrientations(const Gradient& gradient, float x, float y, float octave_scale,
                                     int max_orientations, FrameScratch* scratch) {
  const float window_sigma = kOrientationWindow * octave_scale;
  const int radius = OrientationRadius(octave_scale);
  const int xi = static_cast<int>(std::lround(x)), yi = static_cast<int>(std::lround(y));
  const float* weights_x = GaussianWeights(radius, x - xi, window_sigma, &scratch->weights_x);
  const float* weights_y = GaussianWeights(radius, y - yi, window_sigma, &scratch->weights_y);

  // Every row's samples first (OrientationSamples), then their adds. Each sample adds to
  // two bins: in two histograms (one for the bin below, one for the bin above), so that each
  // add is a float of its own; both in one, the compiler paired them (one 8-byte add), and
  // a pair's load that overlapped an earlier pair's store half waited for it to leave the
  // store buffer.
  const size_t max_samples =
      static_cast<size_t>(2 * radius + 1) * (2 * radius + 1) + kSampleLanes - 1;
  float* sample_lower = FrameScratch::Reserve(2 * max_samples, &scratch->samples);
  float* sample_upper = sample_lower + max_samples;
  int32_t* sample_offset = FrameScratch::Reserve(max_samples, &scratch->offsets);
  int num_samples = 0;
  for (int dy = -radius; dy <= radius; ++dy) {
    const int r = yi + dy;
    if (r < 1 || r >= gradient.rows - 1) continue;
    // The disc's columns on this row: dx^2 + dy^2 <= radius^2.
    const int reach_sq = radius * radius - dy * dy;
    int reach = static_cast<int>(std::sqrt(static_cast<double>(reach_sq)));
    while ((reach + 1) * (reach + 1) <= reach_sq) ++reach;
    while (reach * reach > reach_sq) --reach;
    const int c_begin = std::max(1, xi - reach);
    const int c_end = std::min(gradient.cols - 2, xi + reach);
    const int count = c_end - c_begin + 1;
    if (count <= 0) continue;
    OrientationSamples(count, gradient.Angle(r) + c_begin, gradient.Magnitude(r) + c_begin,
                       weights_x + (c_begin - xi + radius), weights_y[dy + radius],
                       sample_offset + num_samples, sample_lower + num_samples,
                       sample_upper + num_samples);
    num_samples += count;
  }
  constexpr int kCopiesSize = kOrientationCopies * kPaddedOrientationBins;
  std::array<float, kCopiesSize> lower_bins{}, upper_bins{};
  float* upper_above = upper_bins.data() + 1;
  for (int i = 0; i < num_samples; ++i) {
    lower_bins[sample_offset[i]] += sample_lower[i];
    upper_above[sample_offset[i]] += sample_upper[i];
  }
  std::array<float, kPaddedOrientationBins> padded;
  for (int b = 0; b < kPaddedOrientationBins; ++b) {
    float sum = 0;
    for (int c = 0; c < kOrientationCopies; ++c) {
      sum +=
          lower_bins[c * kPaddedOrientationBins + b] + upper_bins[c * kPaddedOrientationBins + b];
    }
    padded[b] = sum;
  }
  std::array<float, kOrientationBins> histogram;
  for (int b = 0; b < kOrientationBins; ++b) histogram[b] = padded[b + 1];
  histogram[kOrientationBins - 1] += padded[0];
  histogram[0] += padded[kPaddedOrientationBins - 1];
  // Each pass from a copy with the ends wrapped, which the compiler vectorises: in place,
  // each bin waited for the one before (and its division).
  std::array<float, kOrientationBins + 2> wrapped;
  for (int pass = 0; pass < kOrientationSmoothing; ++pass) {
    wrapped[0] = histogram[kOrientationBins - 1];
    std::copy(histogram.begin(), histogram.end(), wrapped.begin() + 1);
    wrapped[kOrientationBins + 1] = histogram[0];
    for (int b = 0; b < kOrientationBins; ++b) {
      histogram[b] = (wrapped[b] + wrapped[b + 1] + wrapped[b + 2]) / 3.0f;
    }
  }
  const float highest = *std::max_element(histogram.begin(), histogram.end());
  std::vector<std::pair<float, float>> peaks;  // (height, orientation)
  for (int b = 0; b < kOrientationBins; ++b) {
    const float left = histogram[(b + kOrientationBins - 1) % kOrientationBins];
    const float right = histogram[(b + 1) % kOrientationBins];
    const float h = histogram[b];
    if (h <= left || h <= right || h < kOrientationPeakRatio * highest) continue;
    const float shift = 0.5f * (left - right) / (left - 2.0f * h + right);
    float orientation = kTwoPi * (b + shift + 0.5f) / kOrientationBins;
    if (orientation < 0) orientation += kTwoPi;
    if (orientation >= kTwoPi) orientation -= kTwoPi;
    peaks.emplace_back(h, orientation);
  }
  std::stable_sort(peaks.begin(), peaks.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<float> orientations;
  for (size_t i = 0; i < peaks.size() && static_cast<int>(i) < max_orientations; ++i) {
    orientations.push_back(peaks[i].second);
  }
  return orientations;
}

// Where DescriptorSamples writes each sample's histogram offset, orientation and weights.
struct DescriptorSampleArrays {
  int32_t* offset;
  float *orientation, *w00, *w01, *w10, *w11;
};

// The descriptor bins and weights of a frame's samples, a block of eight at a time: sample i
// of a row is at bin (bin_x + i step_x, bin_y + i step_y), and weighs nothing outside the
// window. For each sample, the offset in the histograms of its lowest (column, row) cell (in
// copy i % kDescriptorCopies), its weight for each of the 2 x 2 cells from there, and its
// orientation in bins, in [0, 8). A row's last block reads and writes up to kSampleLanes - 1
// samples past its end (the rings, the window and `out` are padded for them; what it writes
// there the next row's first block overwrites, or nothing reads). One loop over every block
// of the frame: a loop per row mispredicted its exit each row, and the compiler's
// vectorisation of it ended each row in a scalar tail.
void DescriptorSamples(const DescriptorRow* rows, const DescriptorBlock* blocks, int num_blocks,
                       float step_x, float step_y, float orientation,
                       const DescriptorSampleArrays& out) {
  constexpr float kBinsPerRadian = kDescriptorOrientations / kTwoPi;
  constexpr float kLastOrientationBin = 7.99999952f;  // The float below 8.
  const Float8 zero = {}, lane = {0, 1, 2, 3, 4, 5, 6, 7};
  // Sample i's copy: the same lane by lane, in every block of eight.
  const Int8 copy_offset =
      (Int8{0, 1, 2, 3, 4, 5, 6, 7} & (kDescriptorCopies - 1)) * kDescriptorHistogramSize;
  for (int b = 0; b < num_blocks; ++b) {
    const DescriptorRow& row = rows[blocks[b].row];
    const int i = blocks[b].column;
    const int sample = row.first_sample + i;
    const Float8 steps = lane + static_cast<float>(i);
    const Float8 x = MulAdd8(steps, zero + step_x, zero + row.bin_x);
    const Float8 y = MulAdd8(steps, zero + step_y, zero + row.bin_y);
    const Int8 inside = (x > -1.0f) & (x < kDescriptorGrid) & (y > -1.0f) & (y < kDescriptorGrid);
    // Orientation bins count the gradient's angle from the frame's the other way round
    // (as with y up): Lowe's layout, which OpenCV and COLMAP store, so that descriptors of
    // either SIFT in one database compare bin for bin (VLFeat's count the other way).
    Float8 relative = orientation - Load8(row.angle + i);
    relative += relative < zero ? zero + kTwoPi : zero;
    // Rounding can put an angle just under 2 pi at bin 8.0: held just below it (its weight
    // then goes to bin 7, and the rest, none, to bin 0).
    Store8(out.orientation + sample, Min8(relative * kBinsPerRadian, zero + kLastOrientationBin));
    // floor, not truncation of bin + 1: that sum can round up to the next integer. Outside
    // the window the bins are meaningless (and never used): clamped, so the conversions
    // stay in range.
    const Float8 x0 = Floor8(inside ? x : zero), y0 = Floor8(inside ? y : zero);
    const Float8 fx = x - x0, fy = y - y0;
    const Float8 cell = MulAdd8(y0 + 1.0f, zero + kPaddedGrid, x0 + 1.0f);  // Exact integers.
    const Int8 offset = __builtin_convertvector(cell, Int8) * kDescriptorOrientations + copy_offset;
    std::memcpy(out.offset + sample, &offset, sizeof(offset));
    // The sample's weight split over the 2 x 2 cells around it (bilinearly).
    const Float8 weight = ((inside ? zero + row.window_y : zero) * Load8(row.magnitude + i)) *
                          Load8(row.window_x + i);
    const Float8 w1 = weight * fy, w0 = weight - w1;
    const Float8 w11 = w1 * fx, w01 = w0 * fx;
    Store8(out.w00 + sample, w0 - w01);
    Store8(out.w01 + sample, w01);
    Store8(out.w10 + sample, w1 - w11);
    Store8(out.w11 + sample, w11);
  }
}

// Each sample adds to the 2 x 2 (column, row) cells around it in the padded histograms, to
// each cell's two orientation bins around its own: one vector of eight orientation weights,
// scaled per cell. A loop the compiler cannot vectorise; unrolled, its loop overhead was a
// tenth of its instructions.
void AddDescriptorSamples(const DescriptorSampleArrays& samples, int count, float* histograms) {
  // Local copies: Store8's memcpy might have written over the struct's pointers, as far as
  // the compiler knows, which then reloaded them after every add.
  const int32_t* const offset = samples.offset;
  const float *const orientation = samples.orientation, *const w00 = samples.w00,
                     *const w01 = samples.w01, *const w10 = samples.w10, *const w11 = samples.w11;
  const Float8 bin_index = {0, 1, 2, 3, 4, 5, 6, 7};
  const Float8 zero = {}, one = zero + 1.0f, num_bins = zero + kDescriptorOrientations;
#pragma GCC unroll 4
  for (int i = 0; i < count; ++i) {
    // Bin b takes 1 - (circular distance from the sample's orientation), when positive:
    // 1 - fo for the bin below, fo for the one above (bin 0 above bin 7).
    Float8 distance = Abs8(bin_index - orientation[i]);
    distance = Min8(distance, num_bins - distance);
    const Float8 share = Max8(one - distance, zero);
    float* cell = histograms + offset[i];
    float* below = cell + kPaddedGrid * kDescriptorOrientations;
    Store8(cell, Load8(cell) + w00[i] * share);
    Store8(cell + kDescriptorOrientations, Load8(cell + kDescriptorOrientations) + w01[i] * share);
    Store8(below, Load8(below) + w10[i] * share);
    Store8(below + kDescriptorOrientations,
           Load8(below + kDescriptorOrientations) + w11[i] * share);
  }
}

// Lowe's descriptor: gradients in a square of 4 x 4 bins of side 3 x scale, rotated to the
// frame's orientation, each sample spread over the 2 x 2 x 2 nearest (column, row,
// orientation) bins, under a Gaussian window of two bins' sigma; then unit-L2, clamped at
// 0.2 and renormalised against lighting changes.
void FrameDescriptor(const Gradient& gradient, float x, float y, float octave_scale,
                     float orientation, FrameScratch* scratch, float* descriptor) {
  const float bin_side = kDescriptorMagnification * octave_scale;
  const float half_grid = 0.5f * kDescriptorGrid;
  const int radius = DescriptorRadius(octave_scale, gradient.size());
  const int xi = static_cast<int>(std::lround(x)), yi = static_cast<int>(std::lround(y));
  const float* weights_x =
      GaussianWeights(radius, x - xi, half_grid * bin_side, &scratch->weights_x);
  const float* weights_y =
      GaussianWeights(radius, y - yi, half_grid * bin_side, &scratch->weights_y);

  // The rows first, then the samples of all of them (DescriptorSamples), then their adds
  // (AddDescriptorSamples).
  std::vector<DescriptorRow>& rows = scratch->rows;
  std::vector<DescriptorBlock>& blocks = scratch->blocks;
  rows.clear();
  blocks.clear();
  int num_samples = 0;
  const float cos_t = std::cos(orientation) / bin_side;
  const float sin_t = std::sin(orientation) / bin_side;
  for (int dy = -radius; dy <= radius; ++dy) {
    const int r = yi + dy;
    if (r < 1 || r >= gradient.rows - 1) continue;
    const float oy = static_cast<float>(r) - y;
    // The columns whose samples fall in the rotated window: |u|, |v| < half_grid + 0.5 bins,
    // an interval per row where the two strips cross.
    float ox_low = -radius - 1.0f, ox_high = radius + 1.0f;
    const float half_window = half_grid + 0.5f;
    const auto intersect_strip = [&](float slope, float intercept) {
      // |slope * ox + intercept| < half_window
      if (std::abs(slope) < 1e-6f) {
        if (std::abs(intercept) >= half_window) ox_high = ox_low - 1.0f;
        return;
      }
      float a = (-half_window - intercept) / slope, b = (half_window - intercept) / slope;
      if (a > b) std::swap(a, b);
      ox_low = std::max(ox_low, a);
      ox_high = std::min(ox_high, b);
    };
    intersect_strip(cos_t, sin_t * oy);
    intersect_strip(-sin_t, cos_t * oy);
    if (ox_low > ox_high) continue;
    const int c_begin = std::max({1, xi - radius, static_cast<int>(std::floor(x + ox_low))});
    const int c_end =
        std::min({gradient.cols - 2, xi + radius, static_cast<int>(std::ceil(x + ox_high))});
    const int count = c_end - c_begin + 1;
    if (count <= 0) continue;
    const float bin_x_begin =
        cos_t * (static_cast<float>(c_begin) - x) + sin_t * oy + half_grid - 0.5f;
    const float bin_y_begin =
        -sin_t * (static_cast<float>(c_begin) - x) + cos_t * oy + half_grid - 0.5f;
    const int row = static_cast<int>(rows.size());
    rows.push_back({bin_x_begin, bin_y_begin, gradient.Angle(r) + c_begin,
                    gradient.Magnitude(r) + c_begin, weights_x + (c_begin - xi + radius),
                    weights_y[dy + radius], num_samples});
    for (int i = 0; i < count; i += kSampleLanes) blocks.push_back({row, i});
    num_samples += count;
  }

  const size_t max_samples = static_cast<size_t>(num_samples) + kSampleLanes - 1;
  float* sample_arrays = FrameScratch::Reserve(5 * max_samples, &scratch->samples);
  const DescriptorSampleArrays arrays{FrameScratch::Reserve(max_samples, &scratch->offsets),
                                      sample_arrays,
                                      sample_arrays + max_samples,
                                      sample_arrays + 2 * max_samples,
                                      sample_arrays + 3 * max_samples,
                                      sample_arrays + 4 * max_samples};
  DescriptorSamples(rows.data(), blocks.data(), static_cast<int>(blocks.size()), cos_t, -sin_t,
                    orientation, arrays);
  // kDescriptorCopies copies, taken in turn along a row (see there), summed at the end.
  alignas(32) std::array<float, kDescriptorCopies * kDescriptorHistogramSize> histogram{};
  AddDescriptorSamples(arrays, num_samples, histogram.data());

  for (int by = 0; by < kDescriptorGrid; ++by) {
    for (int bx = 0; bx < kDescriptorGrid; ++bx) {
      const float* cell =
          histogram.data() + ((by + 1) * kPaddedGrid + (bx + 1)) * kDescriptorOrientations;
      float* out = descriptor + (by * kDescriptorGrid + bx) * kDescriptorOrientations;
      static_assert(kDescriptorCopies == 8);
      const auto copy = [cell](int k) { return Load8(cell + k * kDescriptorHistogramSize); };
      Store8(out, ((copy(0) + copy(1)) + (copy(2) + copy(3))) +
                      ((copy(4) + copy(5)) + (copy(6) + copy(7))));
    }
  }

  const auto normalise = [descriptor] {
    float norm_sq = 0;
    for (int k = 0; k < kDescriptorSize; ++k) norm_sq += descriptor[k] * descriptor[k];
    const float inv = norm_sq > 0 ? 1.0f / std::sqrt(norm_sq) : 0.0f;
    for (int k = 0; k < kDescriptorSize; ++k) descriptor[k] *= inv;
  };
  normalise();
  for (int k = 0; k < kDescriptorSize; ++k) {
    descriptor[k] = std::min(descriptor[k], kDescriptorClamp);
  }
  normalise();
}

// A frame with where it was found: octave, Gaussian layer, position and scale in the
// octave's pixels.
struct Detection {
  SiftFrame frame;
  int octave = 0, layer = 0;
  float x = 0, y = 0, octave_scale = 0;
};

bool RanksBefore(const Detection& a, const Detection& b) {
  return FrameRanksBefore(a.frame, b.frame);
}

}  // namespace

bool FrameRanksBefore(const SiftFrame& a, const SiftFrame& b) {
  if (a.response != b.response) return a.response > b.response;
  if (a.y != b.y) return a.y < b.y;
  if (a.x != b.x) return a.x < b.x;
  if (a.scale != b.scale) return a.scale < b.scale;
  return a.orientation < b.orientation;
}

void NativeSiftOptions::Check() const {
  PARALLAX_CHECK_GT(num_octave_layers, 0);
  PARALLAX_CHECK_GT(contrast_threshold, 0.0);
  PARALLAX_CHECK_GT(edge_threshold, 0.0);
  PARALLAX_CHECK_GT(sigma, 0.0);
  PARALLAX_CHECK_GT(max_num_orientations, 0);
  PARALLAX_CHECK_GE(max_num_features, 0);
}

NativeSiftBuffers::NativeSiftBuffers() : space_(std::make_unique<NativeSiftScaleSpace>()) {}

NativeSiftBuffers::~NativeSiftBuffers() = default;

void ComputeNativeSift(const cv::Mat& gray, const NativeSiftOptions& options,
                       std::vector<SiftFrame>* frames, std::vector<float>* descriptors,
                       NativeSiftBuffers* buffers) {
  options.Check();
  PARALLAX_CHECK(frames != nullptr);
  PARALLAX_CHECK(descriptors != nullptr);
  PARALLAX_CHECK_EQ(gray.type(), CV_8UC1);
  frames->clear();
  descriptors->clear();
  if (gray.empty()) return;

  std::optional<NativeSiftBuffers> own_buffers;
  if (buffers == nullptr) buffers = &own_buffers.emplace();
  ScaleSpace& space = buffers->ScaleSpace();
  PrepareScaleSpace(gray, options, &space);
  const int layers = options.num_octave_layers;
  // Half the final threshold screens samples before the 26-neighbour test, as Lowe does.
  const float screen = static_cast<float>(0.5 * options.contrast_threshold / layers);
  // Where the doubled image's pixel 0 lies: centre-aligned upsampling puts doubled pixel X
  // at input coordinate (X + 0.5) / 2, and every later octave samples every other pixel.
  const float origin = options.double_first_octave ? 0.25f : 0.5f;

  // 1. Extrema of the DoG in every octave, refined.
  std::vector<Detection> extrema;
  for (int o = 0; o < static_cast<int>(space.octaves.size()); ++o) {
    const Octave& octave = space.octaves[o];
    DogScreen dog_screen(octave.gaussians, layers, screen, &space);
    BuildOctave(o, &space,
                [&dog_screen](int layer, int row) { dog_screen.LayerRowDone(layer, row); });
    LastLayer last_layer(octave.gaussians, space.increments.back());
    const Differences dogs(octave.gaussians, &last_layer);
    const float pixel_size = std::ldexp(1.0f, octave.index);
    for (const ScreenedSample& sample : dog_screen.samples()) {
      if (!IsExtremumAcrossScales(dogs, sample.layer, sample.row, sample.col, &last_layer)) {
        continue;
      }
      Extremum extremum{sample.layer, sample.row, sample.col};
      if (!RefineExtremum(dogs, options, &last_layer, &extremum)) continue;
      Detection& detection = extrema.emplace_back();
      detection.octave = o;
      detection.x = extremum.col + extremum.offset_col;
      detection.y = extremum.row + extremum.offset_row;
      const float layer_position = extremum.layer + extremum.offset_layer;
      detection.octave_scale =
          static_cast<float>(options.sigma * std::pow(2.0, layer_position / layers));
      // Orientation and descriptor are measured on the Gaussian layer nearest in scale: 0 to
      // S + 1, since RefineExtremum keeps layer_position in [0, S + 1] (layer S + 2 is
      // never stored, see LastLayer).
      detection.layer = std::clamp(static_cast<int>(std::lround(layer_position)), 0, layers + 1);
      detection.frame.x = pixel_size * detection.x + origin;
      detection.frame.y = pixel_size * detection.y + origin;
      detection.frame.scale = pixel_size * detection.octave_scale;
      detection.frame.response = std::abs(extremum.value);
    }
  }

  // 2. The strongest extrema: every frame of an extremum shares its response, so no frame of
  // a weaker one can rank among the strongest max_num_features frames.
  std::sort(extrema.begin(), extrema.end(), RanksBefore);
  if (options.max_num_features > 0 &&
      extrema.size() > static_cast<size_t>(options.max_num_features)) {
    extrema.resize(options.max_num_features);
  }

  // 3. Orientations and descriptors, one Gaussian layer at a time in scan order, so that the
  // gradient's rings hold the rows of one layer's frames at hand, and frames near each other
  // share their cache lines.
  std::stable_sort(extrema.begin(), extrema.end(), [](const Detection& a, const Detection& b) {
    if (a.octave != b.octave) return a.octave < b.octave;
    if (a.layer != b.layer) return a.layer < b.layer;
    return a.y < b.y;
  });
  std::vector<Detection> detections;
  std::vector<float> unranked_descriptors;
  for (size_t begin = 0; begin < extrema.size();) {
    size_t end = begin;
    while (end < extrema.size() && extrema[end].octave == extrema[begin].octave &&
           extrema[end].layer == extrema[begin].layer) {
      ++end;
    }
    const cv::Mat& layer = space.octaves[extrema[begin].octave].gaussians[extrema[begin].layer];
    GradientRegion region(layer.size());
    for (size_t i = begin; i < end; ++i) {
      const Detection& extremum = extrema[i];
      const int radius = GradientRadius(extremum.octave_scale, layer.size());
      region.AddSquare(static_cast<int>(std::lround(extremum.x)),
                       static_cast<int>(std::lround(extremum.y)), radius);
    }
    LayerGradient layer_gradient(layer, region, &space);
    for (size_t i = begin; i < end; ++i) {
      const Detection& extremum = extrema[i];
      const int radius = GradientRadius(extremum.octave_scale, layer.size());
      const int yi = static_cast<int>(std::lround(extremum.y));
      const Gradient& gradient = layer_gradient.Through(yi - radius, yi + radius);
      for (const float orientation :
           FrameOrientations(gradient, extremum.x, extremum.y, extremum.octave_scale,
                             options.max_num_orientations, &space.frame_scratch)) {
        Detection& detection = detections.emplace_back(extremum);
        detection.frame.orientation = orientation;
        unranked_descriptors.resize(unranked_descriptors.size() + kDescriptorSize);
        FrameDescriptor(
            gradient, extremum.x, extremum.y, extremum.octave_scale, orientation,
            &space.frame_scratch,
            unranked_descriptors.data() + unranked_descriptors.size() - kDescriptorSize);
      }
    }
    begin = end;
  }

  // 4. The strongest max_num_features frames, strongest first.
  std::vector<size_t> order(detections.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&detections](size_t a, size_t b) {
    return RanksBefore(detections[a], detections[b]);
  });
  if (options.max_num_features > 0 &&
      order.size() > static_cast<size_t>(options.max_num_features)) {
    order.resize(options.max_num_features);
  }
  frames->reserve(order.size());
  descriptors->resize(order.size() * kDescriptorSize);
  for (size_t i = 0; i < order.size(); ++i) {
    frames->push_back(detections[order[i]].frame);
    std::copy_n(unranked_descriptors.data() + order[i] * kDescriptorSize, kDescriptorSize,
                descriptors->data() + i * kDescriptorSize);
  }
}

}  // namespace parallax
