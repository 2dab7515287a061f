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

// The pair's RANSAC options for one model's search: `max_error` in that model's unit, and
// min_inlier_ratio raised to the ratio of `num_inliers_sought`, the fewest inliers that
// would change the outcome. RANSAC turns it into its bound on trials: the chance matches of a
// non-overlapping pair are few (15-35 on templeRing), which makes this a few dozen to a few
// hundred trials instead of the cap.
RansacOptions BoundedRansacOptions(const TwoViewGeometryOptions& options, double max_error,
                                   RansacStream stream, double num_inliers_sought,
                                   size_t num_correspondences) {
  RansacOptions ransac_options = StreamRansacOptions(options, max_error, stream);
  ransac_options.min_inlier_ratio =
      std::clamp(num_inliers_sought / static_cast<double>(num_correspondences),
                 options.ransac.min_inlier_ratio, 1.0);
  return ransac_options;
}

// The seed of the significance test's chance pairs, shared by E's search and the final test so
// that both measure the same chance rate.
uint64_t ChanceSeed(const TwoViewGeometryOptions& options) {
  return DeriveSeed(options.ransac.random_seed, 0);
}

double Ratio(size_t numerator, size_t denominator) {
  return denominator == 0 ? std::numeric_limits<double>::infinity()
                          : static_cast<double>(numerator) / static_cast<double>(denominator);
}

// Whether the kept model's inliers say nothing: along one line (or on one point) they satisfy
// every model of the family, one keypoint matched many times (no cross-check) is one
// observation, not many, and RANSAC always finds some model that explains a few chance
// matches, more the more matches there are: the pair is kept only when so many inliers would
// be unexpected (max_num_false_alarms).
bool AreDegenerateOrChance(const TwoViewCorrespondences& correspondences,
                           const CalibratedTwoViewModel& E, const TwoViewModelReport& F_report,
                           const TwoViewModelReport& H_report, const TwoViewDecision& decision,
                           const TwoViewGeometryOptions& options) {
  const std::vector<char>& inlier_mask =
      decision.model == TwoViewModelKind::kEssential     ? E.report.inlier_mask
      : decision.model == TwoViewModelKind::kFundamental ? F_report.inlier_mask
                                                         : H_report.inlier_mask;
  const double max_error_px = options.ransac.max_error;
  if (AreNearlyCollinear(correspondences.points1, inlier_mask, max_error_px) ||
      AreNearlyCollinear(correspondences.points2, inlier_mask, max_error_px) ||
      CountDistinctKeypoints(correspondences.matches, inlier_mask) <
          MinNumTwoViewInliers(options)) {
    PARALLAX_LOG(Debug) << "Two-view inliers are collinear or repeated: degenerate pair";
    return true;
  }
  const uint64_t chance_seed = ChanceSeed(options);
  double log10_num_false_alarms = 0.0;
  if (decision.model == TwoViewModelKind::kEssential) {
    log10_num_false_alarms =
        Log10NumFalseAlarms(EssentialMatrixFivePointEstimator(), E.normalized1, E.normalized2,
                            E.report.model, E.max_error, decision.num_inliers, chance_seed);
  } else if (decision.model == TwoViewModelKind::kFundamental) {
    log10_num_false_alarms = Log10NumFalseAlarms(
        FundamentalMatrixSevenPointEstimator(), correspondences.points1, correspondences.points2,
        F_report.model, max_error_px, decision.num_inliers, chance_seed);
  } else {
    log10_num_false_alarms = Log10NumFalseAlarms(
        HomographyMatrixEstimator(), correspondences.points1, correspondences.points2,
        H_report.model, max_error_px, decision.num_inliers, chance_seed);
  }
  if (log10_num_false_alarms > std::log10(options.max_num_false_alarms)) {
    PARALLAX_LOG(Debug) << "Two-view inliers (" << decision.num_inliers << " of "
                        << correspondences.size() << ") could be chance: 10^"
                        << log10_num_false_alarms << " false alarms expected; degenerate pair";
    return true;
  }
  return false;
}

// In a plane or a pure rotation F (and E for a rotation) is a family, and RANSAC settles on
// the member that also collects the most outliers. H is the model there: a panoramic pair
// keeps H's inliers; a planar pair keeps H's inliers plus the matches of `inlier_mask` that
// also fit the epipolar geometry of the pose from H (points off the plane).
FeatureMatches PlanarInlierMatches(const Camera& camera1, const Camera& camera2,
                                   const TwoViewCorrespondences& correspondences,
                                   const TwoViewGeometry& geometry,
                                   const std::vector<char>& inlier_mask,
                                   const TwoViewModelReport& H_report,
                                   const TwoViewGeometryOptions& options) {
  std::vector<char> refined_mask = H_report.inlier_mask;
  if (geometry.config != TwoViewGeometry::kPanoramic) {
    const Eigen::Matrix3d F_pose =
        FundamentalFromEssential(EssentialFromPose(geometry.cam2_from_cam1),
                                 camera1.CalibrationMatrix(), camera2.CalibrationMatrix());
    const double max_squared_error = options.ransac.max_error * options.ransac.max_error;
    for (size_t i = 0; i < refined_mask.size(); ++i) {
      if (!refined_mask[i] && inlier_mask[i] &&
          ComputeSquaredSampsonError(correspondences.points1[i], correspondences.points2[i],
                                     F_pose) <= max_squared_error) {
        refined_mask[i] = 1;
      }
    }
  }
  FeatureMatches inlier_matches;
  for (size_t i = 0; i < correspondences.size(); ++i) {
    if (refined_mask[i]) inlier_matches.push_back(correspondences.matches[i]);
  }
  return inlier_matches;
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

TwoViewCorrespondences FiniteCorrespondences(const std::vector<Eigen::Vector2d>& points1,
                                             const std::vector<Eigen::Vector2d>& points2,
                                             const FeatureMatches& matches) {
  TwoViewCorrespondences correspondences;
  correspondences.matches.reserve(matches.size());
  correspondences.points1.reserve(matches.size());
  correspondences.points2.reserve(matches.size());
  for (const FeatureMatch& match : matches) {
    PARALLAX_CHECK_LT(match.point2D_idx1, points1.size());
    PARALLAX_CHECK_LT(match.point2D_idx2, points2.size());
    const Eigen::Vector2d& point1 = points1[match.point2D_idx1];
    const Eigen::Vector2d& point2 = points2[match.point2D_idx2];
    if (!point1.allFinite() || !point2.allFinite()) continue;
    correspondences.matches.push_back(match);
    correspondences.points1.push_back(point1);
    correspondences.points2.push_back(point2);
  }
  return correspondences;
}

size_t MinNumTwoViewInliers(const TwoViewGeometryOptions& options) {
  return std::max<size_t>(static_cast<size_t>(options.min_num_inliers), 1);
}

bool IsCalibratedPair(const Camera& camera1, const Camera& camera2,
                      const TwoViewGeometryOptions& options) {
  return options.use_essential_when_calibrated && camera1.has_prior_focal_length &&
         camera2.has_prior_focal_length && camera1.VerifyParams() && camera2.VerifyParams();
}

CalibratedTwoViewModel EstimateCalibratedTwoViewModel(const Camera& camera1, const Camera& camera2,
                                                      const TwoViewCorrespondences& correspondences,
                                                      const TwoViewGeometryOptions& options) {
  CalibratedTwoViewModel E;
  const size_t num_correspondences = correspondences.size();
  E.normalized1.resize(num_correspondences);
  E.normalized2.resize(num_correspondences);
  for (size_t i = 0; i < num_correspondences; ++i) {
    E.normalized1[i] = camera1.CamFromImg(correspondences.points1[i]);
    E.normalized2[i] = camera2.CamFromImg(correspondences.points2[i]);
  }
  const double max_error_px = options.ransac.max_error;
  E.max_error =
      0.5 * (camera1.CamFromImgThreshold(max_error_px) + camera2.CamFromImgThreshold(max_error_px));
  // Only E's search stops at the significance test's count: a calibrated epipolar model's
  // chance rate varies little from model to model, while F's seven degrees of freedom (and
  // H's eight) let a chance model take in a cluster of keypoints, and bounding their searches
  // by such a model's rate lost weak real pairs (16 true inliers of 30 matches).
  const LoRansac<EssentialMatrixFivePointEstimator, EssentialMatrixEightPointEstimator> ransac(
      BoundedRansacOptions(options, E.max_error, kEssentialStream,
                           static_cast<double>(MinNumTwoViewInliers(options)),
                           num_correspondences));
  E.report = ransac.Estimate(E.normalized1, E.normalized2,
                             SignificantInlierCount<EssentialMatrixFivePointEstimator>(
                                 E.normalized1, E.normalized2, E.max_error, ChanceSeed(options),
                                 std::log10(options.max_num_false_alarms)));
  return E;
}

TwoViewModelReport EstimateUncalibratedTwoViewModel(const TwoViewCorrespondences& correspondences,
                                                    size_t E_num_inliers,
                                                    const TwoViewGeometryOptions& options) {
  const size_t min_num_inliers = MinNumTwoViewInliers(options);
  const double num_inliers_sought =
      E_num_inliers >= min_num_inliers
          ? static_cast<double>(E_num_inliers) / std::max(options.min_E_F_inlier_ratio, 1e-9)
          : static_cast<double>(min_num_inliers);
  const LoRansac<FundamentalMatrixSevenPointEstimator, FundamentalMatrixEightPointEstimator> ransac(
      BoundedRansacOptions(options, options.ransac.max_error, kFundamentalStream,
                           num_inliers_sought, correspondences.size()));
  return ransac.Estimate(correspondences.points1, correspondences.points2);
}

EpipolarTwoViewModel ChooseEpipolarTwoViewModel(size_t E_num_inliers, size_t F_num_inliers,
                                                const TwoViewGeometryOptions& options) {
  const size_t min_num_inliers = MinNumTwoViewInliers(options);
  if (E_num_inliers >= min_num_inliers &&
      Ratio(E_num_inliers, F_num_inliers) >= options.min_E_F_inlier_ratio) {
    return EpipolarTwoViewModel::kCalibrated;
  }
  if (F_num_inliers >= min_num_inliers) return EpipolarTwoViewModel::kUncalibrated;
  return EpipolarTwoViewModel::kNone;
}

TwoViewModelReport EstimatePlanarTwoViewModel(const TwoViewCorrespondences& correspondences,
                                              size_t E_num_inliers, size_t F_num_inliers,
                                              const TwoViewGeometryOptions& options) {
  const EpipolarTwoViewModel epipolar =
      ChooseEpipolarTwoViewModel(E_num_inliers, F_num_inliers, options);
  const double num_inliers_sought =
      epipolar == EpipolarTwoViewModel::kCalibrated
          ? options.max_H_inlier_ratio * static_cast<double>(E_num_inliers)
      : epipolar == EpipolarTwoViewModel::kUncalibrated
          ? options.max_H_inlier_ratio * static_cast<double>(F_num_inliers)
          : static_cast<double>(MinNumTwoViewInliers(options));
  const LoRansac<HomographyMatrixEstimator> ransac(
      BoundedRansacOptions(options, options.ransac.max_error, kHomographyStream, num_inliers_sought,
                           correspondences.size()));
  return ransac.Estimate(correspondences.points1, correspondences.points2);
}

TwoViewDecision DecideTwoViewGeometry(size_t E_num_inliers, size_t F_num_inliers,
                                      size_t H_num_inliers, const TwoViewGeometryOptions& options) {
  TwoViewDecision decision;
  const auto keep = [&](TwoViewModelKind model, size_t num_inliers) {
    decision.model = model;
    decision.num_inliers = num_inliers;
  };
  // The epipolar model's inliers; H's instead when H explains most of them and more.
  const auto planar_or = [&](int epipolar_config, size_t epipolar_num_inliers) {
    if (Ratio(H_num_inliers, epipolar_num_inliers) > options.max_H_inlier_ratio) {
      decision.config = TwoViewGeometry::kPlanarOrPanoramic;
      if (H_num_inliers > decision.num_inliers) keep(TwoViewModelKind::kHomography, H_num_inliers);
    } else {
      decision.config = epipolar_config;
    }
  };
  switch (ChooseEpipolarTwoViewModel(E_num_inliers, F_num_inliers, options)) {
    case EpipolarTwoViewModel::kCalibrated:
      if (E_num_inliers >= F_num_inliers) {
        keep(TwoViewModelKind::kEssential, E_num_inliers);
      } else {
        keep(TwoViewModelKind::kFundamental, F_num_inliers);
      }
      planar_or(TwoViewGeometry::kCalibrated, E_num_inliers);
      break;
    case EpipolarTwoViewModel::kUncalibrated:
      keep(TwoViewModelKind::kFundamental, F_num_inliers);
      planar_or(TwoViewGeometry::kUncalibrated, F_num_inliers);
      break;
    case EpipolarTwoViewModel::kNone:
      if (H_num_inliers >= MinNumTwoViewInliers(options)) {
        keep(TwoViewModelKind::kHomography, H_num_inliers);
        decision.config = TwoViewGeometry::kPlanarOrPanoramic;
      }
      break;
  }
  return decision;
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
  const TwoViewCorrespondences correspondences = FiniteCorrespondences(points1, points2, matches);
  const size_t min_num_inliers = MinNumTwoViewInliers(options);
  if (correspondences.size() < min_num_inliers) return geometry;

  // 1. Calibrated: E first when the intrinsics are known: it is the model sought, and its
  // 5-point samples find a given inlier ratio in far fewer trials than F's 7-point ones.
  const bool calibrated = IsCalibratedPair(camera1, camera2, options);
  CalibratedTwoViewModel E;
  if (calibrated) E = EstimateCalibratedTwoViewModel(camera1, camera2, correspondences, options);
  const size_t E_num_inliers = NumModelInliers(E.report);

  // 2. Uncalibrated: with the intrinsics known, a pair E does not explain is not searched for
  // an F (see uncalibrated_fallback): only H may still explain it, a pure rotation (where E is
  // not determined) or a plane.
  TwoViewModelReport F_report;
  if (!calibrated || E_num_inliers >= min_num_inliers || options.uncalibrated_fallback) {
    F_report = EstimateUncalibratedTwoViewModel(correspondences, E_num_inliers, options);
  }
  const size_t F_num_inliers = NumModelInliers(F_report);

  // 3. Planar, and the decision.
  const TwoViewModelReport H_report =
      EstimatePlanarTwoViewModel(correspondences, E_num_inliers, F_num_inliers, options);
  const size_t H_num_inliers = NumModelInliers(H_report);
  const TwoViewDecision decision =
      DecideTwoViewGeometry(E_num_inliers, F_num_inliers, H_num_inliers, options);
  if (decision.model == TwoViewModelKind::kNone) return geometry;
  if (AreDegenerateOrChance(correspondences, E, F_report, H_report, decision, options)) {
    return geometry;
  }
  geometry.config = decision.config;

  // 4. The verified geometry: its models and inliers.
  const bool kept_E = decision.model == TwoViewModelKind::kEssential;
  const std::vector<char>& inlier_mask = kept_E ? E.report.inlier_mask
                                         : decision.model == TwoViewModelKind::kFundamental
                                             ? F_report.inlier_mask
                                             : H_report.inlier_mask;
  if (E.report.success) geometry.E = E.report.model;
  if (H_report.success) geometry.H = H_report.model;
  // When E explains the pair, F's RANSAC only searched for a better F and may have stopped
  // early: the F implied by E is then the better estimate.
  if (F_report.success && !kept_E) {
    geometry.F = F_report.model;
  } else if (E.report.success) {
    geometry.F = FundamentalFromEssential(E.report.model, camera1.CalibrationMatrix(),
                                          camera2.CalibrationMatrix());
    geometry.F /= geometry.F.norm();
  }
  geometry.inlier_matches.reserve(decision.num_inliers);
  for (size_t i = 0; i < correspondences.size(); ++i) {
    if (inlier_mask[i]) geometry.inlier_matches.push_back(correspondences.matches[i]);
  }
  if (DetectWatermark(camera1, correspondences.points1, camera2, correspondences.points2,
                      inlier_mask, decision.num_inliers, options)) {
    geometry.config = TwoViewGeometry::kWatermark;
    return geometry;
  }

  // 5. The pose from the geometry; a planar pair's inliers from H and that pose.
  if (!options.compute_relative_pose ||
      !EstimateTwoViewGeometryPose(camera1, points1, camera2, points2, &geometry)) {
    return geometry;
  }
  if ((geometry.config == TwoViewGeometry::kPanoramic ||
       geometry.config == TwoViewGeometry::kPlanar) &&
      H_num_inliers >= min_num_inliers) {
    geometry.inlier_matches = PlanarInlierMatches(camera1, camera2, correspondences, geometry,
                                                  inlier_mask, H_report, options);
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
