#include "parallax/export/image_undistortion.h"

#include "parallax/export/test_models.h"

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
using test::BarrelCamera;
using test::ExactModel;
using test::RingPose;

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
  // blank_pixels 1: every pixel of the photo lands inside the undistorted image (its outer
  // edge up to half a pixel beyond the border pixels' centres, plus a pixel of rounding).
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
      EXPECT_GE(target.x(), -1.5);
      EXPECT_LE(target.x(), full.width + 1.5);
      EXPECT_GE(target.y(), -1.5);
      EXPECT_LE(target.y(), full.height + 1.5);
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
// A 150-degree OPENCV_FISHEYE as Parallax refined it on a synthetic GoPro-like scene, and
// the PINHOLE camera COLMAP 4.2's image_undistorter made of it (default options): the same.
TEST(UndistortedCamera, AFisheyeBecomesColmapsPinhole) {
  Camera fisheye;
  fisheye.camera_id = 1;
  fisheye.model_id = CameraModelId::kOpenCVFisheye;
  fisheye.width = 640;
  fisheye.height = 480;
  fisheye.params = {244.86510848011702,     245.4720216160195,      319.95439136096593,
                    240.17237089142409,     0.047745042994425467,   -0.0077812974090392586,
                    0.00088963640426582542, -8.9451580210456836e-05};
  const Camera pinhole = UndistortedCamera(fisheye, {});
  EXPECT_EQ(pinhole.model_id, CameraModelId::kPinhole);
  EXPECT_EQ(pinhole.width, 1280u);
  EXPECT_EQ(pinhole.height, 674u);
  const std::vector<double> colmap = {244.86510848011702, 245.4720216160195, 639.90878272193186,
                                      337.24203746004133};
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(pinhole.params[i], colmap[i], 1e-6) << i;
}

// Wider than 180 degrees: border pixels behind the image plane never limit the crop, and
// every pixel of the cropped view comes from the photo.
TEST(UndistortedCamera, AFisheyeWiderThanAHemisphereCropsToThePhoto) {
  Camera fisheye =
      Camera::Create(1, CameraModelId::kOpenCVFisheye, 320 / (95 * M_PI / 180), 640, 640);
  const Camera pinhole = UndistortedCamera(fisheye, {});
  EXPECT_GT(pinhole.width, 640u);
  EXPECT_LE(pinhole.width, 1280u);
  for (double x = 0.5; x < pinhole.width; x += pinhole.width / 16.0) {
    for (double y = 0.5; y < pinhole.height; y += pinhole.height / 16.0) {
      const Eigen::Vector2d xy = fisheye.ImgFromCam(pinhole.CamFromImg({x, y}).homogeneous());
      EXPECT_TRUE(xy.x() >= 0 && xy.x() <= 640 && xy.y() >= 0 && xy.y() <= 640) << x << " " << y;
    }
  }
  UndistortionOptions keep_all;
  keep_all.blank_pixels = 1;
  EXPECT_EQ(UndistortedCamera(fisheye, keep_all).width, 1280u);  // As large as allowed.
}

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

TEST(UndistortReconstruction, PointsReprojectAsTheyDidThroughTheDistortedCameras) {
  const Reconstruction model = ExactModel();
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
    model_ = ExactModel();
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

// An output that cannot be written, in a folder that is a file or read-only: the error says
// which folder and why, and nothing of a workspace is left.
TEST_F(WorkspaceTest, UnwritableOutputIsAOneLineErrorAndLeavesNothing) {
  WriteFileAtomically(
      dir_.path() / "a_file", [](std::ostream& stream) { stream << "not a folder\n"; }, true);
  std::vector<fs::path> outputs = {dir_.path() / "a_file" / "dense"};
  const std::optional<fs::path> unwritable = test::UnwritableFolder(dir_);
  if (unwritable) outputs.push_back(*unwritable);
  for (const fs::path& out : outputs) {
    try {
      WriteUndistortedWorkspace(model_, dir_.path() / "photos", out, {});
      FAIL() << "no error for " << out;
    } catch (const InputError& error) {
      const std::string message = error.what();
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
      EXPECT_NE(message.find(out.string()), std::string::npos) << message;
      EXPECT_NE(message.find("cannot create output folder"), std::string::npos) << message;
    }
    EXPECT_FALSE(fs::exists(out / "sparse"));
    EXPECT_FALSE(fs::exists(out / "images"));
  }
}

}  // namespace
}  // namespace parallax
