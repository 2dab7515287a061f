// The native SIFT's orientations: the peaks of each frame's histogram of gradient directions.

#include <cstring>
#include <utility>

#include "parallax/feature/float8.h"
#include "parallax/feature/native_sift_internal.h"

namespace parallax {
namespace native_sift_detail {
namespace {

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

}  // namespace

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

}  // namespace native_sift_detail
}  // namespace parallax
