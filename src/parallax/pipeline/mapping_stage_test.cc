#include "parallax/pipeline/mapping_stage.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <opencv2/imgcodecs.hpp>

#include "parallax/scene/colmap_io.h"
#include "parallax/util/file.h"
#include "parallax/util/test_dir.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;

class MappingStageTest : public ::testing::Test {
 protected:
  // Two registered images of one camera with `num_points` points seen by both, each at the
  // same pixel (x = index) in both images.
  static Reconstruction TwoViewModel(int num_points) {
    Reconstruction model;
    model.AddCamera(Camera::Create(1, CameraModelId::kPinhole, 100, 64, 48));
    for (image_t image_id : {1, 2}) {
      Image image;
      image.image_id = image_id;
      image.camera_id = 1;
      image.name = "view" + std::to_string(image_id) + ".png";
      for (int k = 0; k < num_points; ++k) {
        Point2D point2D;
        point2D.xy = Eigen::Vector2d(k + 0.5, 10.5);
        image.points2D.push_back(point2D);
      }
      model.AddImage(image);
      model.RegisterImage(image_id);
    }
    for (int k = 0; k < num_points; ++k) {
      Track track;
      track.elements = {{1, static_cast<point2D_t>(k)}, {2, static_cast<point2D_t>(k)}};
      model.AddPoint3D(Eigen::Vector3d(k, 0, 5), track);
    }
    return model;
  }

  const test::ScopedTestDir scoped_dir_{"parallax_mapping_stage_test"};
  const fs::path dir_ = scoped_dir_.path();
};

TEST_F(MappingStageTest, ColoursAreTheMeanOfTheObservations) {
  // view1 is (red 10, green 20, blue 30) everywhere, view2 (red 50, green 61, blue 255).
  ASSERT_TRUE(
      cv::imwrite((dir_ / "view1.png").string(), cv::Mat(48, 64, CV_8UC3, cv::Scalar(30, 20, 10))));
  ASSERT_TRUE(cv::imwrite((dir_ / "view2.png").string(),
                          cv::Mat(48, 64, CV_8UC3, cv::Scalar(255, 61, 50))));
  Reconstruction model = TwoViewModel(60);
  ColorizePoints(dir_, nullptr, &model);
  for (const auto& [point3D_id, point] : model.Points3D()) {
    // Exact means (61 + 20) / 2 = 40.5 rounds away from zero. A sum that started from an
    // uninitialised vector gave other values, different in every run.
    EXPECT_EQ(point.color.cast<int>(), Eigen::Vector3i(30, 41, 143)) << point3D_id;
  }
  // A missing image is skipped: the colours come from the other one alone.
  fs::remove(dir_ / "view2.png");
  ColorizePoints(dir_, nullptr, &model);
  EXPECT_EQ(model.Points3D().begin()->second.color.cast<int>(), Eigen::Vector3i(10, 20, 30));
}

TEST_F(MappingStageTest, ColoursComeFromTheDatabaseWhereItStoredTheKeypointsColours) {
  // The images say (red 10, green 20, blue 30) everywhere; the database stored other colours
  // for view1's keypoints, and for view2 colours of a different number of keypoints (another
  // extraction than the model's), which are not used.
  for (const char* name : {"view1.png", "view2.png"}) {
    ASSERT_TRUE(
        cv::imwrite((dir_ / name).string(), cv::Mat(48, 64, CV_8UC3, cv::Scalar(30, 20, 10))));
  }
  const int num_points = 4;
  Database database(dir_ / "database.db");
  const camera_t camera_id =
      database.WriteCamera(Camera::Create(kInvalidCameraId, CameraModelId::kPinhole, 100, 64, 48));
  KeypointColors view1_colors;
  for (int k = 0; k < num_points; ++k) view1_colors.insert(view1_colors.end(), {200, 100, 0});
  const FeatureKeypoints keypoints(num_points);
  const FeatureDescriptors descriptors(num_points, 128);
  database.WriteImageWithFeatures("view1.png", camera_id, keypoints, descriptors, std::nullopt,
                                  std::nullopt, view1_colors);
  database.WriteImageWithFeatures("view2.png", camera_id, keypoints, descriptors, std::nullopt,
                                  std::nullopt, KeypointColors(3 * (num_points + 1), 0));

  Reconstruction model = TwoViewModel(num_points);
  ColorizePoints(dir_, &database, &model);
  for (const auto& [point3D_id, point] : model.Points3D()) {
    EXPECT_EQ(point.color.cast<int>(), Eigen::Vector3i(105, 60, 15)) << point3D_id;
  }
  // Stored colours need no image: without view1.png they are still used.
  fs::remove(dir_ / "view1.png");
  ColorizePoints(dir_, &database, &model);
  EXPECT_EQ(model.Points3D().begin()->second.color.cast<int>(), Eigen::Vector3i(105, 60, 15));
}

TEST_F(MappingStageTest, WriteModelsReplacesTheOutputsOfAnEarlierRunAsAWhole) {
  const fs::path out = dir_ / "out";
  // An earlier run with two models, its summary, and leftovers of a killed write.
  WriteModels({TwoViewModel(3), TwoViewModel(2)}, out, true, true);
  ASSERT_TRUE(fs::exists(out / "sparse" / "1" / "points3D.bin"));
  WriteTextFileAtomically(out / "summary.json", "{}\n");
  CreateDirectoryOrThrow(out / "sparse.tmp-1234" / "0");
  WriteTextFileAtomically(out / "sparse.tmp-1234" / "0" / "cameras.txt", "partial");

  WriteModels({TwoViewModel(5)}, out, true, false);
  EXPECT_FALSE(fs::exists(out / "sparse" / "1"));  // No model of the earlier run.
  EXPECT_FALSE(fs::exists(out / "sparse" / "0" / "points3D.bin"));
  EXPECT_FALSE(fs::exists(out / "summary.json"));  // The caller writes it anew.
  EXPECT_FALSE(fs::exists(out / "sparse.tmp-1234"));
  EXPECT_EQ(ReadReconstruction(out / "sparse" / "0").NumPoints3D(), 5u);
  EXPECT_TRUE(fs::exists(out / "points.ply"));
  for (const auto& entry : fs::directory_iterator(out)) {
    const std::string name = entry.path().filename().string();
    EXPECT_TRUE(name == "sparse" || name == "points.ply") << name;
  }
}

}  // namespace
}  // namespace parallax
