#pragma once

#include "parallax/feature/types.h"

namespace parallax {

struct FeatureMatchingOptions {
  double max_ratio = 0.8;     // Lowe's ratio test on Euclidean distances.
  double max_distance = 0.7;  // Absolute bound on the (unit-vector) Euclidean distance.
  bool cross_check = true;    // Keep only mutual nearest neighbours.
  int num_threads = -1;       // -1: all cores.
  void Check() const;
};

// Descriptors converted once to unit-norm floats, ready for matrix-product matching.
struct MatchableDescriptors {
  Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> values;  // N x 128
};
MatchableDescriptors PrepareDescriptors(const FeatureDescriptors& descriptors);

// Nearest neighbours by ||a - b||^2 = 2 - 2 a.b for unit vectors, computed blockwise as a
// matrix product; ratio test, distance bound and optional cross-check.
FeatureMatches MatchDescriptors(const MatchableDescriptors& descriptors1,
                                const MatchableDescriptors& descriptors2,
                                const FeatureMatchingOptions& options);

}  // namespace parallax
