#pragma once

// Test helpers shared by the two-view geometry tests: two cameras, every keypoint of both
// images and their putative matches, with noise, outliers and the ground truth.

#include <Eigen/Geometry>
#include <algorithm>
#include <numeric>
#include <vector>

#include "parallax/estimators/testing/two_view_scene.h"
#include "parallax/feature/types.h"
#include "parallax/geometry/essential_matrix.h"
#include "parallax/geometry/testing/random_geometry.h"
#include "parallax/geometry/triangulation.h"
#include "parallax/math/random.h"
#include "parallax/scene/camera.h"

namespace parallax {
namespace test {

constexpr size_t kImageWidthPx = 1024, kImageHeightPx = 768;  // kImageWidth, kImageHeight.

// Where the scene's points lie.
enum class PairStructure { kGeneral, kPlane, kLine };

// Two cameras, keypoints of both images and their matches. Image 2's keypoints are stored in
// shuffled order with unmatched extras, so match indices are not the identity.
struct MatchedPair {
  Camera camera1 =
      Camera::Create(1, CameraModelId::kSimplePinhole, 1000, kImageWidth, kImageHeight);
  Camera camera2 = Camera::Create(2, CameraModelId::kPinhole, 1100, kImageWidth, kImageHeight);
  Rigid3d cam2_from_cam1;
  std::vector<Eigen::Vector3d> points3D;  // Per match, in cam1.
  std::vector<Eigen::Vector2d> points1, points2;
  FeatureMatches matches;
  std::vector<char> is_inlier;  // Per match.
  // PairStructure::kPlane: normal . X = distance for the points X (cam1); distance 0 otherwise.
  Eigen::Vector3d plane_normal = Eigen::Vector3d::Zero();
  double plane_distance = 0;

  Eigen::Matrix3d TrueE() const { return EssentialFromPose(cam2_from_cam1); }
  Eigen::Matrix3d TrueF() const {
    return FundamentalFromEssential(TrueE(), camera1.CalibrationMatrix(),
                                    camera2.CalibrationMatrix());
  }
  // H = K2 (R + t n^T / d) K1^-1 of a planar pair.
  Eigen::Matrix3d TrueH() const {
    return camera2.CalibrationMatrix() *
           (cam2_from_cam1.rotation.toRotationMatrix() +
            cam2_from_cam1.translation * plane_normal.transpose() / plane_distance) *
           camera1.CalibrationMatrix().inverse();
  }

  // The true median triangulation angle of the inlier matches.
  double TrueTriAngle() const {
    std::vector<double> angles;
    for (size_t i = 0; i < points3D.size(); ++i) {
      if (is_inlier[i]) {
        angles.push_back(CalculateTriangulationAngle(
            Eigen::Vector3d::Zero(), ProjectionCenter(cam2_from_cam1), points3D[i]));
      }
    }
    std::nth_element(angles.begin(), angles.begin() + angles.size() / 2, angles.end());
    return angles[angles.size() / 2];
  }
};

// `num_matches` matches of points seen by both cameras (depths 4 to 10, or on a plane about
// 6 away, or on a line through (0, 0, 6)), the keypoints with Gaussian noise of `noise_px`;
// each match an outlier (image 2's keypoint anywhere) with probability `outlier_ratio`.
// A rotation of 0.05 to 0.3 rad and the baseline `translation` (zero: a pure rotation).
inline MatchedPair RandomMatchedPair(int num_matches, double noise_px, double outlier_ratio,
                                     PairStructure structure,
                                     Eigen::Vector3d translation = RandomUnitVector()) {
  MatchedPair pair;
  pair.cam2_from_cam1 = Rigid3d(
      Eigen::Quaterniond(Eigen::AngleAxisd(RandomUniformReal(0.05, 0.3), RandomUnitVector())),
      translation);
  const Eigen::Vector3d normal = (Eigen::Vector3d(0, 0, 1) + 0.3 * RandomUnitVector()).normalized();
  const Eigen::Vector3d line_direction = RandomUnitVector();
  if (structure == PairStructure::kPlane) {
    pair.plane_normal = normal;
    pair.plane_distance = 6.0;
  }
  std::vector<Eigen::Vector2d> matched2;
  while (static_cast<int>(pair.points3D.size()) < num_matches) {
    const Eigen::Vector3d ray =
        pair.camera1.CalibrationMatrix().inverse() * RandomImagePoint().homogeneous();
    Eigen::Vector3d point = RandomUniformReal(4, 10) * ray;
    if (structure == PairStructure::kPlane) point = ray * 6.0 / normal.dot(ray);
    if (structure == PairStructure::kLine) {
      point = Eigen::Vector3d(0, 0, 6) + RandomUniformReal(-2, 2) * line_direction;
    }
    const Eigen::Vector3d in_cam2 = pair.cam2_from_cam1 * point;
    if (point.z() < 0.5 || in_cam2.z() < 0.5) continue;
    const Eigen::Vector2d pixel1 = pair.camera1.ImgFromCam(point);
    const Eigen::Vector2d pixel2 = pair.camera2.ImgFromCam(in_cam2);
    if (pixel1.x() < 0 || pixel1.x() > kImageWidth || pixel1.y() < 0 || pixel1.y() > kImageHeight ||
        pixel2.x() < 0 || pixel2.x() > kImageWidth || pixel2.y() < 0 || pixel2.y() > kImageHeight) {
      continue;
    }
    const bool inlier = RandomUniformReal(0, 1) >= outlier_ratio;
    pair.points3D.push_back(point);
    pair.is_inlier.push_back(inlier);
    pair.points1.push_back(
        pixel1 + Eigen::Vector2d(RandomGaussian(0, noise_px), RandomGaussian(0, noise_px)));
    matched2.push_back(inlier
                           ? Eigen::Vector2d(pixel2 + Eigen::Vector2d(RandomGaussian(0, noise_px),
                                                                      RandomGaussian(0, noise_px)))
                           : RandomImagePoint());
  }
  // Shuffle image 2's keypoints and add unmatched ones.
  std::vector<size_t> order(matched2.size() + 20);
  std::iota(order.begin(), order.end(), 0);
  Shuffle(order.size(), &order);
  pair.points2.resize(order.size());
  pair.matches.resize(matched2.size());
  for (size_t slot = 0; slot < order.size(); ++slot) {
    pair.points2[slot] = order[slot] < matched2.size() ? matched2[order[slot]] : RandomImagePoint();
    if (order[slot] < matched2.size()) {
      pair.matches[order[slot]] = {static_cast<point2D_t>(order[slot]),
                                   static_cast<point2D_t>(slot)};
    }
  }
  return pair;
}

// As RandomMatchedPair, with both cameras' focal lengths known (prior focal lengths).
inline MatchedPair RandomCalibratedPair(int num_matches, double noise_px, double outlier_ratio,
                                        PairStructure structure = PairStructure::kGeneral) {
  MatchedPair pair = RandomMatchedPair(num_matches, noise_px, outlier_ratio, structure);
  pair.camera1.has_prior_focal_length = true;
  pair.camera2.has_prior_focal_length = true;
  return pair;
}

}  // namespace test
}  // namespace parallax
