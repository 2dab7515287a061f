#include "parallax/estimators/two_view_geometry.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "parallax/estimators/solvers/essential_matrix.h"
#include "parallax/estimators/solvers/fundamental_matrix.h"
#include "parallax/estimators/solvers/homography_matrix.h"
#include "parallax/estimators/two_view_significance.h"
#include "parallax/geometry/epipolar.h"
#include "parallax/geometry/essential_matrix.h"
#include "parallax/geometry/triangulation.h"
#include "parallax/math/random.h"
#include "parallax/util/check.h"
#include "parallax/util/logging.h"

namespace parallax {
namespace {

// Watermarks sit in this fraction of the image width/height along each border (COLMAP's
// watermark_border_size default).
constexpr double kWatermarkBorderSize = 0.1;
// A planar pair whose baseline is below this fraction of the plane's distance is a pure
// rotation for reconstruction purposes (rays from both centres meet at < ~0.3 degrees).
constexpr double kMaxPanoramicBaselineRatio = 0.005;

// A pure 2D translation x2 = x1 + t: the model of a watermark or time stamp that sits at the
// same place in both images.
struct TranslationEstimator {
  using X_t = Eigen::Vector2d;
  using Y_t = Eigen::Vector2d;
  using M_t = Eigen::Vector2d;
  static constexpr int kMinNumSamples = 1;

  void Estimate(const std::vector<X_t>& points1, const std::vector<Y_t>& points2,
                std::vector<M_t>* models) const {
    models->clear();
    if (points1.empty()) return;
    Eigen::Vector2d translation = Eigen::Vector2d::Zero();
    for (size_t i = 0; i < points1.size(); ++i) translation += points2[i] - points1[i];
    translation /= static_cast<double>(points1.size());
    if (translation.allFinite()) models->push_back(translation);
  }
  void Residuals(const std::vector<X_t>& points1, const std::vector<Y_t>& points2,
                 const M_t& translation, std::vector<double>* squared_residuals) const {
    squared_residuals->resize(points1.size());
    for (size_t i = 0; i < points1.size(); ++i) {
      (*squared_residuals)[i] = (points2[i] - points1[i] - translation).squaredNorm();
    }
  }
};

// The RANSAC streams of one pair: each estimation draws from its own seed.
enum RansacStream : uint64_t {
  kEssentialStream = 1,
  kFundamentalStream,
  kHomographyStream,
  kWatermarkStream
};

// The pair's RANSAC options for one estimation: `max_error` in that model's unit.
RansacOptions StreamRansacOptions(const TwoViewGeometryOptions& options, double max_error,
                                  RansacStream stream) {
  RansacOptions ransac_options = options.ransac;
  ransac_options.max_error = max_error;
  ransac_options.random_seed = DeriveSeed(options.ransac.random_seed, stream);
  return ransac_options;
}

// COLMAP's watermark test: most inliers lie in the border strips of both images and move by
// one common 2D translation.
bool DetectWatermark(const Camera& camera1, const std::vector<Eigen::Vector2d>& points1,
                     const Camera& camera2, const std::vector<Eigen::Vector2d>& points2,
                     const std::vector<char>& inlier_mask, size_t num_inliers,
                     const TwoViewGeometryOptions& options) {
  if (camera1.width == 0 || camera1.height == 0 || camera2.width == 0 || camera2.height == 0) {
    return false;
  }
  const auto in_border = [](const Camera& camera, const Eigen::Vector2d& point) {
    const double border_x = kWatermarkBorderSize * static_cast<double>(camera.width);
    const double border_y = kWatermarkBorderSize * static_cast<double>(camera.height);
    return point.x() < border_x || point.x() > static_cast<double>(camera.width) - border_x ||
           point.y() < border_y || point.y() > static_cast<double>(camera.height) - border_y;
  };
  std::vector<Eigen::Vector2d> border_points1, border_points2;
  for (size_t i = 0; i < points1.size(); ++i) {
    if (inlier_mask[i] && in_border(camera1, points1[i]) && in_border(camera2, points2[i])) {
      border_points1.push_back(points1[i]);
      border_points2.push_back(points2[i]);
    }
  }
  const double min_num_watermark_inliers = options.watermark_min_inlier_ratio * num_inliers;
  if (border_points1.empty() || border_points1.size() < min_num_watermark_inliers) return false;
  const LoRansac<TranslationEstimator> ransac(
      StreamRansacOptions(options, options.ransac.max_error, kWatermarkStream));
  const auto report = ransac.Estimate(border_points1, border_points2);
  return report.success && report.num_inliers >= min_num_watermark_inliers;
}

// The candidate poses of a calibrated homography H = R + T N^T (T = translation / plane
// distance, N the plane's unit normal in cam1), by the SVD method of Ma, Soatto, Kosecka &
// Sastry, "An Invitation to 3-D Vision", sec. 5.3.3. `H` must be scaled so that its middle
// singular value is 1 and (H x1)_z > 0 on the points. Returns the 2 solutions (R, T), each
// standing for the candidates (R, T) and (R, -T) with the normal negated, or 1 with T = 0 when
// H is a rotation (all singular values 1).
struct HomographyCandidate {
  Eigen::Matrix3d rotation;
  Eigen::Vector3d translation_over_distance;
};

int DecomposeCalibratedHomography(const Eigen::Matrix3d& H,
                                  std::array<HomographyCandidate, 2>* candidates) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d singular_values = svd.singularValues();
  const double s1_squared = singular_values(0) * singular_values(0);
  const double s3_squared = singular_values(2) * singular_values(2);
  if (s1_squared - s3_squared < 1e-12) {
    Eigen::Matrix3d U = svd.matrixU();
    Eigen::Matrix3d V = svd.matrixV();
    Eigen::Matrix3d rotation = U * V.transpose();
    if (rotation.determinant() < 0) rotation = -rotation;
    (*candidates)[0] = {rotation, Eigen::Vector3d::Zero()};
    return 1;
  }
  const Eigen::Matrix3d V = svd.matrixV();
  const Eigen::Vector3d v1 = V.col(0), v2 = V.col(1), v3 = V.col(2);
  const double scale = 1.0 / std::sqrt(s1_squared - s3_squared);
  const double a = std::sqrt(std::max(0.0, 1.0 - s3_squared));
  const double b = std::sqrt(std::max(0.0, s1_squared - 1.0));
  const std::array<Eigen::Vector3d, 2> us = {scale * (a * v1 + b * v3), scale * (a * v1 - b * v3)};
  int num_candidates = 0;
  for (const Eigen::Vector3d& u : us) {
    Eigen::Matrix3d U, W;
    U << v2, u, v2.cross(u);
    const Eigen::Vector3d H_v2 = H * v2;
    const Eigen::Vector3d H_u = H * u;
    W << H_v2, H_u, H_v2.cross(H_u);
    const Eigen::Matrix3d rotation = W * U.transpose();
    const Eigen::Vector3d normal = v2.cross(u);
    const Eigen::Vector3d translation = (H - rotation) * normal;
    (*candidates)[num_candidates++] = {rotation, translation};
  }
  return num_candidates;
}

// Relative pose from a calibrated homography: the candidate that puts the most triangulated
// points in front of both cameras. `panoramic` is set when the baseline is negligible.
bool PoseFromCalibratedHomography(const Eigen::Matrix3d& H_calibrated,
                                  const std::vector<Eigen::Vector2d>& points1,
                                  const std::vector<Eigen::Vector2d>& points2,
                                  Rigid3d* cam2_from_cam1, std::vector<Eigen::Vector3d>* points3D,
                                  bool* panoramic) {
  points3D->clear();
  if (!H_calibrated.allFinite() || points1.empty()) return false;
  const Eigen::Vector3d singular_values =
      Eigen::JacobiSVD<Eigen::Matrix3d>(H_calibrated).singularValues();
  if (!(singular_values(1) > 0.0)) return false;
  Eigen::Matrix3d H = H_calibrated / singular_values(1);
  size_t num_positive = 0;
  for (const Eigen::Vector2d& point1 : points1) {
    num_positive += H.row(2).dot(point1.homogeneous()) > 0;
  }
  if (2 * num_positive < points1.size()) H = -H;

  std::array<HomographyCandidate, 2> candidates;
  const int num_candidates = DecomposeCalibratedHomography(H, &candidates);
  if (num_candidates == 1) {
    *panoramic = true;
    *cam2_from_cam1 =
        Rigid3d(Eigen::Quaterniond(candidates[0].rotation).normalized(), Eigen::Vector3d::Zero());
    return cam2_from_cam1->rotation.coeffs().allFinite();
  }

  // Unit translations: depths are then in baselines, as the cheirality vote expects; a
  // candidate with no baseline gets no votes.
  std::vector<Eigen::Matrix3d> rotations;
  std::vector<Eigen::Vector3d> unit_translations;
  for (int candidate = 0; candidate < num_candidates; ++candidate) {
    const Eigen::Vector3d& translation = candidates[candidate].translation_over_distance;
    const double baseline = translation.norm();
    rotations.push_back(candidates[candidate].rotation);
    unit_translations.push_back(
        baseline > 0.0 ? Eigen::Vector3d(translation / baseline)
                       : Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
  }
  const int best_candidate =
      std::max(0, ChoosePoseByCheirality(rotations, unit_translations, points1, points2, points3D));

  // Too little baseline for any point to triangulate in front is a rotation as well.
  const Eigen::Matrix3d& rotation = candidates[best_candidate / 2].rotation;
  const Eigen::Vector3d translation = (best_candidate % 2 == 0 ? 1.0 : -1.0) *
                                      candidates[best_candidate / 2].translation_over_distance;
  *panoramic = points3D->empty() || translation.norm() < kMaxPanoramicBaselineRatio;
  if (*panoramic) {
    points3D->clear();
    *cam2_from_cam1 = Rigid3d(Eigen::Quaterniond(rotation).normalized(), Eigen::Vector3d::Zero());
  } else {
    *cam2_from_cam1 = Rigid3d(Eigen::Quaterniond(rotation).normalized(), translation.normalized());
  }
  return cam2_from_cam1->rotation.coeffs().allFinite() && cam2_from_cam1->translation.allFinite();
}

}  // namespace

void TwoViewGeometryOptions::Check() const {
  PARALLAX_CHECK_GE(min_num_inliers, 0);
  ransac.Check();
  PARALLAX_CHECK(min_E_F_inlier_ratio >= 0.0 && min_E_F_inlier_ratio <= 1.0);
  PARALLAX_CHECK(max_H_inlier_ratio >= 0.0 && max_H_inlier_ratio <= 1.0);
  PARALLAX_CHECK(watermark_min_inlier_ratio >= 0.0 && watermark_min_inlier_ratio <= 1.0);
  PARALLAX_CHECK_GT(max_num_false_alarms, 0.0);
}

TwoViewGeometry EstimateTwoViewGeometry(const Camera& camera1,
                                        const std::vector<Eigen::Vector2d>& points1,
                                        const Camera& camera2,
                                        const std::vector<Eigen::Vector2d>& points2,
                                        const FeatureMatches& matches,
                                        const TwoViewGeometryOptions& options) {
  options.Check();
  TwoViewGeometry geometry;
  geometry.config = TwoViewGeometry::kDegenerate;

  // Matches with non-finite keypoints cannot be explained by any model: leave them out.
  FeatureMatches valid_matches;
  std::vector<Eigen::Vector2d> matched1, matched2;
  valid_matches.reserve(matches.size());
  matched1.reserve(matches.size());
  matched2.reserve(matches.size());
  for (const FeatureMatch& match : matches) {
    PARALLAX_CHECK_LT(match.point2D_idx1, points1.size());
    PARALLAX_CHECK_LT(match.point2D_idx2, points2.size());
    const Eigen::Vector2d& point1 = points1[match.point2D_idx1];
    const Eigen::Vector2d& point2 = points2[match.point2D_idx2];
    if (!point1.allFinite() || !point2.allFinite()) continue;
    valid_matches.push_back(match);
    matched1.push_back(point1);
    matched2.push_back(point2);
  }
  const size_t min_num_inliers = std::max<size_t>(static_cast<size_t>(options.min_num_inliers), 1);
  if (valid_matches.size() < min_num_inliers) return geometry;

  const size_t num_valid = valid_matches.size();
  const double max_error_px = options.ransac.max_error;

  // Trial budgets. A pair needs min_num_inliers inliers, and F and H only change the outcome
  // when they explain a set fraction of the other model's inliers, so each RANSAC need only
  // search for models with at least that many inliers (`num_inliers_sought`), which RANSAC
  // turns into its bound on trials. The chance matches of a non-overlapping pair are few
  // (15-35 on templeRing), which makes this a few dozen to a few hundred trials instead of
  // the cap.
  const auto bounded_options = [&](double max_error, RansacStream stream,
                                   double num_inliers_sought) {
    RansacOptions ransac_options = StreamRansacOptions(options, max_error, stream);
    ransac_options.min_inlier_ratio = std::clamp(
        num_inliers_sought / static_cast<double>(num_valid), options.ransac.min_inlier_ratio, 1.0);
    return ransac_options;
  };

  const bool calibrated = options.use_essential_when_calibrated && camera1.has_prior_focal_length &&
                          camera2.has_prior_focal_length && camera1.VerifyParams() &&
                          camera2.VerifyParams();
  // E's RANSAC stops once its models fall far short of the significance test below
  // (SignificantInlierCount). Only E's: a calibrated epipolar model's chance rate varies
  // little from model to model, while F's seven degrees of freedom (and H's eight) let a
  // chance model take in a cluster of keypoints, and bounding their searches by such a
  // model's rate lost weak real pairs (16 true inliers of 30 matches).
  const uint64_t chance_seed = DeriveSeed(options.ransac.random_seed, 0);
  const double max_log10_num_false_alarms = std::log10(options.max_num_false_alarms);

  // E first when the intrinsics are known: it is the model sought, and its 5-point samples
  // find a given inlier ratio in far fewer trials than F's 7-point ones.
  RansacReport<Eigen::Matrix3d> E_report;
  std::vector<Eigen::Vector2d> normalized1, normalized2;
  double E_max_error = 0.0;
  if (calibrated) {
    normalized1.resize(matched1.size());
    normalized2.resize(matched2.size());
    for (size_t i = 0; i < matched1.size(); ++i) {
      normalized1[i] = camera1.CamFromImg(matched1[i]);
      normalized2[i] = camera2.CamFromImg(matched2[i]);
    }
    E_max_error = 0.5 * (camera1.CamFromImgThreshold(max_error_px) +
                         camera2.CamFromImgThreshold(max_error_px));
    const LoRansac<EssentialMatrixFivePointEstimator, EssentialMatrixEightPointEstimator> E_ransac(
        bounded_options(E_max_error, kEssentialStream, static_cast<double>(min_num_inliers)));
    E_report = E_ransac.Estimate(
        normalized1, normalized2,
        SignificantInlierCount<EssentialMatrixFivePointEstimator>(
            normalized1, normalized2, E_max_error, chance_seed, max_log10_num_false_alarms));
  }
  const size_t E_num_inliers = E_report.success ? E_report.num_inliers : 0;

  // Once E is found, F only matters when it explains more than E's inliers divided by
  // min_E_F_inlier_ratio (the pair is then uncalibrated); otherwise it must reach the minimum.
  const bool E_found = E_num_inliers >= min_num_inliers;
  const double F_num_inliers_sought =
      E_found ? static_cast<double>(E_num_inliers) / std::max(options.min_E_F_inlier_ratio, 1e-9)
              : static_cast<double>(min_num_inliers);
  // With the intrinsics known, a pair E does not explain is not searched for an F (see
  // uncalibrated_fallback): only H may still explain it, a pure rotation (where E is not
  // determined) or a plane.
  RansacReport<Eigen::Matrix3d> F_report;
  if (!calibrated || E_found || options.uncalibrated_fallback) {
    const LoRansac<FundamentalMatrixSevenPointEstimator, FundamentalMatrixEightPointEstimator>
        F_ransac(bounded_options(max_error_px, kFundamentalStream, F_num_inliers_sought));
    F_report = F_ransac.Estimate(matched1, matched2);
  }
  const size_t F_num_inliers = F_report.success ? F_report.num_inliers : 0;

  // H only changes the classification when it explains more than max_H_inlier_ratio of the
  // inliers of the epipolar model chosen (or, with none, when it reaches the minimum).
  const auto ratio = [](size_t numerator, size_t denominator) {
    return denominator == 0 ? std::numeric_limits<double>::infinity()
                            : static_cast<double>(numerator) / static_cast<double>(denominator);
  };
  const bool calibrated_branch =
      E_found && ratio(E_num_inliers, F_num_inliers) >= options.min_E_F_inlier_ratio;
  const bool uncalibrated_branch = !calibrated_branch && F_num_inliers >= min_num_inliers;
  const double H_num_inliers_sought =
      calibrated_branch     ? options.max_H_inlier_ratio * static_cast<double>(E_num_inliers)
      : uncalibrated_branch ? options.max_H_inlier_ratio * static_cast<double>(F_num_inliers)
                            : static_cast<double>(min_num_inliers);
  const LoRansac<HomographyMatrixEstimator> H_ransac(
      bounded_options(max_error_px, kHomographyStream, H_num_inliers_sought));
  const auto H_report = H_ransac.Estimate(matched1, matched2);
  const size_t H_num_inliers = H_report.success ? H_report.num_inliers : 0;

  // COLMAP's classification: prefer the calibrated model when E explains (nearly) all of
  // F's inliers; call the pair planar or panoramic when H explains most of them too.
  const std::vector<char>* inlier_mask = nullptr;
  size_t num_inliers = 0;
  const RansacReport<Eigen::Matrix3d>* chosen = nullptr;
  const auto choose = [&](const RansacReport<Eigen::Matrix3d>& report, size_t count) {
    inlier_mask = &report.inlier_mask;
    num_inliers = count;
    chosen = &report;
  };
  if (calibrated_branch) {
    if (E_num_inliers >= F_num_inliers) {
      choose(E_report, E_num_inliers);
    } else {
      choose(F_report, F_num_inliers);
    }
    if (ratio(H_num_inliers, E_num_inliers) > options.max_H_inlier_ratio) {
      geometry.config = TwoViewGeometry::kPlanarOrPanoramic;
      if (H_num_inliers > num_inliers) choose(H_report, H_num_inliers);
    } else {
      geometry.config = TwoViewGeometry::kCalibrated;
    }
  } else if (uncalibrated_branch) {
    choose(F_report, F_num_inliers);
    if (ratio(H_num_inliers, F_num_inliers) > options.max_H_inlier_ratio) {
      geometry.config = TwoViewGeometry::kPlanarOrPanoramic;
      if (H_num_inliers > num_inliers) choose(H_report, H_num_inliers);
    } else {
      geometry.config = TwoViewGeometry::kUncalibrated;
    }
  } else if (H_num_inliers >= min_num_inliers) {
    // Only H fits: a plane or a pure rotation, where F is not determined.
    choose(H_report, H_num_inliers);
    geometry.config = TwoViewGeometry::kPlanarOrPanoramic;
  } else {
    return geometry;
  }

  // Matches along one line (or on one point) satisfy every model of the family, and one
  // keypoint matched many times (no cross-check) is one observation, not many: refuse both.
  if (AreNearlyCollinear(matched1, *inlier_mask, max_error_px) ||
      AreNearlyCollinear(matched2, *inlier_mask, max_error_px) ||
      CountDistinctKeypoints(valid_matches, *inlier_mask) < min_num_inliers) {
    PARALLAX_LOG(Debug) << "Two-view inliers are collinear or repeated: degenerate pair";
    geometry.config = TwoViewGeometry::kDegenerate;
    return geometry;
  }

  // Chance matches: RANSAC always finds some model that explains a few of them, more the more
  // matches there are. Keep the pair only when so many inliers would be unexpected.
  double log10_num_false_alarms = 0.0;
  if (chosen == &E_report) {
    log10_num_false_alarms =
        Log10NumFalseAlarms(EssentialMatrixFivePointEstimator(), normalized1, normalized2,
                            E_report.model, E_max_error, num_inliers, chance_seed);
  } else if (chosen == &F_report) {
    log10_num_false_alarms =
        Log10NumFalseAlarms(FundamentalMatrixSevenPointEstimator(), matched1, matched2,
                            F_report.model, max_error_px, num_inliers, chance_seed);
  } else {
    log10_num_false_alarms =
        Log10NumFalseAlarms(HomographyMatrixEstimator(), matched1, matched2, H_report.model,
                            max_error_px, num_inliers, chance_seed);
  }
  if (log10_num_false_alarms > max_log10_num_false_alarms) {
    PARALLAX_LOG(Debug) << "Two-view inliers (" << num_inliers << " of " << num_valid
                        << ") could be chance: 10^" << log10_num_false_alarms
                        << " false alarms expected; degenerate pair";
    geometry.config = TwoViewGeometry::kDegenerate;
    return geometry;
  }

  if (E_report.success) geometry.E = E_report.model;
  if (H_report.success) geometry.H = H_report.model;
  // When E explains the pair, F's RANSAC only searched for a better F and may have stopped
  // early: the F implied by E is then the better estimate.
  if (F_report.success && chosen != &E_report) {
    geometry.F = F_report.model;
  } else if (E_report.success) {
    geometry.F = FundamentalFromEssential(E_report.model, camera1.CalibrationMatrix(),
                                          camera2.CalibrationMatrix());
    geometry.F /= geometry.F.norm();
  }
  geometry.inlier_matches.reserve(num_inliers);
  for (size_t i = 0; i < valid_matches.size(); ++i) {
    if ((*inlier_mask)[i]) geometry.inlier_matches.push_back(valid_matches[i]);
  }

  if (DetectWatermark(camera1, matched1, camera2, matched2, *inlier_mask, num_inliers, options)) {
    geometry.config = TwoViewGeometry::kWatermark;
    return geometry;
  }
  if (!options.compute_relative_pose ||
      !EstimateTwoViewGeometryPose(camera1, points1, camera2, points2, &geometry)) {
    return geometry;
  }

  // In a plane or a pure rotation F (and E for a rotation) is a family, and RANSAC settles on
  // the member that also collects the most outliers. H is the model there: a panoramic pair
  // keeps H's inliers; a planar pair keeps H's inliers plus the matches that also fit the
  // epipolar geometry of the pose from H (points off the plane).
  const bool panoramic = geometry.config == TwoViewGeometry::kPanoramic;
  if ((panoramic || geometry.config == TwoViewGeometry::kPlanar) &&
      H_num_inliers >= min_num_inliers) {
    std::vector<char> refined_mask = H_report.inlier_mask;
    if (!panoramic) {
      const Eigen::Matrix3d F_pose =
          FundamentalFromEssential(EssentialFromPose(geometry.cam2_from_cam1),
                                   camera1.CalibrationMatrix(), camera2.CalibrationMatrix());
      const double max_squared_error = max_error_px * max_error_px;
      for (size_t i = 0; i < refined_mask.size(); ++i) {
        if (!refined_mask[i] && (*inlier_mask)[i] &&
            ComputeSquaredSampsonError(matched1[i], matched2[i], F_pose) <= max_squared_error) {
          refined_mask[i] = 1;
        }
      }
    }
    geometry.inlier_matches.clear();
    for (size_t i = 0; i < valid_matches.size(); ++i) {
      if (refined_mask[i]) geometry.inlier_matches.push_back(valid_matches[i]);
    }
  }
  return geometry;
}

bool EstimateTwoViewGeometryPose(const Camera& camera1, const std::vector<Eigen::Vector2d>& points1,
                                 const Camera& camera2, const std::vector<Eigen::Vector2d>& points2,
                                 TwoViewGeometry* geometry) {
  geometry->triangulation_angle = 0.0;
  const int config = geometry->config;
  const bool epipolar =
      config == TwoViewGeometry::kCalibrated || config == TwoViewGeometry::kUncalibrated;
  const bool planar = config == TwoViewGeometry::kPlanar || config == TwoViewGeometry::kPanoramic ||
                      config == TwoViewGeometry::kPlanarOrPanoramic;
  if ((!epipolar && !planar) || !camera1.VerifyParams() || !camera2.VerifyParams()) return false;

  std::vector<Eigen::Vector2d> normalized1, normalized2;
  normalized1.reserve(geometry->inlier_matches.size());
  normalized2.reserve(geometry->inlier_matches.size());
  for (const FeatureMatch& match : geometry->inlier_matches) {
    PARALLAX_CHECK_LT(match.point2D_idx1, points1.size());
    PARALLAX_CHECK_LT(match.point2D_idx2, points2.size());
    const Eigen::Vector2d normalized_point1 = camera1.CamFromImg(points1[match.point2D_idx1]);
    const Eigen::Vector2d normalized_point2 = camera2.CamFromImg(points2[match.point2D_idx2]);
    if (!normalized_point1.allFinite() || !normalized_point2.allFinite()) continue;
    normalized1.push_back(normalized_point1);
    normalized2.push_back(normalized_point2);
  }
  if (normalized1.empty()) return false;

  const Eigen::Matrix3d K1 = camera1.CalibrationMatrix();
  const Eigen::Matrix3d K2 = camera2.CalibrationMatrix();
  Rigid3d cam2_from_cam1;
  std::vector<Eigen::Vector3d> points3D;
  if (epipolar) {
    const Eigen::Matrix3d E = config == TwoViewGeometry::kCalibrated
                                  ? geometry->E
                                  : EssentialFromFundamental(geometry->F, K1, K2);
    if (!PoseFromEssentialMatrix(E, normalized1, normalized2, &cam2_from_cam1, &points3D)) {
      return false;
    }
  } else {
    const Eigen::Matrix3d H_calibrated = K2.inverse() * geometry->H * K1;
    bool panoramic = false;
    if (!PoseFromCalibratedHomography(H_calibrated, normalized1, normalized2, &cam2_from_cam1,
                                      &points3D, &panoramic)) {
      return false;
    }
    geometry->config = panoramic ? TwoViewGeometry::kPanoramic : TwoViewGeometry::kPlanar;
  }
  geometry->cam2_from_cam1 = cam2_from_cam1;

  if (!points3D.empty()) {
    const Eigen::Vector3d center1 = Eigen::Vector3d::Zero();
    const Eigen::Vector3d center2 = ProjectionCenter(cam2_from_cam1);
    std::vector<double> angles(points3D.size());
    for (size_t i = 0; i < points3D.size(); ++i) {
      angles[i] = CalculateTriangulationAngle(center1, center2, points3D[i]);
    }
    const auto middle = angles.begin() + static_cast<std::ptrdiff_t>(angles.size() / 2);
    std::nth_element(angles.begin(), middle, angles.end());
    geometry->triangulation_angle = *middle;
  }
  return true;
}

}  // namespace parallax
