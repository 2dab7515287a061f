#include "parallax/feature/sift.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "parallax/util/check.h"

namespace parallax {
namespace {

// COLMAP's quantisation: a unit-L2 float descriptor times 512, rounded and clamped to 255
// (SIFT components rarely exceed 0.5 after Lowe's 0.2 clamp and renormalisation).
void QuantiseUnitDescriptor(const float* unit, uint8_t* out) {
  for (int k = 0; k < 128; ++k) {
    out[k] = static_cast<uint8_t>(std::min(255.0f, std::round(512.0f * unit[k])));
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

class OpenCvSiftExtractor : public FeatureExtractor {
 public:
  explicit OpenCvSiftExtractor(const SiftExtractionOptions& options) : options_(options) {
    options_.Check();
  }

  void Extract(const cv::Mat& gray, FeatureKeypoints* keypoints,
               FeatureDescriptors* descriptors) const override {
    PARALLAX_CHECK(keypoints != nullptr);
    PARALLAX_CHECK(descriptors != nullptr);
    PARALLAX_CHECK_EQ(gray.type(), CV_8UC1);
    keypoints->clear();
    descriptors->resize(0, 128);
    if (gray.empty()) return;

    // Downscale so the longest side is at most max_image_size; keypoints are mapped back.
    cv::Mat image = gray;
    double scale_x = 1.0, scale_y = 1.0;
    const int longest = std::max(gray.cols, gray.rows);
    if (longest > options_.max_image_size) {
      const double factor = static_cast<double>(options_.max_image_size) / longest;
      const int width = std::max(1, static_cast<int>(std::lround(gray.cols * factor)));
      const int height = std::max(1, static_cast<int>(std::lround(gray.rows * factor)));
      cv::resize(gray, image, cv::Size(width, height), 0, 0, cv::INTER_AREA);
      scale_x = static_cast<double>(gray.cols) / width;
      scale_y = static_cast<double>(gray.rows) / height;
    }
    // A half-size image doubled by OpenCV is the original at sigma 1.6: what a Gaussian of
    // that width leaves above the half-size Nyquist frequency is under 5 %.
    if (options_.max_upsampled_image_size > 0 &&
        std::max(image.cols, image.rows) > options_.max_upsampled_image_size) {
      const int width = std::max(1, image.cols / 2);
      const int height = std::max(1, image.rows / 2);
      cv::Mat half;
      cv::resize(image, half, cv::Size(width, height), 0, 0, cv::INTER_AREA);
      scale_x *= static_cast<double>(image.cols) / width;
      scale_y *= static_cast<double>(image.rows) / height;
      image = half;
    }

    // OpenCV keeps the strongest `nfeatures` before computing descriptors, plus any ties at
    // the boundary response; those are cut below.
    const cv::Ptr<cv::SIFT> sift =
        cv::SIFT::create(options_.max_num_features, options_.num_octave_layers,
                         options_.contrast_threshold, options_.edge_threshold, options_.sigma);
    std::vector<cv::KeyPoint> cv_keypoints;
    cv::Mat cv_descriptors;
    sift->detectAndCompute(image, cv::noArray(), cv_keypoints, cv_descriptors);
    if (cv_keypoints.empty()) return;
    PARALLAX_CHECK_EQ(cv_descriptors.type(), CV_32F);
    PARALLAX_CHECK_EQ(cv_descriptors.cols, 128);
    PARALLAX_CHECK_EQ(static_cast<size_t>(cv_descriptors.rows), cv_keypoints.size());

    // Strongest first, with a total order so the output never depends on the input order.
    std::vector<int> order(cv_keypoints.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int a, int b) {
      const cv::KeyPoint& ka = cv_keypoints[a];
      const cv::KeyPoint& kb = cv_keypoints[b];
      if (ka.response != kb.response) return ka.response > kb.response;
      if (ka.pt.y != kb.pt.y) return ka.pt.y < kb.pt.y;
      if (ka.pt.x != kb.pt.x) return ka.pt.x < kb.pt.x;
      if (ka.size != kb.size) return ka.size < kb.size;
      if (ka.angle != kb.angle) return ka.angle < kb.angle;
      return a < b;
    });
    if (order.size() > static_cast<size_t>(options_.max_num_features)) {
      order.resize(options_.max_num_features);
    }

    constexpr double kDegreesToRadians = 3.14159265358979323846 / 180.0;
    keypoints->reserve(order.size());
    descriptors->resize(static_cast<Eigen::Index>(order.size()), 128);
    for (size_t i = 0; i < order.size(); ++i) {
      const cv::KeyPoint& keypoint = cv_keypoints[order[i]];
      // OpenCV: pixel centres at integers, size = 2 sigma, angle in degrees measured in image
      // coordinates (y down). COLMAP: pixel centres at +0.5, scale = sigma, radians.
      const double x = scale_x * (keypoint.pt.x + 0.5);
      const double y = scale_y * (keypoint.pt.y + 0.5);
      const double scale = 0.5 * (scale_x + scale_y) * 0.5 * keypoint.size;
      const double orientation = keypoint.angle < 0 ? 0.0 : keypoint.angle * kDegreesToRadians;
      keypoints->emplace_back(static_cast<float>(x), static_cast<float>(y),
                              static_cast<float>(scale), static_cast<float>(orientation));
      ConvertDescriptor(cv_descriptors.ptr<float>(order[i]), options_.root_sift,
                        descriptors->row(static_cast<Eigen::Index>(i)).data());
    }
  }

 private:
  SiftExtractionOptions options_;
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
}

std::unique_ptr<FeatureExtractor> CreateSiftExtractor(const SiftExtractionOptions& options) {
  return std::make_unique<OpenCvSiftExtractor>(options);
}

}  // namespace parallax
