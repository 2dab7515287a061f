// The steps of EstimateTwoViewGeometry, one at a time, on synthetic pairs with exact ground
// truth (two_view_geometry_test.cc tests the whole on noise and outliers).

#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cmath>
#include <iostream>
#include <limits>

#include "parallax/estimators/testing/matched_pair.h"
#include "parallax/estimators/two_view_geometry.h"
#include "parallax/geometry/rigid3.h"
#include "parallax/geometry/testing/random_geometry.h"
#include "parallax/math/random.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

using test::MatchedPair;
using test::PairStructure;
using test::ProjectiveDistance;
using test::RandomCalibratedPair;
using test::RandomMatchedPair;

TwoViewCorrespondences Correspondences(const MatchedPair& pair) {
  return FiniteCorrespondences(pair.points1, pair.points2, pair.matches);
}

// Every correspondence's transfer by H within `max_error` pixels.
void ExpectTransfers(const Eigen::Matrix3d& H, const TwoViewCorrespondences& correspondences,
                     double max_error) {
  for (size_t i = 0; i < correspondences.size(); ++i) {
    const Eigen::Vector2d transferred =
        (H * correspondences.points1[i].homogeneous()).hnormalized();
    EXPECT_LT((transferred - correspondences.points2[i]).norm(), max_error) << i;
  }
}

TEST(FiniteCorrespondences, KeepsFiniteMatchesInOrder) {
  SetPRNGSeed(1);
  MatchedPair pair = RandomMatchedPair(30, 0.0, 0.0, PairStructure::kGeneral);
  pair.points1[pair.matches[3].point2D_idx1].x() = std::numeric_limits<double>::quiet_NaN();
  pair.points2[pair.matches[7].point2D_idx2].y() = std::numeric_limits<double>::infinity();
  const TwoViewCorrespondences correspondences = Correspondences(pair);
  ASSERT_EQ(correspondences.size(), 28u);
  size_t kept = 0;
  for (size_t i = 0; i < pair.matches.size(); ++i) {
    if (i == 3 || i == 7) continue;
    EXPECT_EQ(correspondences.matches[kept], pair.matches[i]);
    EXPECT_EQ(correspondences.points1[kept], pair.points1[pair.matches[i].point2D_idx1]);
    EXPECT_EQ(correspondences.points2[kept], pair.points2[pair.matches[i].point2D_idx2]);
    ++kept;
  }
  FeatureMatches bad = pair.matches;
  bad.back().point2D_idx2 = static_cast<point2D_t>(pair.points2.size());
  EXPECT_THROW(FiniteCorrespondences(pair.points1, pair.points2, bad), CheckError);
}

TEST(TwoViewGeometrySteps, MinimumAndCalibration) {
  TwoViewGeometryOptions options;
  options.min_num_inliers = 0;
  EXPECT_EQ(MinNumTwoViewInliers(options), 1u);
  options.min_num_inliers = 15;
  EXPECT_EQ(MinNumTwoViewInliers(options), 15u);
  MatchedPair pair;
  EXPECT_FALSE(IsCalibratedPair(pair.camera1, pair.camera2, options));
  pair.camera1.has_prior_focal_length = pair.camera2.has_prior_focal_length = true;
  EXPECT_TRUE(IsCalibratedPair(pair.camera1, pair.camera2, options));
  options.use_essential_when_calibrated = false;
  EXPECT_FALSE(IsCalibratedPair(pair.camera1, pair.camera2, options));
}

TEST(EstimateCalibratedTwoViewModel, ExactPairGivesTheTrueE) {
  SetPRNGSeed(2);
  for (int trial = 0; trial < 5; ++trial) {
    const MatchedPair pair = RandomCalibratedPair(200, 0.0, 0.0);
    const TwoViewCorrespondences correspondences = Correspondences(pair);
    const TwoViewGeometryOptions options;
    const CalibratedTwoViewModel E =
        EstimateCalibratedTwoViewModel(pair.camera1, pair.camera2, correspondences, options);
    ASSERT_TRUE(E.report.success);
    EXPECT_EQ(NumModelInliers(E.report), 200u);
    EXPECT_LT(ProjectiveDistance(E.report.model, pair.TrueE()), 1e-8);
    // The threshold in normalised units: 4 px through focal lengths of 1000 and 1100 px.
    EXPECT_NEAR(E.max_error, 0.5 * (4.0 / 1000 + 4.0 / 1100), 1e-15);
    ASSERT_EQ(E.normalized1.size(), 200u);
    EXPECT_EQ(E.normalized1[5], pair.camera1.CamFromImg(correspondences.points1[5]));
    EXPECT_EQ(E.normalized2[5], pair.camera2.CamFromImg(correspondences.points2[5]));
  }
}

TEST(EstimateUncalibratedTwoViewModel, ExactPairGivesTheTrueF) {
  SetPRNGSeed(3);
  for (int trial = 0; trial < 5; ++trial) {
    const MatchedPair pair = RandomMatchedPair(200, 0.0, 0.0, PairStructure::kGeneral);
    const TwoViewModelReport F =
        EstimateUncalibratedTwoViewModel(Correspondences(pair), 0, TwoViewGeometryOptions());
    ASSERT_TRUE(F.success);
    EXPECT_EQ(NumModelInliers(F), 200u);
    EXPECT_LT(ProjectiveDistance(F.model, pair.TrueF()), 1e-6);
  }
}

// Once E explains all matches, no F could make the pair uncalibrated: the search is one trial.
TEST(EstimateUncalibratedTwoViewModel, SearchesOnlyForWhatWouldChangeTheOutcome) {
  SetPRNGSeed(4);
  const MatchedPair pair = RandomCalibratedPair(300, 0.5, 0.4);
  const TwoViewCorrespondences correspondences = Correspondences(pair);
  TwoViewGeometryOptions options;
  options.ransac.max_error = 1.5;
  const TwoViewModelReport unbounded =
      EstimateUncalibratedTwoViewModel(correspondences, 0, options);
  const TwoViewModelReport bounded =
      EstimateUncalibratedTwoViewModel(correspondences, correspondences.size(), options);
  EXPECT_GT(unbounded.num_trials, 1u);
  EXPECT_EQ(bounded.num_trials, 1u);
}

TEST(ChooseEpipolarTwoViewModel, ColmapsRule) {
  TwoViewGeometryOptions options;  // At least 15 inliers; E needs 95 % of F's.
  EXPECT_EQ(ChooseEpipolarTwoViewModel(100, 100, options), EpipolarTwoViewModel::kCalibrated);
  EXPECT_EQ(ChooseEpipolarTwoViewModel(95, 100, options), EpipolarTwoViewModel::kCalibrated);
  EXPECT_EQ(ChooseEpipolarTwoViewModel(94, 100, options), EpipolarTwoViewModel::kUncalibrated);
  EXPECT_EQ(ChooseEpipolarTwoViewModel(100, 0, options), EpipolarTwoViewModel::kCalibrated);
  EXPECT_EQ(ChooseEpipolarTwoViewModel(14, 14, options), EpipolarTwoViewModel::kNone);
  EXPECT_EQ(ChooseEpipolarTwoViewModel(0, 15, options), EpipolarTwoViewModel::kUncalibrated);
  EXPECT_EQ(ChooseEpipolarTwoViewModel(0, 0, options), EpipolarTwoViewModel::kNone);
}

TEST(EstimatePlanarTwoViewModel, ExactPlaneGivesTheTrueH) {
  SetPRNGSeed(5);
  for (int trial = 0; trial < 5; ++trial) {
    const MatchedPair pair = RandomMatchedPair(200, 0.0, 0.0, PairStructure::kPlane);
    const TwoViewCorrespondences correspondences = Correspondences(pair);
    const TwoViewModelReport H =
        EstimatePlanarTwoViewModel(correspondences, 0, 0, TwoViewGeometryOptions());
    ASSERT_TRUE(H.success);
    EXPECT_EQ(NumModelInliers(H), 200u);
    EXPECT_LT(ProjectiveDistance(H.model, pair.TrueH()), 1e-8);
    ExpectTransfers(pair.TrueH(), correspondences, 1e-8);
  }
}

TEST(DecideTwoViewGeometry, PlanarAndPanoramicDecision) {
  const TwoViewGeometryOptions options;  // H over 80 % of the epipolar inliers: planar.
  struct Case {
    size_t E, F, H;
    int config;
    TwoViewModelKind model;
    size_t num_inliers;
  };
  using Kind = TwoViewModelKind;
  const Case cases[] = {
      {100, 100, 50, TwoViewGeometry::kCalibrated, Kind::kEssential, 100},
      {96, 100, 50, TwoViewGeometry::kCalibrated, Kind::kFundamental, 100},
      {100, 100, 80, TwoViewGeometry::kCalibrated, Kind::kEssential, 100},
      {100, 100, 81, TwoViewGeometry::kPlanarOrPanoramic, Kind::kEssential, 100},
      {100, 100, 120, TwoViewGeometry::kPlanarOrPanoramic, Kind::kHomography, 120},
      {50, 100, 60, TwoViewGeometry::kUncalibrated, Kind::kFundamental, 100},
      {0, 100, 90, TwoViewGeometry::kPlanarOrPanoramic, Kind::kFundamental, 100},
      {0, 100, 101, TwoViewGeometry::kPlanarOrPanoramic, Kind::kHomography, 101},
      {0, 0, 15, TwoViewGeometry::kPlanarOrPanoramic, Kind::kHomography, 15},
      {10, 14, 14, TwoViewGeometry::kDegenerate, Kind::kNone, 0},
  };
  for (const Case& c : cases) {
    const TwoViewDecision decision = DecideTwoViewGeometry(c.E, c.F, c.H, options);
    EXPECT_EQ(decision.config, c.config) << c.E << " " << c.F << " " << c.H;
    EXPECT_EQ(decision.model, c.model) << c.E << " " << c.F << " " << c.H;
    EXPECT_EQ(decision.num_inliers, c.num_inliers) << c.E << " " << c.F << " " << c.H;
  }
}

// A geometry with the true model and every match an inlier.
TwoViewGeometry TrueGeometry(const MatchedPair& pair, int config) {
  TwoViewGeometry geometry;
  geometry.config = config;
  geometry.E = pair.TrueE();
  geometry.F = pair.TrueF();
  if (pair.plane_distance > 0) geometry.H = pair.TrueH();
  geometry.inlier_matches = pair.matches;
  return geometry;
}

TEST(EstimateTwoViewGeometryPose, FromTheTrueEssentialMatrix) {
  SetPRNGSeed(6);
  const MatchedPair pair = RandomCalibratedPair(100, 0.0, 0.0);
  TwoViewGeometry geometry = TrueGeometry(pair, TwoViewGeometry::kCalibrated);
  ASSERT_TRUE(EstimateTwoViewGeometryPose(pair.camera1, pair.points1, pair.camera2, pair.points2,
                                          &geometry));
  EXPECT_EQ(geometry.config, TwoViewGeometry::kCalibrated);
  EXPECT_LT(RotationAngleDegrees(geometry.cam2_from_cam1.rotation, pair.cam2_from_cam1.rotation),
            1e-9);
  EXPECT_LT((geometry.cam2_from_cam1.translation - pair.cam2_from_cam1.translation).norm(), 1e-9);
  EXPECT_NEAR(geometry.triangulation_angle, pair.TrueTriAngle(), 1e-9);
}

// A calibrated homography has two decompositions R + t n^T that put the points in front of
// both cameras when both see the plane from one side, and the points cannot tell them apart
// (Ma et al., "An Invitation to 3-D Vision", sec. 5.3.3): the pose must be one of them, the
// true one where it is that.
TEST(EstimateTwoViewGeometryPose, FromTheTrueHomographyOfAPlane) {
  SetPRNGSeed(7);
  int num_true = 0;
  for (int trial = 0; trial < 10; ++trial) {
    const MatchedPair pair = RandomMatchedPair(100, 0.0, 0.0, PairStructure::kPlane);
    TwoViewGeometry geometry = TrueGeometry(pair, TwoViewGeometry::kPlanarOrPanoramic);
    ASSERT_TRUE(EstimateTwoViewGeometryPose(pair.camera1, pair.points1, pair.camera2, pair.points2,
                                            &geometry));
    EXPECT_EQ(geometry.config, TwoViewGeometry::kPlanar);
    EXPECT_GT(geometry.triangulation_angle, 0.0);
    // R + t n^T for some n: the calibrated H, scaled to a middle singular value of 1, less R
    // is of rank one, along t.
    Eigen::Matrix3d H = pair.camera2.CalibrationMatrix().inverse() * pair.TrueH() *
                        pair.camera1.CalibrationMatrix();
    H /= Eigen::JacobiSVD<Eigen::Matrix3d>(H).singularValues()(1);
    const Eigen::Matrix3d rotation = geometry.cam2_from_cam1.rotation.toRotationMatrix();
    const Eigen::Matrix3d rest_plus = H - rotation, rest_minus = -H - rotation;
    const Eigen::Matrix3d rest = rest_plus.norm() < rest_minus.norm() ? rest_plus : rest_minus;
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(rest, Eigen::ComputeFullU);
    EXPECT_LT(svd.singularValues()(1), 1e-9 * svd.singularValues()(0));
    EXPECT_NEAR(std::abs(svd.matrixU().col(0).dot(geometry.cam2_from_cam1.translation)), 1.0, 1e-9);
    if (RotationAngleDegrees(geometry.cam2_from_cam1.rotation, pair.cam2_from_cam1.rotation) <
        1e-6) {
      ++num_true;
      EXPECT_LT((geometry.cam2_from_cam1.translation - pair.cam2_from_cam1.translation).norm(),
                1e-6);
      EXPECT_NEAR(geometry.triangulation_angle, pair.TrueTriAngle(), 1e-6);
    }
  }
  std::cerr << num_true << " of 10 planar pairs gave the true pose, the others its twin\n";
  EXPECT_GE(num_true, 3);
}

TEST(EstimateTwoViewGeometryPose, PureRotationIsPanoramic) {
  SetPRNGSeed(8);
  const MatchedPair pair =
      RandomMatchedPair(100, 0.0, 0.0, PairStructure::kGeneral, Eigen::Vector3d::Zero());
  // A rotation's homography is K2 R K1^-1 for any scene.
  TwoViewGeometry geometry;
  geometry.config = TwoViewGeometry::kPlanarOrPanoramic;
  geometry.H = pair.camera2.CalibrationMatrix() * pair.cam2_from_cam1.rotation.toRotationMatrix() *
               pair.camera1.CalibrationMatrix().inverse();
  geometry.inlier_matches = pair.matches;
  ASSERT_TRUE(EstimateTwoViewGeometryPose(pair.camera1, pair.points1, pair.camera2, pair.points2,
                                          &geometry));
  EXPECT_EQ(geometry.config, TwoViewGeometry::kPanoramic);
  EXPECT_LT(RotationAngleDegrees(geometry.cam2_from_cam1.rotation, pair.cam2_from_cam1.rotation),
            1e-9);
  EXPECT_EQ(geometry.cam2_from_cam1.translation, Eigen::Vector3d::Zero());
  EXPECT_EQ(geometry.triangulation_angle, 0.0);
}

}  // namespace
}  // namespace parallax
