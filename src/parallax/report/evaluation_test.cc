#include "parallax/report/evaluation.h"

#include <gtest/gtest.h>

#include "parallax/util/eigen_matchers.h"

#include <cmath>

#include "parallax/math/random.h"
#include "parallax/scene/synthetic_dataset.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

using test::Sim3dNear;

Reconstruction SyntheticTruth(int num_images) {
  SyntheticDatasetOptions options;
  options.num_images = num_images;
  options.num_points3D = 150;
  Reconstruction truth;
  SynthesizeDataset(options, &truth);
  return truth;
}

GroundTruth GroundTruthOf(const Reconstruction& truth) {
  GroundTruth gt;
  gt.source = "synthetic";
  for (const auto& [image_id, image] : truth.Images()) {
    gt.images.push_back({image.name, truth.GetCamera(image.camera_id), image.cam_from_world});
  }
  return gt;
}

Sim3d RandomSim3d() {
  const Eigen::Vector3d axis =
      Eigen::Vector3d(RandomGaussian(0, 1), RandomGaussian(0, 1), RandomGaussian(0, 1))
          .normalized();
  const Eigen::Quaterniond rotation(Eigen::AngleAxisd(RandomUniformReal(0.2, 3.0), axis));
  const Eigen::Vector3d translation(RandomUniformReal(-10, 10), RandomUniformReal(-10, 10),
                                    RandomUniformReal(-10, 10));
  return Sim3d(std::exp(RandomUniformReal(-2, 2)), rotation, translation);
}

TEST(EvaluateReconstruction, RecoversKnownSimilarityExactly) {
  const Reconstruction truth = SyntheticTruth(12);
  const GroundTruth gt = GroundTruthOf(truth);
  for (int trial = 0; trial < 5; ++trial) {
    const Sim3d model_from_gt = RandomSim3d();
    Reconstruction model = truth;
    model.Transform(model_from_gt);
    const EvaluationMetrics metrics = EvaluateReconstruction(model, gt);
    ASSERT_TRUE(metrics.alignment_success);
    EXPECT_THAT(metrics.gt_from_model, Sim3dNear(model_from_gt.Inverse(), 1e-9));
    EXPECT_EQ(metrics.num_gt_images, 12u);
    EXPECT_EQ(metrics.num_registered_in_gt, 12u);
    EXPECT_EQ(metrics.num_alignment_inliers, 12u);
    EXPECT_LT(metrics.center_error.max, 1e-9);
    EXPECT_LT(metrics.center_error_ratio.max, 1e-9);
    EXPECT_LT(metrics.rotation_error_deg.max, 1e-6);
    EXPECT_EQ(metrics.rotation_error_deg.count, 12u);
    for (const AccuracyAtThreshold& point : metrics.rotation_accuracy) {
      EXPECT_DOUBLE_EQ(point.fraction, 1.0);
      EXPECT_NEAR(point.auc, 1.0, 1e-6);
    }
    for (const AccuracyAtThreshold& point : metrics.center_accuracy) {
      EXPECT_DOUBLE_EQ(point.fraction, 1.0);
      EXPECT_NEAR(point.auc, 1.0, 1e-6);
    }
    // Reprojection errors are invariant to the similarity (noiseless keypoints).
    EXPECT_LT(metrics.mean_reprojection_error_px, 1e-9);
    EXPECT_EQ(metrics.num_points3D, truth.NumPoints3D());
    EXPECT_DOUBLE_EQ(metrics.mean_track_length, truth.ComputeMeanTrackLength());
    size_t num_histogram_points = 0;
    for (const auto& [length, count] : metrics.track_length_histogram) {
      EXPECT_GE(length, 2u);
      num_histogram_points += count;
    }
    EXPECT_EQ(num_histogram_points, truth.NumPoints3D());
    // The scene scale is the mean distance of the GT centres from their centroid: the ring
    // radius of the synthetic layout.
    EXPECT_NEAR(metrics.gt_scene_scale, 4.0, 1e-9);
  }
}

TEST(EvaluateReconstruction, OneWildCameraDoesNotSkewTheOthers) {
  const Reconstruction truth = SyntheticTruth(12);
  const GroundTruth gt = GroundTruthOf(truth);
  const Sim3d model_from_gt = RandomSim3d();
  Reconstruction model = truth;
  model.Transform(model_from_gt);
  const image_t wild_id = model.RegImageIds()[4];
  Image& wild = model.GetImage(wild_id);
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(1.0, Eigen::Vector3d(1, 2, 3).normalized()));
  wild.cam_from_world.rotation = (turn * wild.cam_from_world.rotation).normalized();
  wild.cam_from_world.translation += Eigen::Vector3d(7, -5, 11) * model_from_gt.scale;

  const EvaluationMetrics metrics = EvaluateReconstruction(model, gt);
  ASSERT_TRUE(metrics.alignment_success);
  EXPECT_THAT(metrics.gt_from_model, Sim3dNear(model_from_gt.Inverse(), 1e-9));
  EXPECT_EQ(metrics.num_alignment_inliers, 11u);
  for (const ImageEvaluation& image : metrics.images) {
    if (image.image_id == wild_id) {
      EXPECT_FALSE(image.alignment_inlier);
      EXPECT_GT(image.center_error, 1.0);
      EXPECT_NEAR(image.rotation_error_deg, 180.0 / M_PI, 1e-6);
    } else {
      EXPECT_TRUE(image.alignment_inlier) << image.name;
      EXPECT_LT(image.center_error, 1e-9) << image.name;
      EXPECT_LT(image.rotation_error_deg, 1e-6) << image.name;
    }
  }
  EXPECT_LT(metrics.center_error.median, 1e-9);
  EXPECT_GT(metrics.center_error.max, 1.0);
  EXPECT_NEAR(metrics.rotation_error_deg.max, 180.0 / M_PI, 1e-6);
  for (const AccuracyAtThreshold& point : metrics.rotation_accuracy) {
    EXPECT_DOUBLE_EQ(point.fraction, 11.0 / 12.0);
  }
  // The wild camera moved ~14 units, more than 5 % of the 4-unit ring radius.
  for (const AccuracyAtThreshold& point : metrics.center_accuracy) {
    EXPECT_DOUBLE_EQ(point.fraction, 11.0 / 12.0);
  }
}

TEST(EvaluateReconstruction, MatchesNamesAndCountsUnregisteredImages) {
  const Reconstruction truth = SyntheticTruth(8);
  GroundTruth gt = GroundTruthOf(truth);
  // Names that differ by folder or extension still match; an extra GT view has no image.
  gt.images[0].name = "some/folder/" + gt.images[0].name;
  gt.images[1].name = gt.images[1].name.substr(0, gt.images[1].name.rfind('.'));
  gt.images.push_back({"never_seen.png", gt.images[2].camera, gt.images[2].cam_from_world});
  Reconstruction model = truth;
  const std::vector<image_t> registered = model.RegImageIds();
  model.DeRegisterImage(registered[5]);

  const EvaluationMetrics metrics = EvaluateReconstruction(model, gt);
  EXPECT_EQ(metrics.num_gt_images, 9u);
  EXPECT_EQ(metrics.num_model_images, 8u);
  EXPECT_EQ(metrics.num_model_registered, 7u);
  EXPECT_EQ(metrics.num_registered_in_gt, 7u);
  EXPECT_TRUE(metrics.images[0].registered);
  EXPECT_TRUE(metrics.images[1].registered);
  EXPECT_FALSE(metrics.images[5].registered);
  EXPECT_EQ(metrics.images[8].image_id, kInvalidImageId);
  ASSERT_TRUE(metrics.alignment_success);
  EXPECT_LT(metrics.center_error.max, 1e-9);
  // Two of nine GT views are missing from the model: they fail every threshold.
  for (const AccuracyAtThreshold& point : metrics.rotation_accuracy) {
    EXPECT_DOUBLE_EQ(point.fraction, 7.0 / 9.0);
    EXPECT_NEAR(point.auc, 7.0 / 9.0, 1e-6);
  }

  const nlohmann::json json = MetricsToJson(metrics);
  EXPECT_EQ(json["images_gt"], 9);
  EXPECT_EQ(json["images_registered_in_gt"], 7);
  EXPECT_EQ(json["rotation_accuracy"].size(), 3u);
  EXPECT_EQ(json["images"][5]["registered"], false);
  EXPECT_FALSE(json["images"][5].contains("rotation_error_deg"));
  EXPECT_TRUE(json["images"][0].contains("rotation_error_deg"));
  const std::string text = MetricsToText(metrics);
  EXPECT_NE(text.find("registered / in ground truth"), std::string::npos);
  EXPECT_NE(text.find("7 / 9"), std::string::npos);
}

TEST(EvaluateReconstruction, TooFewCamerasGiveNoAlignment) {
  const Reconstruction truth = SyntheticTruth(6);
  const GroundTruth gt = GroundTruthOf(truth);
  Reconstruction model = truth;
  const std::vector<image_t> registered = model.RegImageIds();
  for (size_t i = 2; i < registered.size(); ++i) model.DeRegisterImage(registered[i]);
  const EvaluationMetrics metrics = EvaluateReconstruction(model, gt);
  EXPECT_FALSE(metrics.alignment_success);
  EXPECT_EQ(metrics.num_registered_in_gt, 2u);
  EXPECT_EQ(metrics.center_error.count, 0u);
  for (const AccuracyAtThreshold& point : metrics.rotation_accuracy) EXPECT_EQ(point.fraction, 0.0);
}

// `parallax model align`: the model moved by a similarity comes back onto the reference, points
// included; a reference it shares too little with is a one-line error naming it.
TEST(AlignToReference, MovesTheModelOntoTheReference) {
  const Reconstruction truth = SyntheticTruth(10);
  Reconstruction model = truth;
  model.Transform(RandomSim3d());
  const Reconstruction aligned = AlignToReference(model, GroundTruthOf(truth));
  for (const auto& [image_id, image] : truth.Images()) {
    EXPECT_LT((aligned.GetImage(image_id).ProjectionCenter() - image.ProjectionCenter()).norm(),
              1e-8);
  }
  for (const auto& [point3D_id, point] : truth.Points3D()) {
    EXPECT_LT((aligned.GetPoint3D(point3D_id).xyz - point.xyz).norm(), 1e-8);
  }
  Reconstruction two_images = model;
  const std::vector<image_t> registered = two_images.RegImageIds();
  for (size_t i = 2; i < registered.size(); ++i) two_images.DeRegisterImage(registered[i]);
  try {
    AlignToReference(two_images, GroundTruthOf(truth));
    FAIL() << "aligned with two images";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("synthetic: no similarity aligns the model"),
              std::string::npos);
  }
}

TEST(ModelStatisticsToJson, CountsWhatTheModelHolds) {
  const Reconstruction truth = SyntheticTruth(6);
  const nlohmann::json statistics = ModelStatisticsToJson(truth);
  EXPECT_EQ(statistics["images_registered"], 6);
  EXPECT_EQ(statistics["points3D"], truth.NumPoints3D());
  EXPECT_EQ(statistics["observations"], truth.NumObservations());
  size_t points = 0;
  for (const nlohmann::json& bin : statistics["track_length_histogram"])
    points += bin["points"].get<size_t>();
  EXPECT_EQ(points, truth.NumPoints3D());
  EXPECT_NEAR(statistics["mean_track_length"].get<double>(), truth.ComputeMeanTrackLength(), 1e-12);
}

TEST(EvaluationOptions, CheckRejectsBadThresholds) {
  EvaluationOptions options;
  EXPECT_NO_THROW(options.Check());
  options.rotation_thresholds_deg = {1.0, 0.0};
  EXPECT_THROW(options.Check(), CheckError);
}

}  // namespace
}  // namespace parallax
