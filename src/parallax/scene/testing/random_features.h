#pragma once

// Test helpers shared by the scene tests: random keypoints, descriptors and matches drawn from
// the tests' seeded generator (math/random.h), for round trips through the database.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>

#include "parallax/feature/types.h"
#include "parallax/math/random.h"

namespace parallax {
namespace test {

inline FeatureKeypoints RandomKeypoints(size_t count) {
  FeatureKeypoints keypoints(count);
  for (FeatureKeypoint& keypoint : keypoints) {
    keypoint = FeatureKeypoint(RandomUniformReal(0.0f, 640.0f), RandomUniformReal(0.0f, 480.0f),
                               RandomUniformReal(1.0f, 8.0f), RandomUniformReal(-3.0f, 3.0f));
  }
  return keypoints;
}

inline FeatureDescriptors RandomDescriptors(size_t count) {
  FeatureDescriptors descriptors(count, 128);
  for (Eigen::Index i = 0; i < descriptors.size(); ++i) {
    descriptors.data()[i] = static_cast<uint8_t>(RandomUniformReal(0.0, 255.99));
  }
  return descriptors;
}

inline FeatureMatches RandomMatches(size_t count) {
  FeatureMatches matches(count);
  for (size_t i = 0; i < count; ++i) {
    matches[i].point2D_idx1 = static_cast<point2D_t>(i);
    matches[i].point2D_idx2 = static_cast<point2D_t>(RandomUniformReal(0.0, 1000.0));
  }
  return matches;
}

}  // namespace test
}  // namespace parallax
