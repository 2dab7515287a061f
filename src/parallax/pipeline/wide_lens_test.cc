// Wide lenses end to end (issue 60): a fisheye wider than a hemisphere, rendered by `synth`
// through its own model with EXIF focal length, reconstructed as a user would with only the
// model's name given.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "parallax/pipeline/reconstruction_pipeline.h"
#include "parallax/render/synthetic_scene.h"
#include "parallax/report/evaluation.h"
#include "parallax/report/ground_truth.h"
#include "parallax/util/test_dir.h"

namespace parallax {
namespace {

// 30 views of 400x400 around the temple with k1..k4 in the lens; the distortion starts at
// zero. (docs/camera-models.md has the 640x640, 40-view figures.)
TEST(WideLens, A190DegreeFisheyeRegistersEveryViewAndRefinesItsDistortion) {
  const test::ScopedTestDir dir("wide_lens");
  SyntheticSceneOptions scene;
  scene.num_views = 30;
  scene.width = 400;
  scene.height = 400;
  scene.camera_model = CameraModelId::kOpenCVFisheye;
  const double focal = 200 / (95 * M_PI / 180);  // 190 degrees across the width
  scene.camera_params = {focal, focal, 200, 200, 0.02, -0.005, 0.001, -0.0002};
  scene.write_exif = true;
  scene.num_threads = 2;
  GenerateSyntheticScene(scene, dir.path() / "scene");
  ASSERT_FALSE(std::filesystem::exists(dir.path() / "scene" / "K.txt"));

  ReconstructionPipelineOptions options;
  options.extraction.camera.camera_model = "OPENCV_FISHEYE";
  SetSeedAndThreads(0, 2, /*keep_ba_threads=*/false, &options);
  const ReconstructionPipelineResult result =
      RunReconstructionPipeline(options, dir.path() / "scene", dir.path() / "out");
  ASSERT_TRUE(result.Success()) << result.mapping.summary.failure;
  ASSERT_EQ(result.mapping.models.size(), 1u);
  const Reconstruction& model = result.mapping.models[0];
  EXPECT_EQ(model.NumRegImages(), 30u);
  const EvaluationMetrics metrics =
      EvaluateReconstruction(model, ReadGroundTruth(dir.path() / "scene" / "gt"));
  EXPECT_LT(metrics.rotation_error_deg.median, 0.5);
  ASSERT_EQ(model.NumCameras(), 1u);
  const Camera& camera = model.Cameras().begin()->second;
  EXPECT_EQ(camera.model_id, CameraModelId::kOpenCVFisheye);
  EXPECT_NEAR(camera.MeanFocalLength(), focal, 0.02 * focal);
  // The refined lens (its distortion started at zero) maps rays up to 80 degrees off the
  // axis where the true one does, within a pixel and a half; k1..k4 trade off against each
  // other, so the coefficients themselves are not compared.
  Camera truth = camera;
  truth.params = scene.camera_params;
  double worst = 0;
  for (double theta = 0; theta <= 80 * M_PI / 180; theta += 5 * M_PI / 180) {
    for (double phi = 0; phi < 2 * M_PI; phi += M_PI / 6) {
      const Eigen::Vector3d ray(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                                std::cos(theta));
      worst = std::max(worst, (camera.ImgFromCam(ray) - truth.ImgFromCam(ray)).norm());
    }
  }
  EXPECT_LT(worst, 1.5);
}

}  // namespace
}  // namespace parallax
