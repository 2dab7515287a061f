#pragma once

// The parts of the native SIFT (native_sift.h) that its files share: constants, buffers and
// the stages, one file each:
//   native_sift_scale_space.cc  the Gaussian scale space and the layers' gradients
//   native_sift_extrema.cc      extrema of the differences of Gaussians, refined
//   native_sift_orientation.cc  each frame's dominant orientations
//   native_sift_descriptor.cc   each frame's descriptor
//   native_sift.cc              the stages in order (ComputeNativeSift)
// Not an interface: only those files include it.

#include <opencv2/core.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "parallax/feature/native_sift.h"
#include "parallax/util/check.h"
#include "parallax/util/huge_page_buffer.h"

namespace parallax {
namespace native_sift_detail {

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

}  // namespace native_sift_detail

// The Gaussian scale space of one image, and the buffers it is built in (NativeSiftBuffers
// keeps one between images).
struct NativeSiftScaleSpace {
  cv::Mat input, doubled;
  cv::Mat base;  // input or doubled.
  int first_octave = 0;
  std::vector<double> increments;  // Blur from layer k - 1 to layer k.
  double first_blur = 0;           // Blur from the base image to the first layer.
  std::vector<native_sift_detail::Octave> octaves;
  // Three rows of one difference of Gaussians and of their RowExtremes, where the extrema
  // screen reads them.
  std::vector<float> dog_rows;
  // The gradient's rings (Gradient), as wide as the first octave, of a power of two rows
  // (fewer where the first octave has fewer rows).
  cv::Mat magnitude_ring, angle_ring;
  int ring_mask = 0;
  std::vector<float> dx_row, dy_row;               // One row of differences, before PolarRow.
  native_sift_detail::FrameScratch frame_scratch;  // FrameOrientations' and FrameDescriptor's.
  HugePageBuffer memory;                           // Holds every cv::Mat above.
};

namespace native_sift_detail {

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
  // Band b's rows, in the columns of the region (native_sift_scale_space.cc).
  void ComputeBand(int b);

  const cv::Mat& image_;
  const GradientRegion& region_;
  Gradient gradient_;
  ScaleSpace* space_;
  int next_band_ = 0;
};

// Half-sides of the square of gradient samples around (round(x), round(y)) that a frame's
// orientation histogram and its descriptor read.
inline int OrientationRadius(float octave_scale) {
  return std::max(1, static_cast<int>(std::lround(3.0f * kOrientationWindow * octave_scale)));
}

inline int DescriptorRadius(float octave_scale, cv::Size layer_size) {
  const float bin_side = kDescriptorMagnification * octave_scale;
  const int max_radius = static_cast<int>(std::sqrt(static_cast<float>(
      layer_size.height * layer_size.height + layer_size.width * layer_size.width)));
  return std::min(max_radius, static_cast<int>(std::lround(bin_side * std::sqrt(2.0f) *
                                                           (kDescriptorGrid + 1) * 0.5f)));
}

// Half-side of the square of gradient samples a frame reads, for both.
inline int GradientRadius(float octave_scale, cv::Size layer_size) {
  return std::max(OrientationRadius(octave_scale), DescriptorRadius(octave_scale, layer_size));
}

// A frame with where it was found: octave, Gaussian layer, position and scale in the
// octave's pixels.
struct Detection {
  SiftFrame frame;
  int octave = 0, layer = 0;
  float x = 0, y = 0, octave_scale = 0;
};

inline bool RanksBefore(const Detection& a, const Detection& b) {
  return FrameRanksBefore(a.frame, b.frame);
}

// The stages, in the order ComputeNativeSift runs them.

// The base image of the scale space and the octaves' layout (native_sift_scale_space.cc).
void PrepareScaleSpace(const cv::Mat& gray, const NativeSiftOptions& options, ScaleSpace* space);

// Builds octave o; see native_sift_scale_space.cc.
void BuildOctave(int o, ScaleSpace* space,
                 const std::function<void(int layer, int row)>& layer_row_done);

// Every octave built (BuildOctave) and its extrema of the differences of Gaussians found and
// refined: a Detection each, its frame without orientation (native_sift_extrema.cc).
std::vector<Detection> DetectExtrema(const NativeSiftOptions& options, ScaleSpace* space);

// Gaussian window weights for d = i - fraction, i = -radius..radius, followed by zeros for a
// block of samples (native_sift_orientation.cc).
const float* GaussianWeights(int radius, float fraction, float sigma, std::vector<float>* weights);

// A frame's dominant orientations, strongest first (native_sift_orientation.cc).
std::vector<float> FrameOrientations(const Gradient& gradient, float x, float y, float octave_scale,
                                     int max_orientations, FrameScratch* scratch);

// A frame's 128 descriptor values at `orientation` (native_sift_descriptor.cc).
void FrameDescriptor(const Gradient& gradient, float x, float y, float octave_scale,
                     float orientation, FrameScratch* scratch, float* descriptor);

}  // namespace native_sift_detail
}  // namespace parallax
