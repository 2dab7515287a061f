#include "parallax/pipeline/reconstruction_pipeline.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "parallax/render/synthetic_scene.h"
#include "parallax/report/evaluation.h"
#include "parallax/report/ground_truth.h"
#include "parallax/util/content_hash.h"
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
  for (const char* file :
       {"sparse/0/cameras.txt", "sparse/0/images.bin", "points.ply", "summary.json"}) {
    EXPECT_TRUE(std::filesystem::exists(dir / "out" / file)) << file;
  }
  // summary.json counts the points by track length, and they add up to the model's.
  const nlohmann::json summary =
      nlohmann::json::parse(ReadFileToString(dir / "out" / "summary.json"));
  size_t num_points = 0, num_observations = 0;
  for (const nlohmann::json& bin : summary["track_length_histogram"]) {
    num_points += bin["points"].get<size_t>();
    num_observations += bin["length"].get<size_t>() * bin["points"].get<size_t>();
  }
  EXPECT_EQ(num_points, model.NumPoints3D());
  EXPECT_EQ(num_observations, model.NumObservations());
  std::filesystem::remove_all(dir);
}

// A folder that gains photos after a run: the rerun registers the new ones into the earlier
// model (whose images keep their poses), leaves out the photos that are gone, and says so in
// summary.json; the result is as accurate as a run on all photos.
TEST(ReconstructionPipeline, PhotosAddedLaterAreRegisteredIntoTheEarlierModel) {
  namespace fs = std::filesystem;
  const fs::path dir = TempDir("pipeline_added_photos");
  SyntheticSceneOptions scene;
  scene.num_views = 20;
  GenerateSyntheticScene(scene, dir / "scene");
  const auto view = [](int index) {
    char name[32];
    std::snprintf(name, sizeof(name), "view_%04d.png", index);
    return std::string(name);
  };
  // First run: the 14 views 1-14; the second adds 15-20 and loses 1 and 2.
  fs::create_directories(dir / "photos");
  for (int index = 1; index <= 14; ++index) {
    fs::copy_file(dir / "scene" / view(index), dir / "photos" / view(index));
  }
  ReconstructionPipelineOptions options;
  options.extraction.camera.intrinsics_path = dir / "scene" / "K.txt";
  options.ground_truth_path = dir / "scene" / (scene.name + "_par.txt");
  const ReconstructionPipelineResult first =
      RunReconstructionPipeline(options, dir / "photos", dir / "out");
  ASSERT_TRUE(first.Success());
  ASSERT_EQ(first.mapping.models.front().NumRegImages(), 14u);
  EXPECT_EQ(first.mapping.num_input_model_images, 0u);
  // How the model started: from a pair, at the thresholds as given (step 0).
  const nlohmann::json& start = first.summary["models"][0]["start"];
  EXPECT_EQ(start["from"], "pair");
  EXPECT_EQ(start["images"].size(), 2u);
  EXPECT_EQ(start["min_inliers"], options.mapping.mapper.init_min_num_inliers);
  EXPECT_EQ(start["relaxation_step"], 0);
  EXPECT_GE(start["median_tri_angle_deg"].get<double>(), start["min_tri_angle_deg"].get<double>());
  EXPECT_EQ(first.summary["models"][0]["links"].size(), 0u);
  EXPECT_EQ(first.summary["mapper"]["discarded_models"], 0);

  for (int index = 15; index <= 20; ++index) {
    fs::copy_file(dir / "scene" / view(index), dir / "photos" / view(index));
  }
  fs::remove(dir / "photos" / view(1));
  fs::remove(dir / "photos" / view(2));
  const ReconstructionPipelineResult second =
      RunReconstructionPipeline(options, dir / "photos", dir / "out");
  ASSERT_TRUE(second.Success());
  EXPECT_EQ(second.extraction.num_extracted, 6u);
  EXPECT_EQ(second.mapping.num_input_model_images, 12u);
  EXPECT_EQ(second.mapping.input_model_images_missing,
            (std::vector<std::string>{view(1), view(2)}));
  const Reconstruction& model = second.mapping.models.front();
  EXPECT_EQ(model.NumRegImages(), 18u);
  for (const image_t image_id : model.RegImageIds()) {
    EXPECT_NE(model.GetImage(image_id).name, view(1));
    EXPECT_NE(model.GetImage(image_id).name, view(2));
  }
  ASSERT_TRUE(second.evaluation.has_value());
  EXPECT_LT(second.evaluation->rotation_error_deg.median, 0.1);
  EXPECT_LT(second.evaluation->center_error_ratio.median, 0.002);
  EXPECT_EQ(second.summary["mapper"]["type"], "incremental");
  EXPECT_FALSE(second.summary["mapper"].contains("type_reason"));  // The default, not chosen.
  EXPECT_EQ(second.summary["mapper"]["input_model"]["images_kept"], 12);
  EXPECT_EQ(second.summary["mapper"]["input_model"]["images_missing"].size(), 2u);
  EXPECT_EQ(second.summary["models"][0]["start"]["from"], "input model");
  // Where the mapping time went, by phase; the adjustments' share is the solver's time.
  const nlohmann::json& phases = second.summary["mapper"]["phase_s"];
  EXPECT_GT(phases["registration"].get<double>(), 0.0);
  EXPECT_GT(phases["triangulation"].get<double>(), 0.0);
  EXPECT_NEAR(phases["local_ba"].get<double>() + phases["global_ba"].get<double>(),
              second.summary["mapper"]["bundle_adjustment_s"].get<double>(), 1e-9);
  // The stage's time outside the mapper: loading the database, colouring and writing.
  EXPECT_GT(second.summary["mapper"]["load_s"].get<double>(), 0.0);
  EXPECT_GT(second.summary["mapper"]["write_s"].get<double>(), 0.0);

  // --remap: from scratch, the same photos.
  fs::copy_file(dir / "scene" / view(1), dir / "photos" / view(1));
  options.extend_model_with_new_photos = false;
  const ReconstructionPipelineResult remapped =
      RunReconstructionPipeline(options, dir / "photos", dir / "out");
  ASSERT_TRUE(remapped.Success());
  EXPECT_EQ(remapped.mapping.num_input_model_images, 0u);
  EXPECT_EQ(remapped.mapping.models.front().NumRegImages(), 19u);
  fs::remove_all(dir);
}

// templeRing reconstructed end to end into a fresh folder, evaluated against its ground truth.
class TempleRingTest : public ::testing::Test {
 protected:
  void SetUp() override {
    data_ = DataRoot() / "templeRing";
    if (!std::filesystem::exists(data_ / "templeR_par.txt")) GTEST_SKIP() << "no " << data_;
    truth_ = ReadGroundTruth(data_ / "templeR_par.txt");
    dir_ = TempDir("pipeline_" +
                   std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
  }
  void TearDown() override {
    if (!dir_.empty()) std::filesystem::remove_all(dir_);
  }

  // Runs the pipeline; `model_` and `metrics_` describe its largest model.
  void Reconstruct(const ReconstructionPipelineOptions& options) {
    const ReconstructionPipelineResult result =
        RunReconstructionPipeline(options, data_ / "images", dir_ / "out");
    ASSERT_TRUE(result.Success());
    model_ = result.mapping.models.front();
    metrics_ = EvaluateReconstruction(model_, truth_);
    std::cout << MetricsToText(metrics_) << std::endl;
  }

  std::filesystem::path data_, dir_;
  GroundTruth truth_;
  Reconstruction model_;
  EvaluationMetrics metrics_;
};

// The digests of the templeRing model the default build writes, as `xxh128sum` prints them
// ("DIGEST  FILE" lines). The default build computes the same bits on every x86-64-v3 machine
// (issue 23, docs/portable-build.md), and each rank of an MPI run must; any change that moves
// a bit of this model updates the file, and says why in its commit.
const char kTempleRingModelDigests[] =
    PARALLAX_SOURCE_DIR "/src/parallax/pipeline/testdata/templering_known_k_model.xxh128";

// With the ground-truth K: registration and accuracy against the ground truth, and the model's
// bytes against the checked-in digests.
TEST_F(TempleRingTest, KnownIntrinsics) {
  std::ofstream(dir_ / "K.txt") << truth_.images.front().camera.CalibrationMatrix() << "\n";
  ReconstructionPipelineOptions options;
  options.extraction.camera.intrinsics_path = dir_ / "K.txt";
  // The bytes depend on the number of BA threads (each sums its own partial system), not on
  // the machine: fix every thread count.
  options.extraction.num_threads = 2;
  options.matching.num_threads = 2;
  for (BundleAdjustmentOptions* ba : options.mapping.mapper.BundleAdjustments())
    ba->num_threads = 2;
  ASSERT_NO_FATAL_FAILURE(Reconstruct(options));
  EXPECT_EQ(model_.NumRegImages(), 47u);
  EXPECT_LE(metrics_.center_error.median, 0.0013);  // Metres.
  EXPECT_LE(metrics_.rotation_error_deg.median, 0.2);
  EXPECT_LE(metrics_.mean_reprojection_error_px, 0.5);
  // COLMAP 3.8 on the same images: 7,662 points, 47,895 observations, 6.25 images per point.
  EXPECT_GE(model_.NumPoints3D(), 7000u);
  EXPECT_GE(model_.NumObservations(), 40000u);
  EXPECT_GE(model_.ComputeMeanTrackLength(), 5.5);

  std::string digests;
  for (const char* file : {"cameras.bin", "images.bin", "points3D.bin"}) {
    digests += HashFile(dir_ / "out" / "sparse" / "0" / file) + "  " + file + "\n";
  }
  std::cout << "model digests:\n" << digests;
#if PARALLAX_REFERENCE_BUILD
  EXPECT_EQ(digests, ReadFileToString(kTempleRingModelDigests))
      << "the templeRing model's bytes changed; if on purpose, update " << kTempleRingModelDigests;
#else
  std::cout << "not compared with " << kTempleRingModelDigests
            << ": this is not the default build (x86-64-v3, GCC 12.2)\n";
#endif
}

// With no intrinsics at all (issue 5): the focal length starts from the prior of
// 1.2 x 640 px = 768 px and bundle adjustment must find the true 1520 px.
TEST_F(TempleRingTest, NoIntrinsics) {
  ASSERT_NO_FATAL_FAILURE(Reconstruct(ReconstructionPipelineOptions()));
  EXPECT_GE(model_.NumRegImages(), 45u);
  EXPECT_LE(metrics_.center_error.median, 2 * 0.0013);  // Twice the calibrated run's bar.
  ASSERT_EQ(model_.Cameras().size(), 1u);
  const double focal = model_.Cameras().begin()->second.params[0];
  std::cout << "recovered focal length " << focal << " px (ground truth 1520.4)\n";
  EXPECT_NEAR(focal, 1520.4, 0.02 * 1520.4);
}

}  // namespace
}  // namespace parallax
