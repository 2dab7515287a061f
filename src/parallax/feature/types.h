#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "parallax/util/types.h"

namespace parallax {

// A keypoint with its affine shape, stored as COLMAP stores it (6 floats: x, y, a11, a12,
// a21, a22) so keypoint blobs are interchangeable. Pixel centre convention: COLMAP's, the
// top-left pixel's centre is (0.5, 0.5).
struct FeatureKeypoint {
  float x = 0, y = 0;
  float a11 = 1, a12 = 0, a21 = 0, a22 = 1;

  FeatureKeypoint() = default;
  FeatureKeypoint(float x, float y) : x(x), y(y) {}
  // From a SIFT frame: scale (sigma in pixels) and orientation (radians).
  FeatureKeypoint(float x, float y, float scale, float orientation);
  float ComputeScale() const;
  float ComputeOrientation() const;
};
using FeatureKeypoints = std::vector<FeatureKeypoint>;

// The colour of the image under each keypoint, as red, green, blue bytes in keypoint order
// (3 per keypoint): stored at extraction, so that colouring a model needs no image decoded.
using KeypointColors = std::vector<uint8_t>;

// One descriptor per row, 128 bytes for SIFT.
using FeatureDescriptors = Eigen::Matrix<uint8_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Rows `rows` of `from`, in that order, into `to` (resized, its memory reused). Row by row
// with memcpy: Eigen's row assignment copies a byte at a time.
void GatherDescriptorRows(const FeatureDescriptors& from, const std::vector<int>& rows,
                          FeatureDescriptors* to);

struct FeatureMatch {
  point2D_t point2D_idx1 = kInvalidPoint2DIdx;
  point2D_t point2D_idx2 = kInvalidPoint2DIdx;
  bool operator==(const FeatureMatch& other) const = default;
};
using FeatureMatches = std::vector<FeatureMatch>;

}  // namespace parallax
