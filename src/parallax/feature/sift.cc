#include "parallax/feature/sift.h"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "parallax/feature/native_sift.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

// COLMAP's quantisation: a unit-L2 float descriptor times 512, rounded and clamped to 255
// (SIFT components rarely exceed 0.5 after Lowe's 0.2 clamp and renormalisation). Components
// are never negative, so rounding half away from zero (std::round, a call per component:
// docs/performance.md, "Descriptor quantisation") is the floor plus one where the exact
// remainder reaches one half, which the compiler vectorises.
void QuantiseUnitDescriptor(const float* __restrict unit, uint8_t* __restrict out) {
  for (int k = 0; k < 128; ++k) {
    const float scaled = 512.0f * unit[k];
    const float below = std::floor(scaled);
    const float rounded = scaled - below >= 0.5f ? below + 1.0f : below;
    out[k] = static_cast<uint8_t>(rounded < 255.0f ? rounded : 255.0f);
  }
}

// One descriptor row from OpenCV (non-negative floats, any scale) to the stored uint8 row.
void ConvertDescriptor(const float* raw, bool root_sift, uint8_t* out) {
  float unit[128];
  if (root_sift) {
    // L1-normalise then square-root: the result is unit-L2 since sum(sqrt(v)^2) = |v|_1 = 1.
    float l1 = 0.0f;
    for (int k = 0; k < 128; ++k) l1 += std::abs(raw[k]);
    const float inv_l1 = l1 > 0.0f ? 1.0f / l1 : 0.0f;
    for (int k = 0; k < 128; ++k) unit[k] = std::sqrt(std::abs(raw[k]) * inv_l1);
  } else {
    float l2 = 0.0f;
    for (int k = 0; k < 128; ++k) l2 += raw[k] * raw[k];
    const float inv_l2 = l2 > 0.0f ? 1.0f / std::sqrt(l2) : 0.0f;
    for (int k = 0; k < 128; ++k) unit[k] = std::max(0.0f, raw[k]) * inv_l2;
  }
  QuantiseUnitDescriptor(unit, out);
}

// A frame before ranking, in the coordinates of the image the extractor was given.
struct Candidate {
  SiftFrame frame;
  const float* descriptor;  // 128 raw floats, any positive scale.
};

// The image SIFT runs on: the input downscaled to max_image_size, and the factors that take
// its coordinates back to the input's.
struct SiftInput {
  cv::Mat image;
  double scale_x = 1.0, scale_y = 1.0;
};

SiftInput DownscaleToMaxSize(const cv::Mat& gray, int max_image_size) {
  SiftInput input{gray};
  const int longest = std::max(gray.cols, gray.rows);
  if (longest > max_image_size) {
    const double factor = static_cast<double>(max_image_size) / longest;
    const int width = std::max(1, static_cast<int>(std::lround(gray.cols * factor)));
    const int height = std::max(1, static_cast<int>(std::lround(gray.rows * factor)));
    cv::resize(gray, input.image, cv::Size(width, height), 0, 0, cv::INTER_AREA);
    input.scale_x = static_cast<double>(gray.cols) / width;
    input.scale_y = static_cast<double>(gray.rows) / height;
  }
  return input;
}

// Keeps the strongest max_num_features candidates, strongest first (the native SIFT's
// order; its frames come in it already).
void KeepStrongest(int max_num_features, std::vector<Candidate>* candidates) {
  std::sort(candidates->begin(), candidates->end(), [](const Candidate& a, const Candidate& b) {
    if (FrameRanksBefore(a.frame, b.frame)) return true;
    if (FrameRanksBefore(b.frame, a.frame)) return false;
    return a.descriptor < b.descriptor;
  });
  if (candidates->size() > static_cast<size_t>(max_num_features)) {
    candidates->resize(max_num_features);
  }
}

// Stores the candidates, in their order, in the input image's coordinates.
void StoreCandidates(const std::vector<Candidate>& candidates, bool root_sift, double scale_x,
                     double scale_y, FeatureKeypoints* keypoints, FeatureDescriptors* descriptors) {
  keypoints->reserve(candidates.size());
  descriptors->resize(static_cast<Eigen::Index>(candidates.size()), 128);
  for (size_t i = 0; i < candidates.size(); ++i) {
    const SiftFrame& frame = candidates[i].frame;
    keypoints->emplace_back(
        static_cast<float>(scale_x * frame.x), static_cast<float>(scale_y * frame.y),
        static_cast<float>(0.5 * (scale_x + scale_y) * frame.scale), frame.orientation);
    ConvertDescriptor(candidates[i].descriptor, root_sift,
                      descriptors->row(static_cast<Eigen::Index>(i)).data());
  }
}

// Checks Extract's arguments and empties the outputs; false when the image is empty.
bool StartExtraction(const cv::Mat& gray, FeatureKeypoints* keypoints,
                     FeatureDescriptors* descriptors) {
  PARALLAX_CHECK(keypoints != nullptr);
  PARALLAX_CHECK(descriptors != nullptr);
  PARALLAX_CHECK_EQ(gray.type(), CV_8UC1);
  keypoints->clear();
  descriptors->resize(0, 128);
  return !gray.empty();
}

class OpenCvSiftExtractor : public FeatureExtractor {
 public:
  explicit OpenCvSiftExtractor(const SiftExtractionOptions& options) : options_(options) {
    options_.Check();
  }

  void Extract(const cv::Mat& gray, FeatureKeypoints* keypoints,
               FeatureDescriptors* descriptors) const override {
    if (!StartExtraction(gray, keypoints, descriptors)) return;

    SiftInput input = DownscaleToMaxSize(gray, options_.max_image_size);
    // A half-size image doubled by OpenCV is the original at sigma 1.6: what a Gaussian of
    // that width leaves above the half-size Nyquist frequency is under 5 %.
    if (options_.max_upsampled_image_size > 0 &&
        std::max(input.image.cols, input.image.rows) > options_.max_upsampled_image_size) {
      const int width = std::max(1, input.image.cols / 2);
      const int height = std::max(1, input.image.rows / 2);
      cv::Mat half;
      cv::resize(input.image, half, cv::Size(width, height), 0, 0, cv::INTER_AREA);
      input.scale_x *= static_cast<double>(input.image.cols) / width;
      input.scale_y *= static_cast<double>(input.image.rows) / height;
      input.image = half;
    }

    // OpenCV keeps the strongest `nfeatures` before computing descriptors, plus any ties at
    // the boundary response; those are cut below.
    const cv::Ptr<cv::SIFT> sift =
        cv::SIFT::create(options_.max_num_features, options_.num_octave_layers,
                         options_.contrast_threshold, options_.edge_threshold, options_.sigma);
    std::vector<cv::KeyPoint> cv_keypoints;
    cv::Mat cv_descriptors;
    sift->detectAndCompute(input.image, cv::noArray(), cv_keypoints, cv_descriptors);
    if (cv_keypoints.empty()) return;
    PARALLAX_CHECK_EQ(cv_descriptors.type(), CV_32F);
    PARALLAX_CHECK_EQ(cv_descriptors.cols, 128);
    PARALLAX_CHECK_EQ(static_cast<size_t>(cv_descriptors.rows), cv_keypoints.size());

    constexpr double kDegreesToRadians = 3.14159265358979323846 / 180.0;
    std::vector<Candidate> candidates;
    candidates.reserve(cv_keypoints.size());
    for (size_t i = 0; i < cv_keypoints.size(); ++i) {
      const cv::KeyPoint& keypoint = cv_keypoints[i];
      // OpenCV: pixel centres at integers, size = 2 sigma, angle in degrees measured in image
      // coordinates (y down). COLMAP: pixel centres at +0.5, scale = sigma, radians.
      const double orientation = keypoint.angle < 0 ? 0.0 : keypoint.angle * kDegreesToRadians;
      candidates.push_back({{keypoint.pt.x + 0.5f, keypoint.pt.y + 0.5f, 0.5f * keypoint.size,
                             static_cast<float>(orientation), keypoint.response},
                            cv_descriptors.ptr<float>(static_cast<int>(i))});
    }
    KeepStrongest(options_.max_num_features, &candidates);
    StoreCandidates(candidates, options_.root_sift, input.scale_x, input.scale_y, keypoints,
                    descriptors);
  }

 private:
  SiftExtractionOptions options_;
};

class NativeSiftExtractor : public FeatureExtractor {
 public:
  explicit NativeSiftExtractor(const SiftExtractionOptions& options) : options_(options) {
    options_.Check();
  }

  void Extract(const cv::Mat& gray, FeatureKeypoints* keypoints,
               FeatureDescriptors* descriptors) const override {
    if (!StartExtraction(gray, keypoints, descriptors)) return;

    const SiftInput input = DownscaleToMaxSize(gray, options_.max_image_size);
    NativeSiftOptions sift;
    sift.double_first_octave =
        options_.max_upsampled_image_size == 0 ||
        std::max(input.image.cols, input.image.rows) <= options_.max_upsampled_image_size;
    sift.num_octave_layers = options_.num_octave_layers;
    sift.contrast_threshold = options_.contrast_threshold;
    sift.edge_threshold = options_.edge_threshold;
    sift.sigma = options_.sigma;
    sift.max_num_orientations = options_.max_num_orientations;
    sift.max_num_features = options_.max_num_features;
    std::vector<SiftFrame> frames;
    std::vector<float> raw_descriptors;
    std::unique_ptr<NativeSiftBuffers> buffers = TakeBuffers();
    ComputeNativeSift(input.image, sift, &frames, &raw_descriptors, buffers.get());
    ReturnBuffers(std::move(buffers));

    // Already the strongest max_num_features, strongest first.
    std::vector<Candidate> candidates;
    candidates.reserve(frames.size());
    for (size_t i = 0; i < frames.size(); ++i) {
      candidates.push_back({frames[i], raw_descriptors.data() + 128 * i});
    }
    StoreCandidates(candidates, options_.root_sift, input.scale_x, input.scale_y, keypoints,
                    descriptors);
  }

 private:
  // A set of buffers per call in progress, kept for the next call and freed with the
  // extractor: one extractor for a run's images reuses a scale space per thread.
  std::unique_ptr<NativeSiftBuffers> TakeBuffers() const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (idle_buffers_.empty()) return std::make_unique<NativeSiftBuffers>();
    std::unique_ptr<NativeSiftBuffers> buffers = std::move(idle_buffers_.back());
    idle_buffers_.pop_back();
    return buffers;
  }
  void ReturnBuffers(std::unique_ptr<NativeSiftBuffers> buffers) const {
    std::lock_guard<std::mutex> lock(mutex_);
    idle_buffers_.push_back(std::move(buffers));
  }

  SiftExtractionOptions options_;
  mutable std::mutex mutex_;
  mutable std::vector<std::unique_ptr<NativeSiftBuffers>> idle_buffers_;
};

}  // namespace

void SiftExtractionOptions::Check() const {
  PARALLAX_CHECK_GT(max_num_features, 0);
  PARALLAX_CHECK_GT(max_image_size, 0);
  PARALLAX_CHECK_GE(max_upsampled_image_size, 0);
  PARALLAX_CHECK_GT(num_octave_layers, 0);
  PARALLAX_CHECK_GT(contrast_threshold, 0.0);
  PARALLAX_CHECK_GT(edge_threshold, 0.0);
  PARALLAX_CHECK_GT(sigma, 0.0);
  PARALLAX_CHECK_GT(max_num_orientations, 0);
}

std::unique_ptr<FeatureExtractor> CreateSiftExtractor(const SiftExtractionOptions& options) {
  switch (options.implementation) {
    case SiftImplementation::kNative:
      return std::make_unique<NativeSiftExtractor>(options);
    case SiftImplementation::kOpenCv:
      return std::make_unique<OpenCvSiftExtractor>(options);
  }
  PARALLAX_CHECK_MSG(false, "unknown SIFT implementation");
  return nullptr;
}

const char* SiftImplementationName(SiftImplementation implementation) {
  return implementation == SiftImplementation::kNative ? "native" : "opencv";
}

std::optional<SiftImplementation> SiftImplementationFromName(const std::string& name) {
  for (const SiftImplementation implementation :
       {SiftImplementation::kNative, SiftImplementation::kOpenCv}) {
    if (name == SiftImplementationName(implementation)) return implementation;
  }
  return std::nullopt;
}

}  // namespace parallax
