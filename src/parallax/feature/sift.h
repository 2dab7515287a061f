#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "parallax/feature/types.h"

namespace parallax {

// Which SIFT computes the features (both store the same frame and descriptor conventions).
enum class SiftImplementation {
  kNative,  // Parallax's own (native_sift.h): float descriptors, exact positions.
  kOpenCv,  // OpenCV's cv::SIFT.
};

// SIFT settings; defaults are the paper's (Lowe 2004 as configured in Zeeshan et al.).
struct SiftExtractionOptions {
  SiftImplementation implementation = SiftImplementation::kNative;
  int max_num_features = 8192;  // Keep the strongest (largest response) keypoints.
  int max_image_size = 3200;    // Downscale larger images (longest side), rescale keypoints.
  // OpenCV's SIFT always doubles the image for its first octave (Lowe's -1 octave). Above this
  // longest side it is given the half-size image instead, so that octave lands at the image's
  // own resolution: the doubled octave is three quarters of the work, and on large images its
  // fine-scale keypoints fall below the max_num_features cut anyway (0: always double).
  int max_upsampled_image_size = 2000;
  int num_octave_layers = 3;         // Layers per octave.
  double contrast_threshold = 0.04;  // OpenCV convention (divided by layers internally).
  double edge_threshold = 10.0;
  double sigma = 1.6;
  bool root_sift = true;  // L1-normalise, square-root (Arandjelovic & Zisserman 2012).
  // Native SIFT: frames per extremum with distinct dominant orientations (COLMAP's 2).
  // OpenCV's makes one per histogram peak within 80 % of the highest, without a cap.
  int max_num_orientations = 2;
  void Check() const;
};

// Extraction behind an interface, so that the native SIFT and OpenCV's are interchangeable.
// Extract may be called from several threads at once; an extractor may keep buffers between
// calls (the native one keeps a scale space per thread at work), so a run uses one for all
// its images.
class FeatureExtractor {
 public:
  virtual ~FeatureExtractor() = default;
  // `gray` is CV_8UC1. Keypoints use COLMAP's convention (pixel centres at +0.5).
  // Descriptors are unit-L2 vectors quantised to uint8 (x 512, clamped), one row each.
  virtual void Extract(const cv::Mat& gray, FeatureKeypoints* keypoints,
                       FeatureDescriptors* descriptors) const = 0;
};

std::unique_ptr<FeatureExtractor> CreateSiftExtractor(const SiftExtractionOptions& options);

// "native" or "opencv", as the command line spells them, and back (nullopt for other names).
const char* SiftImplementationName(SiftImplementation implementation);
std::optional<SiftImplementation> SiftImplementationFromName(const std::string& name);

}  // namespace parallax
