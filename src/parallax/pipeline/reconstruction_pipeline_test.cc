#include "parallax/pipeline/reconstruction_pipeline.h"

#include <gtest/gtest.h>

#include <fstream>

#include "parallax/render/synthetic_scene.h"
#include "parallax/report/evaluation.h"
#include "parallax/report/ground_truth.h"
#include "parallax/util/file.h"

namespace parallax {
namespace {

std::filesystem::path TempDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("parallax_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// The embedded default end to end: rendered views -> SIFT -> matching -> mapping.
TEST(ReconstructionPipeline, SyntheticTempleThirtyViews) {
  const auto dir = TempDir("pipeline_synth");
  SyntheticSceneOptions scene;
  scene.num_views = 30;
  GenerateSyntheticScene(scene, dir / "scene");
  ReconstructionPipelineOptions options;
  options.extraction.camera.intrinsics_path = dir / "scene" / "K.txt";
  const ReconstructionPipelineResult result =
      RunReconstructionPipeline(options, dir / "scene", dir / "out");
  ASSERT_TRUE(result.Success());
  const Reconstruction& model = result.mapping.models.front();
  EXPECT_EQ(model.NumRegImages(), 30u);
  const EvaluationMetrics metrics =
      EvaluateReconstruction(model, ReadGroundTruth(dir / "scene" / (scene.name + "_par.txt")));
  EXPECT_LT(metrics.rotation_error_deg.median, 0.1);
  for (const char* file : {"sparse/0/cameras.txt", "sparse/0/images.bin", "points.ply", "summary.json"}) {
    EXPECT_TRUE(std::filesystem::exists(dir / "out" / file)) << file;
  }
  std::filesystem::remove_all(dir);
}

// templeRing with the ground-truth K: registration and accuracy against the ground truth.
TEST(ReconstructionPipeline, TempleRingWithKnownIntrinsics) {
  const auto data = DataRoot() / "templeRing";
  if (!std::filesystem::exists(data / "templeR_par.txt")) GTEST_SKIP() << "no " << data;
  const auto dir = TempDir("pipeline_temple");
  const GroundTruth truth = ReadGroundTruth(data / "templeR_par.txt");
  const Eigen::Matrix3d K = truth.images.front().camera.CalibrationMatrix();
  std::ofstream(dir / "K.txt") << K << "\n";
  ReconstructionPipelineOptions options;
  options.extraction.camera.intrinsics_path = dir / "K.txt";
  const ReconstructionPipelineResult result =
      RunReconstructionPipeline(options, data / "images", dir / "out");
  ASSERT_TRUE(result.Success());
  const Reconstruction& model = result.mapping.models.front();
  const EvaluationMetrics metrics = EvaluateReconstruction(model, truth);
  std::cout << MetricsToText(metrics) << std::endl;
  EXPECT_EQ(model.NumRegImages(), 47u);
  EXPECT_LE(metrics.center_error.median, 0.0013);  // Metres.
  EXPECT_LE(metrics.rotation_error_deg.median, 0.2);
  EXPECT_LE(metrics.mean_reprojection_error_px, 0.5);
  EXPECT_GE(model.NumPoints3D(), 7500u);  // COLMAP 3.8: 7,649 on the same images.
  std::filesystem::remove_all(dir);
}

// templeRing with no intrinsics at all (issue 5): the focal length starts from the prior of
// 1.2 x 640 px = 768 px and bundle adjustment must find the true 1520 px.
TEST(ReconstructionPipeline, TempleRingWithoutIntrinsics) {
  const auto data = DataRoot() / "templeRing";
  if (!std::filesystem::exists(data / "templeR_par.txt")) GTEST_SKIP() << "no " << data;
  const auto dir = TempDir("pipeline_temple_uncalibrated");
  const GroundTruth truth = ReadGroundTruth(data / "templeR_par.txt");
  const ReconstructionPipelineResult result =
      RunReconstructionPipeline(ReconstructionPipelineOptions(), data / "images", dir / "out");
  ASSERT_TRUE(result.Success());
  const Reconstruction& model = result.mapping.models.front();
  const EvaluationMetrics metrics = EvaluateReconstruction(model, truth);
  std::cout << MetricsToText(metrics) << std::endl;
  EXPECT_GE(model.NumRegImages(), 45u);
  EXPECT_LE(metrics.center_error.median, 2 * 0.0013);  // Twice the calibrated run's bar.
  ASSERT_EQ(model.Cameras().size(), 1u);
  const Camera& camera = model.Cameras().begin()->second;
  const double focal = camera.params[0];
  std::cout << "recovered focal length " << focal << " px (ground truth 1520.4)\n";
  EXPECT_NEAR(focal, 1520.4, 0.02 * 1520.4);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace parallax
