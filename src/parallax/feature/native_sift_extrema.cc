// The native SIFT's extrema: samples of the differences of Gaussians screened as each octave
// is built, tested across scales and refined to sub-sample precision.

#include <bit>

#include "parallax/feature/float8.h"
#include "parallax/feature/gaussian_blur.h"
#include "parallax/feature/native_sift_internal.h"

namespace parallax {
namespace native_sift_detail {
namespace {

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

}  // namespace

std::vector<Detection> DetectExtrema(const NativeSiftOptions& options, ScaleSpace* space) {
  const int layers = options.num_octave_layers;
  // Half the final threshold screens samples before the 26-neighbour test, as Lowe does.
  const float screen = static_cast<float>(0.5 * options.contrast_threshold / layers);
  // Where the doubled image's pixel 0 lies: centre-aligned upsampling puts doubled pixel X
  // at input coordinate (X + 0.5) / 2, and every later octave samples every other pixel.
  const float origin = options.double_first_octave ? 0.25f : 0.5f;

  // 1. Extrema of the DoG in every octave, refined.
  std::vector<Detection> extrema;
  for (int o = 0; o < static_cast<int>(space->octaves.size()); ++o) {
    const Octave& octave = space->octaves[o];
    DogScreen dog_screen(octave.gaussians, layers, screen, space);
    BuildOctave(o, space,
                [&dog_screen](int layer, int row) { dog_screen.LayerRowDone(layer, row); });
    LastLayer last_layer(octave.gaussians, space->increments.back());
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
  return extrema;
}

}  // namespace native_sift_detail
}  // namespace parallax
