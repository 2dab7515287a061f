#pragma once

#include <Eigen/Core>
#include <vector>

#include "parallax/feature/types.h"
#include "parallax/optim/ransac.h"
#include "parallax/scene/camera.h"
#include "parallax/scene/two_view_geometry.h"

namespace parallax {

struct TwoViewGeometryOptions {
  int min_num_inliers = 15;  // Fewer inliers: the pair is degenerate.
  // The RANSAC of E, F, H and the watermark test. max_error is in pixels (F, H; E's is
  // scaled by the focal lengths). min_inlier_ratio is COLMAP's 0.25 with a multiplier of 1 on
  // its bound; each model's search is raised further to the fewest inliers that could change
  // the outcome (min_num_inliers, and the E/F and H/F ratios below), so chance matches are
  // rejected in few trials; E's, also to the fewest that would pass the significance test at
  // the chance rate of its best model so far (SignificantInlierCount). The seed is the pair's:
  // matching derives it from --seed and the pair, and each model's RANSAC derives its own from it.
  // Confidence 0.999 (COLMAP's) and at most 5,000 trials per model: pairs that overlap stop
  // long before (their inlier ratio is high), so the cap binds on pairs that fail with many
  // chance matches, two in five of the pairs retrieval proposes on a survey; at 0.9999 and
  // 10,000 trials they took most of verification's time (docs/pair-selection.md, "Trials per
  // pair").
  RansacOptions ransac = [] {
    RansacOptions options;
    options.max_error = 4.0;
    options.confidence = 0.999;
    options.max_num_trials = 5000;
    options.min_inlier_ratio = 0.25;
    options.min_inlier_ratio_trials_multiplier = 1.0;
    return options;
  }();
  // Significance: a pair is kept only when at most this many models would be expected to
  // explain as many of its matches by chance (a-contrario number of false alarms; Moisan &
  // Stival 2004). Without it, random matches pass once a pair has ~100 of them.
  double max_num_false_alarms = 1.0;
  // Planar/panoramic classification (COLMAP's rules).
  double min_E_F_inlier_ratio = 0.95;  // E explains F's inliers: calibrated.
  double max_H_inlier_ratio = 0.8;     // H explains more than this of the inliers: planar.
  double watermark_min_inlier_ratio = 0.7;
  // Use the essential matrix when both cameras have a prior focal length.
  bool use_essential_when_calibrated = true;
  // When E explains fewer than min_num_inliers matches of a calibrated pair, search F as
  // well, as COLMAP does (a pair F alone explains is then uncalibrated). Off by default, as in
  // OpenMVG and Theia, which verify calibrated pairs by E alone: a prior focal length is one
  // the user gave and bundle adjustment holds (Parallax never sets it from EXIF), so a rigid
  // pair of views has an E, and what only F's two more degrees of freedom explain is not
  // one. H is still searched (a pure rotation leaves E undetermined). For COLMAP databases,
  // whose priors may come from EXIF.
  bool uncalibrated_fallback = false;
  // Compute cam2_from_cam1 and triangulation_angle for calibrated/uncalibrated pairs.
  bool compute_relative_pose = true;
  void Check() const;
};

// Verifies putative matches between two images with LO-RANSAC around the 5-point essential
// matrix when the cameras are calibrated (tried first), the 7-point fundamental matrix (8-point
// refinement) and the 4-point homography; classifies the pair as COLMAP does, then rejects it
// when its inliers could be chance (max_num_false_alarms).
// points1/points2 are all keypoints of each image in pixels.
//
// The steps below, in this order (COLMAP's split of two-view geometry): the calibrated model
// (E), the uncalibrated one (F), the homography (H) and the planar/panoramic decision, then the
// pose from the geometry.
TwoViewGeometry EstimateTwoViewGeometry(const Camera& camera1,
                                        const std::vector<Eigen::Vector2d>& points1,
                                        const Camera& camera2,
                                        const std::vector<Eigen::Vector2d>& points2,
                                        const FeatureMatches& matches,
                                        const TwoViewGeometryOptions& options);

// Relative pose and median triangulation angle of a verified pair from its E (or F and the
// cameras, or H): fills geometry->cam2_from_cam1 and triangulation_angle, and tells a planar
// pair (kPlanarOrPanoramic) planar from panoramic. False when no pose.
bool EstimateTwoViewGeometryPose(const Camera& camera1, const std::vector<Eigen::Vector2d>& points1,
                                 const Camera& camera2, const std::vector<Eigen::Vector2d>& points2,
                                 TwoViewGeometry* geometry);

// ---------------------------------------------------------------------------------------------
// The steps of EstimateTwoViewGeometry, each callable alone.

// The matches whose keypoints are both finite (no model explains the others), with their
// keypoints in pixels: what the models are estimated on. Checks the match indices.
struct TwoViewCorrespondences {
  FeatureMatches matches;
  std::vector<Eigen::Vector2d> points1, points2;  // One per match.
  size_t size() const { return matches.size(); }
};
TwoViewCorrespondences FiniteCorrespondences(const std::vector<Eigen::Vector2d>& points1,
                                             const std::vector<Eigen::Vector2d>& points2,
                                             const FeatureMatches& matches);

// The fewest inliers of a pair that is not degenerate: min_num_inliers, at least 1.
size_t MinNumTwoViewInliers(const TwoViewGeometryOptions& options);

// Whether the pair is verified by E first: use_essential_when_calibrated and both cameras
// with a prior focal length and valid parameters.
bool IsCalibratedPair(const Camera& camera1, const Camera& camera2,
                      const TwoViewGeometryOptions& options);

// One model's LO-RANSAC report, and its number of inliers (0 when it found none).
using TwoViewModelReport = RansacReport<Eigen::Matrix3d>;
inline size_t NumModelInliers(const TwoViewModelReport& report) {
  return report.success ? report.num_inliers : 0;
}

// Calibrated: E by LO-RANSAC around the 5-point solver (8-point refinement) on the
// correspondences' normalised coordinates, at max_error converted through both cameras
// (Camera::CamFromImgThreshold, averaged). It searches for at least MinNumTwoViewInliers and
// stops once its models fall far short of the significance test (SignificantInlierCount).
struct CalibratedTwoViewModel {
  TwoViewModelReport report;
  std::vector<Eigen::Vector2d> normalized1, normalized2;  // CamFromImg of the points.
  double max_error = 0.0;                                 // Normalised units.
};
CalibratedTwoViewModel EstimateCalibratedTwoViewModel(const Camera& camera1, const Camera& camera2,
                                                      const TwoViewCorrespondences& correspondences,
                                                      const TwoViewGeometryOptions& options);

// Uncalibrated: F by LO-RANSAC around the 7-point solver (8-point refinement) in pixels. Once
// E has MinNumTwoViewInliers, F only matters when it explains more than E's inliers divided
// by min_E_F_inlier_ratio (the pair is then uncalibrated), so it searches only for that many;
// otherwise for MinNumTwoViewInliers. `E_num_inliers` is 0 for an uncalibrated pair.
TwoViewModelReport EstimateUncalibratedTwoViewModel(const TwoViewCorrespondences& correspondences,
                                                    size_t E_num_inliers,
                                                    const TwoViewGeometryOptions& options);

// The epipolar model that explains the pair, from E's and F's inlier counts (COLMAP's rule):
// E (calibrated) when it has MinNumTwoViewInliers and at least min_E_F_inlier_ratio of F's
// inliers; else F (uncalibrated) when it has MinNumTwoViewInliers; else none.
enum class EpipolarTwoViewModel { kNone, kCalibrated, kUncalibrated };
EpipolarTwoViewModel ChooseEpipolarTwoViewModel(size_t E_num_inliers, size_t F_num_inliers,
                                                const TwoViewGeometryOptions& options);

// Planar: H by LO-RANSAC around the 4-point solver in pixels. H only changes the decision when
// it explains more than max_H_inlier_ratio of the inliers of the epipolar model chosen, so it
// searches only for that many (MinNumTwoViewInliers when there is none).
TwoViewModelReport EstimatePlanarTwoViewModel(const TwoViewCorrespondences& correspondences,
                                              size_t E_num_inliers, size_t F_num_inliers,
                                              const TwoViewGeometryOptions& options);

// The planar/panoramic decision (COLMAP's): the configuration from the three inlier counts,
// and the model whose inliers the pair keeps. The calibrated model keeps E's inliers (F's
// if more), the uncalibrated F's; either becomes kPlanarOrPanoramic when H explains more than
// max_H_inlier_ratio of them, and keeps H's inliers if more. With no epipolar model, H alone
// with MinNumTwoViewInliers makes a kPlanarOrPanoramic pair (a plane or a pure rotation, where
// F is not determined). With nothing, model is kNone and the pair degenerate.
enum class TwoViewModelKind { kNone, kEssential, kFundamental, kHomography };
struct TwoViewDecision {
  int config = TwoViewGeometry::kDegenerate;
  TwoViewModelKind model = TwoViewModelKind::kNone;
  size_t num_inliers = 0;  // The kept model's.
};
TwoViewDecision DecideTwoViewGeometry(size_t E_num_inliers, size_t F_num_inliers,
                                      size_t H_num_inliers, const TwoViewGeometryOptions& options);

}  // namespace parallax
