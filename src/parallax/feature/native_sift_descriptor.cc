// The native SIFT's descriptors: Lowe's 4 x 4 x 8 histograms of gradients around each frame.

#include <cstring>

#include "parallax/feature/float8.h"
#include "parallax/feature/native_sift_internal.h"

namespace parallax {
namespace native_sift_detail {
namespace {

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

}  // namespace

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

}  // namespace native_sift_detail
}  // namespace parallax
