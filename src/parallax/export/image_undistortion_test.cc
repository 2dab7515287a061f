#include "parallax/export/image_undistortion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

#include "parallax/image/image_codecs.h"
#include "parallax/render/renderer.h"
#include "parallax/render/scene_model.h"
#include "parallax/scene/colmap_io.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"
#include "parallax/util/test_dir.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;

// Strong barrel distortion: 640 x 480, f = 500, k = -0.2 (corners move by about 40 px).
Camera BarrelCamera() {
  Camera camera = Camera::Create(1, CameraModelId::kSimpleRadial, 500, 640, 480);
  camera.params[3] = -0.2;
  return camera;
}

// cam_from_world of a camera at `center` looking at `target`, image up towards +z.
Rigid3d LookAt(const Eigen::Vector3d& center, const Eigen::Vector3d& target) {
  const Eigen::Vector3d forward = (target - center).normalized();
  const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ()).normalized();
  Eigen::Matrix3d rotation;
  rotation.row(0) = right.transpose();
  rotation.row(1) = forward.cross(right).transpose();
  rotation.row(2) = forward.transpose();
  return Rigid3d(rotation, -rotation * center);
}

Rigid3d RingPose(double azimuth_degrees) {
  const double azimuth = azimuth_degrees * M_PI / 180.0;
  return LookAt(Eigen::Vector3d(21 * std::cos(azimuth), 21 * std::sin(azimuth), 9.5),
                Eigen::Vector3d(0, 0, 3));
}

// The pixel of `camera`'s photo that the undistorted pixel (x, y) shows.
Eigen::Vector2d SourcePixel(const Camera& camera, const Camera& undistorted, double x, double y) {
  return camera.ImgFromCam(undistorted.CamFromImg(Eigen::Vector2d(x, y)).homogeneous());
}

TEST(UndistortedCamera, CropsToValidPixelsOrKeepsAllOfThePhoto) {
  const Camera camera = BarrelCamera();
  const Camera cropped = UndistortedCamera(camera, {});
  EXPECT_EQ(cropped.model_id, CameraModelId::kPinhole);
  EXPECT_DOUBLE_EQ(cropped.FocalLengthX(), 500);
  EXPECT_DOUBLE_EQ(cropped.FocalLengthY(), 500);
  // Barrel distortion pulls the edges in: undistorted, the photo covers more than 640 x 480.
  EXPECT_GT(cropped.width, 640u);
  // blank_pixels 0: every pixel of the undistorted image comes from inside the photo.
  const double w = cropped.width, h = cropped.height;
  for (double t = 0; t <= 1.0; t += 0.01) {
    for (const Eigen::Vector2d& pixel : {Eigen::Vector2d(t * w, 0), Eigen::Vector2d(t * w, h),
                                         Eigen::Vector2d(0, t * h), Eigen::Vector2d(w, t * h)}) {
      const Eigen::Vector2d source = SourcePixel(camera, cropped, pixel.x(), pixel.y());
      EXPECT_GE(source.x(), -1e-6);
      EXPECT_LE(source.x(), 640 + 1e-6);
      EXPECT_GE(source.y(), -1e-6);
      EXPECT_LE(source.y(), 480 + 1e-6);
    }
  }
  // blank_pixels 1: every pixel of the photo lands inside the undistorted image.
  UndistortionOptions keep_all;
  keep_all.blank_pixels = 1.0;
  const Camera full = UndistortedCamera(camera, keep_all);
  EXPECT_GT(full.width, cropped.width);
  EXPECT_GT(full.height, cropped.height);
  for (double t = 0; t <= 1.0; t += 0.01) {
    for (const Eigen::Vector2d& pixel :
         {Eigen::Vector2d(t * 640, 0), Eigen::Vector2d(t * 640, 480), Eigen::Vector2d(0, t * 480),
          Eigen::Vector2d(640, t * 480)}) {
      const Eigen::Vector2d target = full.ImgFromCam(camera.CamFromImg(pixel).homogeneous());
      EXPECT_GE(target.x(), -1.0);
      EXPECT_LE(target.x(), full.width + 1.0);
      EXPECT_GE(target.y(), -1.0);
      EXPECT_LE(target.y(), full.height + 1.0);
    }
  }
  // max_image_size scales focal lengths and size together.
  UndistortionOptions small;
  small.max_image_size = 320;
  const Camera scaled = UndistortedCamera(camera, small);
  EXPECT_EQ(std::max(scaled.width, scaled.height), 320u);
  EXPECT_NEAR(scaled.FocalLengthX() / cropped.FocalLengthX(),
              320.0 / std::max(cropped.width, cropped.height), 0.01);
}

// The undistorted image of a distorted render is the render of the same view by the ideal
// pinhole camera. Both are rendered as a camera takes photos: each pixel integrates its area
// (3 x 3 rays) and the lens blurs a little (sigma 0.5 px), so neither aliases.
TEST(UndistortImage, MatchesAnIdealPinholeRenderOfTheSameView) {
  const SceneModel scene;
  RenderOptions render;
  render.antialiasing = Antialiasing::kGrid3x3;
  render.blur_sigma = 0.5;
  const Camera camera = BarrelCamera();
  const Camera pinhole = UndistortedCamera(camera, {});
  const cv::Mat distorted = RenderView(scene, camera, RingPose(40), render);
  const cv::Mat ideal = RenderView(scene, pinhole, RingPose(40), render);
  const cv::Mat undistorted = UndistortImage(distorted, camera, pinhole);
  ASSERT_EQ(undistorted.size(), ideal.size());
  // One pixel of margin: bilinear interpolation at the border reads the black outside.
  const cv::Rect inner(1, 1, ideal.cols - 2, ideal.rows - 2);
  const double psnr = cv::PSNR(undistorted(inner), ideal(inner));
  RecordProperty("psnr_db", std::to_string(psnr));
  EXPECT_GE(psnr, 35.0);
}

// A small exact model: three views of 40 points through the barrel camera.
Reconstruction DistortedModel() {
  Reconstruction model;
  model.AddCamera(BarrelCamera());
  std::mt19937 random(3);
  std::uniform_real_distribution<double> uniform(-4, 4);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 40; ++i)
    points.emplace_back(uniform(random), uniform(random), 3 + uniform(random) / 4);
  for (image_t image_id = 1; image_id <= 3; ++image_id) {
    Image image;
    image.image_id = image_id;
    image.camera_id = 1;
    image.name = "view" + std::to_string(image_id) + ".png";
    image.cam_from_world = RingPose(30.0 + 10.0 * image_id);
    for (const Eigen::Vector3d& point : points) {
      Point2D point2D;
      point2D.xy = model.GetCamera(1).ImgFromCam(image.cam_from_world * point);
      image.points2D.push_back(point2D);
    }
    model.AddImage(image);
    model.RegisterImage(image_id);
  }
  for (size_t index = 0; index < points.size(); ++index) {
    Track track;
    for (image_t image_id = 1; image_id <= 3; ++image_id) {
      track.AddElement(image_id, static_cast<point2D_t>(index));
    }
    // A little off the truth, so that reprojection errors are not all zero.
    model.AddPoint3D(points[index] + Eigen::Vector3d(0.01, -0.02, 0.005), track);
  }
  return model;
}

TEST(UndistortReconstruction, PointsReprojectAsTheyDidThroughTheDistortedCameras) {
  const Reconstruction model = DistortedModel();
  const std::map<camera_t, Camera> cameras = {{1, UndistortedCamera(model.GetCamera(1), {})}};
  const Reconstruction undistorted = UndistortReconstruction(model, cameras);
  EXPECT_EQ(undistorted.GetCamera(1).ModelName(), "PINHOLE");
  double max_difference = 0;
  for (const auto& [point3D_id, point] : model.Points3D()) {
    for (const TrackElement& element : point.track.elements) {
      const double before = model.ReprojectionError(element.image_id, element.point2D_idx);
      const double after = undistorted.ReprojectionError(element.image_id, element.point2D_idx);
      EXPECT_GT(before, 0.01);
      max_difference = std::max(max_difference, std::abs(after - before));
    }
  }
  // The same rays, so the same errors up to the distortion's local scale (well under 0.05).
  EXPECT_LT(max_difference, 0.05);
}

class WorkspaceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    model_ = DistortedModel();
    const SceneModel scene;
    fs::create_directories(dir_.path() / "photos");
    for (const auto& [image_id, image] : model_.Images()) {
      const cv::Mat pixels = RenderView(scene, model_.GetCamera(1), image.cam_from_world, {});
      WriteFileAtomically(
          dir_.path() / "photos" / image.name,
          [&](std::ostream& stream) { stream << EncodePng(pixels); }, true);
    }
  }
  test::ScopedTestDir dir_{"undistort"};
  Reconstruction model_;
};

TEST_F(WorkspaceTest, WritesColmapsDenseWorkspace) {
  const fs::path out = dir_.path() / "dense";
  const UndistortionResult result =
      WriteUndistortedWorkspace(model_, dir_.path() / "photos", out, {});
  EXPECT_EQ(result.num_images, 3u);
  const Reconstruction sparse = ReadReconstruction(out / "sparse");
  EXPECT_EQ(sparse.NumRegImages(), 3u);
  EXPECT_EQ(sparse.GetCamera(1).ModelName(), "PINHOLE");
  for (const auto& [image_id, image] : sparse.Images()) {
    const Bitmap bitmap = ReadBitmap(out / "images" / image.name);
    EXPECT_EQ(bitmap.Width(), static_cast<int>(sparse.GetCamera(1).width));
    EXPECT_EQ(bitmap.Height(), static_cast<int>(sparse.GetCamera(1).height));
  }
  EXPECT_EQ(ReadFileToString(out / "stereo" / "fusion.cfg"), "view1.png\nview2.png\nview3.png\n");
  EXPECT_EQ(SplitLines(ReadFileToString(out / "stereo" / "patch-match.cfg")).size(), 6u);
  EXPECT_TRUE(fs::is_directory(out / "stereo" / "depth_maps"));
}

TEST_F(WorkspaceTest, BadPhotosAreOneLineErrorsAndLeaveNoModel) {
  const fs::path out = dir_.path() / "dense";
  fs::remove(dir_.path() / "photos" / "view2.png");
  try {
    WriteUndistortedWorkspace(model_, dir_.path() / "photos", out, {});
    FAIL() << "no error";
  } catch (const MissingFileError& error) {
    EXPECT_NE(std::string(error.what()).find("view2.png: photo of the model not found"),
              std::string::npos);
  }
  EXPECT_FALSE(fs::exists(out));
  // A photo of another size than its camera's.
  const cv::Mat small(100, 120, CV_8UC3, cv::Scalar(50, 60, 70));
  WriteFileAtomically(
      dir_.path() / "photos" / "view2.png",
      [&](std::ostream& stream) { stream << EncodePng(small); }, true);
  try {
    WriteUndistortedWorkspace(model_, dir_.path() / "photos", out, {});
    FAIL() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(
        std::string(error.what()).find("view2.png: image is 120x100 but its camera 1 is 640x480"),
        std::string::npos);
  }
  EXPECT_FALSE(fs::exists(out / "sparse"));
}

}  // namespace
}  // namespace parallax
