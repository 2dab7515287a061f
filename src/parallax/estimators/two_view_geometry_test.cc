#include "parallax/estimators/two_view_geometry.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <iostream>
#include <limits>
#include <numeric>

#include "parallax/estimators/solvers/fundamental_matrix.h"
#include "parallax/estimators/testing/matched_pair.h"
#include "parallax/geometry/triangulation.h"
#include "parallax/math/random.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

using test::kImageHeight;
using test::kImageWidth;
using test::MatchedPair;
using test::PairStructure;
using test::RandomCalibratedPair;
using test::RandomImagePoint;
using test::RandomMatchedPair;

struct InlierCounts {
  size_t inliers_kept = 0, outliers_kept = 0, num_true_inliers = 0;
};

InlierCounts CountInliers(const MatchedPair& scene, const TwoViewGeometry& geometry) {
  InlierCounts counts;
  for (char inlier : scene.is_inlier) counts.num_true_inliers += inlier;
  for (const FeatureMatch& match : geometry.inlier_matches) {
    (scene.is_inlier[match.point2D_idx1] ? counts.inliers_kept : counts.outliers_kept)++;
  }
  return counts;
}

void ExpectGoodInliers(const MatchedPair& scene, const TwoViewGeometry& geometry) {
  const InlierCounts counts = CountInliers(scene, geometry);
  std::cerr << "kept " << counts.inliers_kept << "/" << counts.num_true_inliers << " inliers, "
            << counts.outliers_kept << "/" << scene.is_inlier.size() - counts.num_true_inliers
            << " outliers\n";
  EXPECT_GE(counts.inliers_kept, 0.95 * counts.num_true_inliers);
  // About 1 % of uniform outliers fall within 1.5 px of their epipolar line and cannot be
  // rejected (see NoisyOptions); the count is Poisson, so allow two and a half times that.
  const size_t num_outliers = scene.is_inlier.size() - counts.num_true_inliers;
  EXPECT_LE(counts.outliers_kept, 0.025 * num_outliers);
}

double TranslationAngleDegrees(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / M_PI;
}

// Noisy tests run at 3 sigma of the 0.5 px noise instead of COLMAP's 4 px default: a random
// outlier within the threshold of its epipolar line cannot be told from an inlier, and at 4 px
// about 1 % of uniform outliers are.
TwoViewGeometryOptions NoisyOptions() {
  TwoViewGeometryOptions options;
  options.ransac.max_error = 1.5;
  return options;
}

TwoViewGeometry Estimate(const MatchedPair& scene, const TwoViewGeometryOptions& options = {}) {
  return EstimateTwoViewGeometry(scene.camera1, scene.points1, scene.camera2, scene.points2,
                                 scene.matches, options);
}

TEST(EstimateTwoViewGeometry, CalibratedExactRecoversPose) {
  SetPRNGSeed(1);
  for (int trial = 0; trial < 5; ++trial) {
    const MatchedPair scene = RandomCalibratedPair(200, 0.0, 0.0);
    const TwoViewGeometry geometry = Estimate(scene);
    ASSERT_EQ(geometry.config, TwoViewGeometry::kCalibrated);
    EXPECT_EQ(geometry.inlier_matches.size(), scene.matches.size());
    EXPECT_LT((geometry.cam2_from_cam1.rotation.toRotationMatrix() -
               scene.cam2_from_cam1.rotation.toRotationMatrix())
                  .norm(),
              1e-8);
    EXPECT_LT((geometry.cam2_from_cam1.translation - scene.cam2_from_cam1.translation).norm(),
              1e-8);
    EXPECT_NEAR(geometry.triangulation_angle, scene.TrueTriAngle(), 1e-8);
    EXPECT_GT(geometry.F.norm(), 0.0);
    EXPECT_GT(geometry.H.norm(), 0.0);
  }
}

TEST(EstimateTwoViewGeometry, CalibratedNoiseAndOutliers) {
  SetPRNGSeed(2);
  for (int trial = 0; trial < 3; ++trial) {
    const MatchedPair scene = RandomCalibratedPair(1000, 0.5, 0.4);
    const TwoViewGeometry geometry = Estimate(scene, NoisyOptions());
    ASSERT_EQ(geometry.config, TwoViewGeometry::kCalibrated);
    ExpectGoodInliers(scene, geometry);
    EXPECT_LT(RotationAngleDegrees(geometry.cam2_from_cam1.rotation, scene.cam2_from_cam1.rotation),
              0.2);
    EXPECT_LT(TranslationAngleDegrees(geometry.cam2_from_cam1.translation,
                                      scene.cam2_from_cam1.translation),
              1.0);
    EXPECT_NEAR(geometry.triangulation_angle, scene.TrueTriAngle(), 0.02 * scene.TrueTriAngle());
  }
}

TEST(EstimateTwoViewGeometry, UncalibratedNoiseAndOutliers) {
  SetPRNGSeed(3);
  for (int trial = 0; trial < 3; ++trial) {
    const MatchedPair scene = RandomMatchedPair(1000, 0.5, 0.4, PairStructure::kGeneral);
    const TwoViewGeometry geometry = Estimate(scene, NoisyOptions());
    ASSERT_EQ(geometry.config, TwoViewGeometry::kUncalibrated);
    ExpectGoodInliers(scene, geometry);
    EXPECT_EQ(geometry.E, Eigen::Matrix3d::Zero());
    // The intrinsics happen to be right, so the pose from F and K is close.
    EXPECT_LT(RotationAngleDegrees(geometry.cam2_from_cam1.rotation, scene.cam2_from_cam1.rotation),
              0.5);
    EXPECT_LT(TranslationAngleDegrees(geometry.cam2_from_cam1.translation,
                                      scene.cam2_from_cam1.translation),
              2.0);
  }
  // Priors present but E switched off.
  const MatchedPair scene = RandomCalibratedPair(300, 0.5, 0.2);
  TwoViewGeometryOptions options;
  options.use_essential_when_calibrated = false;
  EXPECT_EQ(Estimate(scene, options).config, TwoViewGeometry::kUncalibrated);
}

TEST(EstimateTwoViewGeometry, PlanarSceneIsDetected) {
  SetPRNGSeed(4);
  for (const double noise : {0.0, 0.5}) {
    for (const bool calibrated : {false, true}) {
      MatchedPair scene =
          RandomMatchedPair(1000, noise, noise > 0 ? 0.4 : 0.0, PairStructure::kPlane);
      scene.camera1.has_prior_focal_length = calibrated;
      scene.camera2.has_prior_focal_length = calibrated;
      // H's transfer error carries the noise of both images: at 1.5 px H keeps ~85 % of the
      // plane's matches, F (Sampson error) nearly all plus some outliers, which puts H/F at
      // the 0.8 planar threshold; 2 px keeps ~95 % (see PureRotationIsPanoramic).
      TwoViewGeometryOptions options = NoisyOptions();
      options.ransac.max_error = 2.0;
      const TwoViewGeometry geometry = Estimate(scene, options);
      EXPECT_EQ(geometry.config, TwoViewGeometry::kPlanar)
          << "noise " << noise << " calibrated " << calibrated;
      ExpectGoodInliers(scene, geometry);
      EXPECT_GT(geometry.triangulation_angle, 0.0);
      EXPECT_NEAR(geometry.cam2_from_cam1.translation.norm(), 1.0, 1e-9);
    }
  }
}

TEST(EstimateTwoViewGeometry, PureRotationIsPanoramic) {
  SetPRNGSeed(5);
  for (const double noise : {0.0, 0.5}) {
    MatchedPair scene = RandomMatchedPair(1000, noise, noise > 0 ? 0.4 : 0.0,
                                          PairStructure::kGeneral, Eigen::Vector3d::Zero());
    scene.camera1.has_prior_focal_length = true;
    scene.camera2.has_prior_focal_length = true;
    // A panoramic pair keeps H's inliers, whose transfer error carries the noise of both
    // images (sigma sqrt(2) per axis): 1.5 px would drop ~10 % of them, 2 px drops ~2 %.
    TwoViewGeometryOptions options = NoisyOptions();
    options.ransac.max_error = 2.0;
    const TwoViewGeometry geometry = Estimate(scene, options);
    ASSERT_EQ(geometry.config, TwoViewGeometry::kPanoramic) << "noise " << noise;
    ExpectGoodInliers(scene, geometry);
    EXPECT_LT(RotationAngleDegrees(geometry.cam2_from_cam1.rotation, scene.cam2_from_cam1.rotation),
              0.1);
    EXPECT_EQ(geometry.cam2_from_cam1.translation, Eigen::Vector3d::Zero());
    EXPECT_EQ(geometry.triangulation_angle, 0.0);
  }
}

TEST(EstimateTwoViewGeometry, TooFewMatchesIsDegenerate) {
  SetPRNGSeed(6);
  const MatchedPair scene = RandomCalibratedPair(10, 0.0, 0.0);
  TwoViewGeometry geometry = Estimate(scene);
  EXPECT_EQ(geometry.config, TwoViewGeometry::kDegenerate);
  EXPECT_TRUE(geometry.inlier_matches.empty());
  geometry = EstimateTwoViewGeometry(scene.camera1, {}, scene.camera2, {}, {}, {});
  EXPECT_EQ(geometry.config, TwoViewGeometry::kDegenerate);
  EXPECT_TRUE(geometry.inlier_matches.empty());
  // Enough matches, too few of them consistent.
  const MatchedPair outliers = RandomCalibratedPair(40, 0.5, 0.95);
  geometry = Estimate(outliers);
  EXPECT_EQ(geometry.config, TwoViewGeometry::kDegenerate);
  EXPECT_TRUE(geometry.inlier_matches.empty());
}

// n matches between random keypoints: uniform over the image, or clustered in a 250 x 200
// box as on an object before a black background (templeRing), where chance fits are likelier.
MatchedPair RandomMatches(int num_matches, bool clustered, bool calibrated) {
  MatchedPair scene;
  scene.camera1.has_prior_focal_length = calibrated;
  scene.camera2.has_prior_focal_length = calibrated;
  const auto random_point = [&] {
    return clustered ? Eigen::Vector2d(RandomUniformReal(400, 650), RandomUniformReal(300, 500))
                     : RandomImagePoint();
  };
  for (int i = 0; i < num_matches; ++i) {
    scene.points1.push_back(random_point());
    scene.points2.push_back(random_point());
    scene.matches.push_back({static_cast<point2D_t>(i), static_cast<point2D_t>(i)});
    scene.is_inlier.push_back(0);
  }
  return scene;
}

TEST(EstimateTwoViewGeometry, RandomMatchesAreRejected) {
  SetPRNGSeed(12);
  // Without the significance test most of these pass from ~100 matches on: RANSAC always
  // finds a model that explains min_num_inliers of enough chance matches.
  TwoViewGeometryOptions without_significance;
  without_significance.max_num_false_alarms = std::numeric_limits<double>::infinity();
  int num_accepted_without = 0, num_tried_without = 0;
  for (const auto& [num_matches, num_pairs] :
       {std::pair{20, 6}, {30, 6}, {50, 6}, {100, 2}, {200, 1}, {500, 1}}) {
    for (int pair = 0; pair < num_pairs; ++pair) {
      for (const bool clustered : {false, true}) {
        for (const bool calibrated : {false, true}) {
          const MatchedPair scene = RandomMatches(num_matches, clustered, calibrated);
          const TwoViewGeometry geometry = Estimate(scene);
          EXPECT_EQ(geometry.config, TwoViewGeometry::kDegenerate)
              << num_matches << " matches, clustered " << clustered << ", calibrated " << calibrated
              << ": " << geometry.inlier_matches.size() << " inliers";
          EXPECT_TRUE(geometry.inlier_matches.empty());
          if (num_matches >= 100 && num_matches <= 200) {
            ++num_tried_without;
            num_accepted_without +=
                Estimate(scene, without_significance).config != TwoViewGeometry::kDegenerate;
          }
        }
      }
    }
  }
  std::cerr << num_accepted_without << " of " << num_tried_without
            << " random pairs of 100-200 matches pass without the significance test\n";
  EXPECT_GE(num_accepted_without, num_tried_without / 3);
}

// A prior focal length is one the user asserts: a pair E cannot explain is not verified by F
// unless uncalibrated_fallback asks for COLMAP's rule, which makes it uncalibrated.
TEST(EstimateTwoViewGeometry, CalibratedPairsThatEDoesNotExplainFallBackToFOnlyWhenAsked) {
  SetPRNGSeed(21);
  for (int trial = 0; trial < 5; ++trial) {
    MatchedPair scene = RandomCalibratedPair(300, 0.5, 0.2);
    // Image 2 sheared: still one epipolar geometry (F), but not that of its prior, a pinhole
    // without skew, so no E explains it.
    for (Eigen::Vector2d& point : scene.points2) point.x() += 0.5 * point.y();
    // E still fits a subset of the 240 true matches (once it has min_num_inliers, F is
    // searched to classify the pair, fallback or not): ask for more than such a subset holds.
    TwoViewGeometryOptions options = NoisyOptions();
    options.min_num_inliers = 200;
    EXPECT_EQ(Estimate(scene, options).config, TwoViewGeometry::kDegenerate) << trial;
    options.uncalibrated_fallback = true;
    const TwoViewGeometry geometry = Estimate(scene, options);
    ASSERT_EQ(geometry.config, TwoViewGeometry::kUncalibrated) << trial;
    // The shear stretches image 2, so an outlier lands near its epipolar line a little more
    // often than ExpectGoodInliers allows.
    const InlierCounts counts = CountInliers(scene, geometry);
    EXPECT_GE(counts.inliers_kept, 0.95 * counts.num_true_inliers) << trial;
    EXPECT_LE(counts.outliers_kept, 4u) << trial;
  }
  // Where E explains the pair, the option changes nothing.
  const MatchedPair scene = RandomCalibratedPair(300, 0.5, 0.2);
  for (const bool fallback : {false, true}) {
    TwoViewGeometryOptions options = NoisyOptions();
    options.uncalibrated_fallback = fallback;
    EXPECT_EQ(Estimate(scene, options).config, TwoViewGeometry::kCalibrated) << fallback;
  }
}

TEST(EstimateTwoViewGeometry, RealPairsWithFortyPercentOutliersAreKept) {
  SetPRNGSeed(13);
  // From few matches (the weakest pairs a reconstruction links) to many.
  for (const int num_matches : {30, 50, 100, 300}) {
    for (int pair = 0; pair < 4; ++pair) {
      for (const bool calibrated : {false, true}) {
        MatchedPair scene = RandomMatchedPair(num_matches, 0.5, 0.4, PairStructure::kGeneral);
        scene.camera1.has_prior_focal_length = calibrated;
        scene.camera2.has_prior_focal_length = calibrated;
        const TwoViewGeometry geometry = Estimate(scene, NoisyOptions());
        const InlierCounts counts = CountInliers(scene, geometry);
        // Too few to verify whatever the test; with the intrinsics known E must explain 15
        // itself (no F fallback), and at the minimum noise can cost it one or two.
        if (counts.num_true_inliers < (calibrated ? 17u : 15u)) continue;
        // With few matches F may pick up an outlier or two more than E, which makes a
        // calibrated pair uncalibrated (COLMAP's rule): verified either way.
        const bool verified = geometry.config == TwoViewGeometry::kUncalibrated ||
                              (calibrated && geometry.config == TwoViewGeometry::kCalibrated);
        EXPECT_TRUE(verified) << num_matches << " matches (" << counts.num_true_inliers
                              << " inliers), calibrated " << calibrated << ": config "
                              << geometry.config;
        EXPECT_GE(counts.inliers_kept, 0.85 * counts.num_true_inliers);
        // A uniform outlier lands within 1.5 px of its epipolar line about once in 200, and
        // fitted to few matches F's seven degrees of freedom bend to take in a few more.
        EXPECT_LE(counts.outliers_kept, 4 + 0.02 * counts.inliers_kept);
      }
    }
  }
}

TEST(EstimateTwoViewGeometry, NonFiniteKeypointsAreIgnored) {
  SetPRNGSeed(7);
  MatchedPair scene = RandomCalibratedPair(300, 0.5, 0.2);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<size_t> poisoned;
  for (size_t i = 0; i < scene.matches.size(); i += 6) {
    scene.points1[scene.matches[i].point2D_idx1] =
        (i % 4 == 0) ? Eigen::Vector2d(nan, 1) : Eigen::Vector2d(1, inf);
    poisoned.push_back(i);
  }
  const TwoViewGeometry geometry = Estimate(scene);
  EXPECT_EQ(geometry.config, TwoViewGeometry::kCalibrated);
  for (const FeatureMatch& match : geometry.inlier_matches) {
    EXPECT_TRUE(scene.points1[match.point2D_idx1].allFinite());
  }
  // Every keypoint non-finite.
  for (Eigen::Vector2d& point : scene.points1) point = Eigen::Vector2d(nan, -inf);
  const TwoViewGeometry none = Estimate(scene);
  EXPECT_EQ(none.config, TwoViewGeometry::kDegenerate);
  EXPECT_TRUE(none.inlier_matches.empty());
}

TEST(EstimateTwoViewGeometry, DuplicateAndCollinearPointsAreDegenerate) {
  SetPRNGSeed(8);
  // All matches between one pair of points.
  MatchedPair scene = RandomCalibratedPair(100, 0.0, 0.0);
  for (Eigen::Vector2d& point : scene.points1) point = Eigen::Vector2d(100, 200);
  for (Eigen::Vector2d& point : scene.points2) point = Eigen::Vector2d(300, 400);
  for (const bool calibrated : {false, true}) {
    scene.camera1.has_prior_focal_length = calibrated;
    const TwoViewGeometry geometry = Estimate(scene);
    EXPECT_EQ(geometry.config, TwoViewGeometry::kDegenerate);
    EXPECT_TRUE(geometry.inlier_matches.empty());
  }
  // 3D points on one line, exact and noisy.
  for (const double noise : {0.0, 0.5}) {
    for (const bool calibrated : {false, true}) {
      MatchedPair line = RandomMatchedPair(200, noise, 0.0, PairStructure::kLine);
      line.camera1.has_prior_focal_length = calibrated;
      line.camera2.has_prior_focal_length = calibrated;
      const TwoViewGeometry geometry = Estimate(line);
      EXPECT_EQ(geometry.config, TwoViewGeometry::kDegenerate)
          << "noise " << noise << " calibrated " << calibrated;
      EXPECT_TRUE(geometry.inlier_matches.empty());
    }
  }
  // Twelve real matches, each repeated three times: 36 consistent matches but 12 keypoints,
  // below min_num_inliers.
  MatchedPair repeated = RandomCalibratedPair(12, 0.0, 0.0);
  const FeatureMatches originals = repeated.matches;
  for (int copy = 0; copy < 2; ++copy) {
    repeated.matches.insert(repeated.matches.end(), originals.begin(), originals.end());
  }
  for (const bool calibrated : {false, true}) {
    repeated.camera1.has_prior_focal_length = calibrated;
    const TwoViewGeometry geometry = Estimate(repeated);
    EXPECT_EQ(geometry.config, TwoViewGeometry::kDegenerate);
    EXPECT_TRUE(geometry.inlier_matches.empty());
  }
  // Half of a good scene duplicated: still verified.
  MatchedPair duplicated = RandomCalibratedPair(200, 0.5, 0.0);
  const size_t num_matches = duplicated.matches.size();
  for (size_t i = 0; i < num_matches; i += 2) duplicated.matches.push_back(duplicated.matches[i]);
  duplicated.is_inlier.resize(duplicated.matches.size(), 1);
  const TwoViewGeometry geometry = Estimate(duplicated);
  EXPECT_EQ(geometry.config, TwoViewGeometry::kCalibrated);
  EXPECT_GE(geometry.inlier_matches.size(), 0.95 * duplicated.matches.size());
}

TEST(EstimateTwoViewGeometry, WatermarkIsDetected) {
  SetPRNGSeed(9);
  // A logo in the bottom-left corner at the same place in both images, a few scene matches.
  MatchedPair scene = RandomCalibratedPair(20, 0.5, 0.0);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector2d logo(RandomUniformReal(5, 90),
                               RandomUniformReal(kImageHeight - 70, kImageHeight - 5));
    scene.points1.push_back(logo);
    scene.points2.push_back(logo + Eigen::Vector2d(RandomGaussian(0, 0.3), RandomGaussian(0, 0.3)));
    scene.matches.push_back({static_cast<point2D_t>(scene.points1.size() - 1),
                             static_cast<point2D_t>(scene.points2.size() - 1)});
  }
  const TwoViewGeometry geometry = Estimate(scene);
  EXPECT_EQ(geometry.config, TwoViewGeometry::kWatermark);
}

TEST(EstimateTwoViewGeometry, RejectsBadOptionsAndIndices) {
  SetPRNGSeed(10);
  const MatchedPair scene = RandomCalibratedPair(50, 0.0, 0.0);
  TwoViewGeometryOptions options;
  options.ransac.max_error = 0.0;
  EXPECT_THROW(Estimate(scene, options), CheckError);
  options = {};
  options.ransac.confidence = 1.0;
  EXPECT_THROW(Estimate(scene, options), CheckError);
  FeatureMatches matches = scene.matches;
  matches[3].point2D_idx2 = static_cast<point2D_t>(scene.points2.size());
  EXPECT_THROW(EstimateTwoViewGeometry(scene.camera1, scene.points1, scene.camera2, scene.points2,
                                       matches, {}),
               CheckError);
}

TEST(EstimateTwoViewGeometryPose, FromFundamentalAndRefusals) {
  SetPRNGSeed(11);
  const MatchedPair scene = RandomMatchedPair(300, 0.0, 0.0, PairStructure::kGeneral);
  TwoViewGeometryOptions options;
  options.compute_relative_pose = false;
  TwoViewGeometry geometry = Estimate(scene, options);
  ASSERT_EQ(geometry.config, TwoViewGeometry::kUncalibrated);
  EXPECT_EQ(geometry.triangulation_angle, 0.0);
  ASSERT_TRUE(EstimateTwoViewGeometryPose(scene.camera1, scene.points1, scene.camera2,
                                          scene.points2, &geometry));
  EXPECT_LT(RotationAngleDegrees(geometry.cam2_from_cam1.rotation, scene.cam2_from_cam1.rotation),
            1e-6);
  EXPECT_NEAR(geometry.triangulation_angle, scene.TrueTriAngle(), 1e-6);
  geometry.config = TwoViewGeometry::kDegenerate;
  EXPECT_FALSE(EstimateTwoViewGeometryPose(scene.camera1, scene.points1, scene.camera2,
                                           scene.points2, &geometry));
  geometry.config = TwoViewGeometry::kUncalibrated;
  geometry.inlier_matches.clear();
  EXPECT_FALSE(EstimateTwoViewGeometryPose(scene.camera1, scene.points1, scene.camera2,
                                           scene.points2, &geometry));
}

}  // namespace
}  // namespace parallax
