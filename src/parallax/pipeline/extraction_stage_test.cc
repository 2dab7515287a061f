#include "parallax/pipeline/extraction_stage.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "parallax/math/random.h"
#include "parallax/util/check.h"
#include "parallax/util/test_dir.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;

// Blobs of random size and grey level, lightly blurred: plenty of SIFT features.
cv::Mat TexturedImage(int width, int height) {
  cv::Mat image(height, width, CV_8UC3, cv::Scalar(128, 128, 128));
  for (int k = 0; k < 150; ++k) {
    const cv::Point center(static_cast<int>(RandomUniformInteger(0, width - 1)),
                           static_cast<int>(RandomUniformInteger(0, height - 1)));
    const int radius = static_cast<int>(RandomUniformInteger(2, 12));
    const int level = static_cast<int>(RandomUniformInteger(0, 255));
    cv::circle(image, center, radius, cv::Scalar(level, level, 255 - level), cv::FILLED);
  }
  cv::GaussianBlur(image, image, cv::Size(3, 3), 0.8);
  return image;
}

class FeatureExtractionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    images_ = dir_ / "images";
    fs::create_directories(images_);
  }
  void WriteImage(const std::string& name, int width, int height) {
    ASSERT_TRUE(cv::imwrite((images_ / name).string(), TexturedImage(width, height)));
  }
  const test::ScopedTestDir scoped_dir_{"parallax_feature_extraction_test"};
  const fs::path dir_ = scoped_dir_.path();
  fs::path images_;
};

TEST_F(FeatureExtractionTest, ExtractsSkipsBadFilesAndResumes) {
  WriteImage("c.png", 320, 240);
  WriteImage("a.png", 320, 240);
  WriteImage("b.jpg", 200, 160);
  // A PNG signature followed by garbage: listed as an image, fails to decode.
  std::ofstream(images_ / "broken.png", std::ios::binary)
      << std::string("\x89PNG\r\n\x1a\n", 8) << "not really a png";
  std::ofstream(images_ / "notes.txt") << "not an image\n";

  ExtractionStageOptions options;
  options.num_threads = 2;
  Database database(dir_ / "database.db");
  const ExtractionStageResult stats = RunExtractionStage(options, images_, &database);
  EXPECT_EQ(stats.num_images_found, 4u);
  EXPECT_EQ(stats.num_extracted, 3u);
  EXPECT_EQ(stats.num_skipped, 0u);
  ASSERT_EQ(stats.failed.size(), 1u);
  EXPECT_EQ(stats.failed[0].first, "broken.png");
  EXPECT_NE(stats.failed[0].second.find("broken.png"), std::string::npos);
  EXPECT_GT(stats.mean_num_keypoints, 50);

  // Ids follow the names; one camera per image size.
  EXPECT_EQ(database.ImageIdByName("a.png"), std::optional<image_t>(1));
  EXPECT_EQ(database.ImageIdByName("b.jpg"), std::optional<image_t>(2));
  EXPECT_EQ(database.ImageIdByName("c.png"), std::optional<image_t>(3));
  EXPECT_EQ(database.NumCameras(), 2u);
  EXPECT_EQ(database.ReadImage(1).camera_id, database.ReadImage(3).camera_id);
  const Camera small = database.ReadCamera(database.ReadImage(2).camera_id);
  EXPECT_EQ(small.width, 200u);
  EXPECT_EQ(small.height, 160u);
  EXPECT_EQ(small.model_id, CameraModelId::kSimpleRadial);
  EXPECT_DOUBLE_EQ(small.params[0], 1.2 * 200);
  EXPECT_FALSE(small.has_prior_focal_length);

  // The stored features are what the extractor gives for the image.
  const Bitmap bitmap = ReadBitmap(images_ / "a.png");
  FeatureKeypoints keypoints;
  FeatureDescriptors descriptors;
  CreateSiftExtractor(options.sift)->Extract(bitmap.gray, &keypoints, &descriptors);
  const FeatureKeypoints stored = database.ReadKeypoints(1);
  ASSERT_EQ(stored.size(), keypoints.size());
  for (size_t k = 0; k < stored.size(); ++k) {
    EXPECT_EQ(stored[k].x, keypoints[k].x);
    EXPECT_EQ(stored[k].a12, keypoints[k].a12);
    EXPECT_GE(stored[k].x, 0.0f);
    EXPECT_LE(stored[k].x, 320.0f);
  }
  EXPECT_EQ(database.ReadDescriptors(1), descriptors);
  // With the colour of the image under each keypoint (red, green, blue), for the model's
  // points: the circles are (level, level, 255 - level) in BGR.
  const std::optional<KeypointColors> colors = database.ReadKeypointColors(1);
  ASSERT_TRUE(colors.has_value());
  ASSERT_EQ(colors->size(), 3 * keypoints.size());
  for (size_t k = 0; k < stored.size(); ++k) {
    const cv::Vec3b bgr = bitmap.color.at<cv::Vec3b>(static_cast<int>(keypoints[k].y),
                                                     static_cast<int>(keypoints[k].x));
    EXPECT_EQ((*colors)[3 * k], bgr[2]) << k;
    EXPECT_EQ((*colors)[3 * k + 1], bgr[1]) << k;
    EXPECT_EQ((*colors)[3 * k + 2], bgr[0]) << k;
  }

  // A second run (a resumed one) only retries what failed; new images are added with the
  // existing camera of their size.
  WriteImage("d.png", 320, 240);
  const ExtractionStageResult resumed = RunExtractionStage(options, images_, &database);
  EXPECT_EQ(resumed.num_images_found, 5u);
  EXPECT_EQ(resumed.num_skipped, 3u);
  EXPECT_EQ(resumed.num_extracted, 1u);
  EXPECT_EQ(resumed.failed.size(), 1u);
  EXPECT_EQ(database.NumImages(), 4u);
  EXPECT_EQ(database.NumCameras(), 2u);
  EXPECT_EQ(database.ReadImage(*database.ImageIdByName("d.png")).camera_id,
            database.ReadImage(1).camera_id);
}

TEST_F(FeatureExtractionTest, IntrinsicsAndSingleCamera) {
  WriteImage("a.png", 320, 240);
  WriteImage("b.png", 320, 240);
  WriteImage("c.png", 300, 240);
  std::ofstream(dir_ / "K.txt", std::ios::binary) << "400 0 161.5 \r\n0 401 119.5 \r\n0 0 1 \r\n";
  ExtractionStageOptions options;
  options.camera.intrinsics_path = dir_ / "K.txt";
  options.camera.single_camera = true;
  options.sift.max_num_features = 100;
  Database database(dir_ / "database.db");
  const ExtractionStageResult stats = RunExtractionStage(options, images_, &database);
  EXPECT_EQ(stats.num_extracted, 2u);
  ASSERT_EQ(stats.failed.size(), 1u);
  EXPECT_EQ(stats.failed[0].first, "c.png");  // Not the single camera's size.
  EXPECT_EQ(database.NumCameras(), 1u);
  const Camera camera = database.ReadAllCameras().at(0);
  EXPECT_EQ(camera.model_id, CameraModelId::kPinhole);
  EXPECT_EQ(camera.params, (std::vector<double>{400, 401, 161.5, 119.5}));
  EXPECT_TRUE(camera.has_prior_focal_length);
  EXPECT_LE(database.NumKeypoints(1), 100u);
}

TEST_F(FeatureExtractionTest, WarnsAboutFilesNamedLikeImagesAndBlankImages) {
  WriteImage("a.png", 160, 120);
  std::ofstream(images_ / "empty.jpg", std::ios::binary);
  std::ofstream(images_ / "text.png") << "not an image\n";
  std::ofstream(images_ / "notes.txt") << "not named like one\n";
  ASSERT_TRUE(cv::imwrite((images_ / "blank.png").string(),
                          cv::Mat(120, 160, CV_8UC3, cv::Scalar::all(90))));
  ExtractionStageOptions options;
  Database database(dir_ / "database.db");
  const ExtractionStageResult stats = RunExtractionStage(options, images_, &database);
  EXPECT_EQ(stats.num_images_found, 2u);
  EXPECT_EQ(stats.num_extracted, 2u);  // The blank image is stored, with no keypoints.
  ASSERT_EQ(stats.failed.size(), 2u);
  EXPECT_EQ(stats.failed[0].first, "empty.jpg");
  EXPECT_EQ(stats.failed[0].second, (images_ / "empty.jpg").string() + ": empty file");
  EXPECT_EQ(stats.failed[1].first, "text.png");
  EXPECT_EQ(database.NumKeypoints(*database.ImageIdByName("blank.png")), 0u);
}

TEST_F(FeatureExtractionTest, CameraSettingsNoImageCanSatisfyFailBeforeAnyWork) {
  WriteImage("a.png", 64, 48);
  ExtractionStageOptions options;
  options.camera.camera_model = "PINHOLE";
  options.camera.camera_params = {100, 100, 32};
  EXPECT_THROW(LoadCameraSetup(options.camera), InputError);
  Database database(dir_ / "database.db");
  EXPECT_THROW(RunExtractionStage(options, images_, &database), InputError);
  EXPECT_EQ(database.NumImages(), 0u);
  options.camera.camera_params = {100, 100, 32, 24};
  EXPECT_NO_THROW(LoadCameraSetup(options.camera));
  options.camera.camera_model = "NO_SUCH_MODEL";
  EXPECT_THROW(LoadCameraSetup(options.camera), InputError);
  options.camera = CameraSetupOptions();
  std::ofstream(dir_ / "K.txt") << "1 2 3\n";
  options.camera.intrinsics_path = dir_ / "K.txt";
  EXPECT_THROW(LoadCameraSetup(options.camera), InputError);
}

TEST_F(FeatureExtractionTest, MissingInputsThrow) {
  ExtractionStageOptions options;
  Database database(dir_ / "database.db");
  EXPECT_THROW(RunExtractionStage(options, dir_ / "no_such_folder", &database), InputError);
  options.camera.intrinsics_path = dir_ / "missing_K.txt";
  WriteImage("a.png", 64, 48);
  EXPECT_THROW(RunExtractionStage(options, images_, &database), InputError);
  EXPECT_EQ(database.NumImages(), 0u);
}

}  // namespace
}  // namespace parallax
