#include "parallax/sfm/initial_pair.h"

#include <algorithm>
#include <cmath>

#include "parallax/geometry/essential_matrix.h"
#include "parallax/geometry/triangulation.h"

namespace parallax {

std::vector<InitThresholds> InitThresholdSchedule(const IncrementalMapperOptions& options) {
  const int inliers_floor =
      std::min(options.init_min_num_inliers, options.init_min_num_inliers_floor);
  const double angle_floor = std::min(options.init_min_triangulation_angle_deg,
                                      options.init_min_triangulation_angle_floor_deg);
  InitThresholds thresholds{options.init_min_num_inliers, options.init_min_triangulation_angle_deg,
                            0};
  std::vector<InitThresholds> schedule = {thresholds};
  bool halve_angle = true;
  while (thresholds.min_num_inliers > inliers_floor || thresholds.min_angle_deg > angle_floor) {
    // The other one when this one is at its floor.
    if (halve_angle ? thresholds.min_angle_deg <= angle_floor
                    : thresholds.min_num_inliers <= inliers_floor) {
      halve_angle = !halve_angle;
    }
    if (halve_angle) {
      thresholds.min_angle_deg = std::max(angle_floor, 0.5 * thresholds.min_angle_deg);
    } else {
      thresholds.min_num_inliers = std::max(inliers_floor, thresholds.min_num_inliers / 2);
    }
    ++thresholds.step;
    schedule.push_back(thresholds);
    halve_angle = !halve_angle;
  }
  return schedule;
}

InitialPairEvaluation EvaluateInitialPair(const Reconstruction& reconstruction,
                                          image_pair_t pair_id, const TwoViewGeometry& geometry,
                                          double max_error_px) {
  const auto [image_id1, image_id2] = PairIdToImagePair(pair_id);
  const Image& image1 = reconstruction.GetImage(image_id1);
  const Image& image2 = reconstruction.GetImage(image_id2);
  const Camera& camera1 = reconstruction.GetCamera(image1.camera_id);
  const Camera& camera2 = reconstruction.GetCamera(image2.camera_id);

  std::vector<Eigen::Vector2d> points1, points2;
  for (const FeatureMatch& match : geometry.inlier_matches) {
    points1.push_back(camera1.CamFromImg(image1.points2D[match.point2D_idx1].xy));
    points2.push_back(camera2.CamFromImg(image2.points2D[match.point2D_idx2].xy));
  }
  InitialPairEvaluation evaluation;
  // Verification stores every accepted pair's relative pose (from E, F or H, whichever
  // explains the pair); databases without one (COLMAP's before 3.7) get it from E here.
  Rigid3d cam2_from_cam1 = geometry.cam2_from_cam1;
  if (cam2_from_cam1.translation.isZero() || !cam2_from_cam1.translation.allFinite()) {
    Eigen::Matrix3d E = geometry.E;
    if (geometry.config != TwoViewGeometry::kCalibrated || E.isZero()) {
      E = EssentialFromFundamental(geometry.F, camera1.CalibrationMatrix(),
                                   camera2.CalibrationMatrix());
    }
    if (!E.allFinite() || !PoseFromEssentialMatrix(E, points1, points2, &cam2_from_cam1)) {
      return evaluation;
    }
  }
  evaluation.has_pose = true;
  evaluation.cam2_from_cam1 = cam2_from_cam1;

  const Matrix3x4d proj1 = Rigid3d().ToMatrix();
  const Matrix3x4d proj2 = cam2_from_cam1.ToMatrix();
  const Eigen::Vector3d center2 = ProjectionCenter(cam2_from_cam1);
  std::vector<double> angles;
  for (size_t i = 0; i < points1.size(); ++i) {
    const auto xyz = TriangulatePoint(proj1, proj2, points1[i], points2[i]);
    if (!xyz || xyz->z() <= 0 || (cam2_from_cam1 * *xyz).z() <= 0) continue;
    const FeatureMatch& match = geometry.inlier_matches[i];
    const double error1 =
        (camera1.ImgFromCam(*xyz) - image1.points2D[match.point2D_idx1].xy).norm();
    const double error2 =
        (camera2.ImgFromCam(cam2_from_cam1 * *xyz) - image2.points2D[match.point2D_idx2].xy).norm();
    if (error1 > max_error_px || error2 > max_error_px) continue;
    angles.push_back(CalculateTriangulationAngle(Eigen::Vector3d::Zero(), center2, *xyz));
  }
  evaluation.num_triangulated = static_cast<int>(angles.size());
  if (!angles.empty()) {
    std::nth_element(angles.begin(), angles.begin() + angles.size() / 2, angles.end());
    evaluation.median_angle_deg = angles[angles.size() / 2] * 180.0 / M_PI;
  }
  return evaluation;
}

}  // namespace parallax
