#include "parallax/feature/native_sift.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "parallax/feature/native_sift_internal.h"
#include "parallax/util/check.h"

namespace parallax {

using native_sift_detail::DetectExtrema;
using native_sift_detail::Detection;
using native_sift_detail::FrameDescriptor;
using native_sift_detail::FrameOrientations;
using native_sift_detail::Gradient;
using native_sift_detail::GradientRadius;
using native_sift_detail::GradientRegion;
using native_sift_detail::kDescriptorSize;
using native_sift_detail::LayerGradient;
using native_sift_detail::PrepareScaleSpace;
using native_sift_detail::RanksBefore;
using native_sift_detail::ScaleSpace;

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
  // 1. Extrema of the DoG in every octave, refined (native_sift_extrema.cc).
  std::vector<Detection> extrema = DetectExtrema(options, &space);

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