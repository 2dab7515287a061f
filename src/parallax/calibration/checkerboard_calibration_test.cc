#include "parallax/calibration/checkerboard_calibration.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <filesystem>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>

#include "parallax/geometry/rigid3.h"
#include "parallax/math/random.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"

namespace parallax {
namespace {

constexpr int kCols = 8;
constexpr int kRows = 6;
constexpr double kSquare = 0.025;  // metres

Camera MakeTrueCamera(int width, int height) {
  Camera camera;
  camera.camera_id = 1;
  camera.model_id = CameraModelId::kOpenCV;
  camera.width = width;
  camera.height = height;
  const double scale = width / 640.0;
  camera.params = {scale * 700, scale * 705, scale * 322.5, scale * 236.25,
                   -0.12,       0.05,        0.0008,        -0.0005};
  return camera;
}

Eigen::Vector3d BoardPoint(double col, double row) {
  return Eigen::Vector3d(col * kSquare, row * kSquare, 0);
}

// Projected inner corners; `k3` adds OpenCV's sixth-order radial term to the OPENCV model.
std::vector<Eigen::Vector2d> ProjectCorners(const Camera& camera, const Rigid3d& cam_from_board,
                                            double k3 = 0) {
  std::vector<Eigen::Vector2d> corners;
  for (int row = 0; row < kRows; ++row) {
    for (int col = 0; col < kCols; ++col) {
      const Eigen::Vector3d point_in_cam = cam_from_board * BoardPoint(col, row);
      const Eigen::Vector2d normalized = point_in_cam.hnormalized();
      const double r2 = normalized.squaredNorm();
      corners.push_back(camera.ImgFromCam(point_in_cam) +
                        k3 * r2 * r2 * r2 *
                            normalized.cwiseProduct(
                                Eigen::Vector2d(camera.FocalLengthX(), camera.FocalLengthY())));
    }
  }
  return corners;
}

// A random tilted board pose whose printed sheet (board plus one white square of margin)
// fills about half of the image and stays inside it.
Rigid3d RandomBoardPose(const Camera& camera) {
  const Eigen::Vector3d center = BoardPoint((kCols - 1) / 2.0, (kRows - 1) / 2.0);
  const double sheet_width = (kCols + 3) * kSquare;
  while (true) {
    const Eigen::Matrix3d rotation =
        (Eigen::AngleAxisd(RandomUniformReal(-0.6, 0.6), Eigen::Vector3d::UnitX()) *
         Eigen::AngleAxisd(RandomUniformReal(-0.6, 0.6), Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(RandomUniformReal(-0.4, 0.4), Eigen::Vector3d::UnitZ()))
            .toRotationMatrix();
    const double depth =
        camera.FocalLengthX() * sheet_width / (RandomUniformReal(0.45, 0.7) * camera.width);
    const Eigen::Vector3d center_in_cam(RandomUniformReal(-0.15, 0.15) * depth,
                                        RandomUniformReal(-0.1, 0.1) * depth, depth);
    const Rigid3d cam_from_board(rotation, center_in_cam - rotation * center);
    bool inside = true;
    for (const double col : {-2.0, kCols + 1.0}) {
      for (const double row : {-2.0, kRows + 1.0}) {
        const Eigen::Vector2d xy = camera.ImgFromCam(cam_from_board * BoardPoint(col, row));
        inside &=
            xy.x() > 4 && xy.y() > 4 && xy.x() < camera.width - 5 && xy.y() < camera.height - 5;
      }
    }
    if (inside) return cam_from_board;
  }
}

// Normalised camera coordinates (distortion undone) of the pixel corners, a
// (width + 1) x (height + 1) grid shared by all renderings with one camera. Inside a pixel the
// rays are interpolated bilinearly: the distortion's curvature over one pixel is negligible.
std::vector<Eigen::Vector2d> PixelCornerRays(const Camera& camera) {
  std::vector<Eigen::Vector2d> grid;
  grid.reserve((camera.width + 1) * (camera.height + 1));
  for (size_t y = 0; y <= camera.height; ++y) {
    for (size_t x = 0; x <= camera.width; ++x) {
      grid.push_back(camera.CamFromImg(Eigen::Vector2d(x - 0.5, y - 0.5)));
    }
  }
  return grid;
}

// An anti-aliased, slightly blurred photo of the board: black and white squares, one white
// square of margin, grey background. Each pixel averages 16 samples in an "n-rooks" pattern (16
// distinct x and 16 distinct y offsets), so that edges along the pixel axes are located to 1/16 px,
// where a 4 x 4 grid would snap them to quarter pixels.
cv::Mat RenderBoard(const Camera& camera, const std::vector<Eigen::Vector2d>& corner_rays,
                    const Rigid3d& cam_from_board) {
  constexpr int kSamples = 16;
  const Eigen::Matrix3d rotation = cam_from_board.rotation.toRotationMatrix();
  Eigen::Matrix3d plane_to_rays;  // [r1 r2 t]: board (X, Y, 1) to rays (u, v, 1) up to scale.
  plane_to_rays << rotation.col(0), rotation.col(1), cam_from_board.translation;
  const Eigen::Matrix3d rays_to_plane = plane_to_rays.inverse();
  // Homogeneous board coordinates of the pixel corners; the map from rays is linear, so
  // interpolating these equals mapping interpolated rays.
  std::vector<Eigen::Vector3d> corner_planes(corner_rays.size());
  for (size_t i = 0; i < corner_rays.size(); ++i) {
    corner_planes[i] = rays_to_plane * corner_rays[i].homogeneous();
  }
  const size_t stride = camera.width + 1;
  cv::Mat image(camera.height, camera.width, CV_32FC1);
  for (size_t y = 0; y < camera.height; ++y) {
    for (size_t x = 0; x < camera.width; ++x) {
      const Eigen::Vector3d& top_left = corner_planes[y * stride + x];
      const Eigen::Vector3d& top_right = corner_planes[y * stride + x + 1];
      const Eigen::Vector3d& bottom_left = corner_planes[(y + 1) * stride + x];
      const Eigen::Vector3d& bottom_right = corner_planes[(y + 1) * stride + x + 1];
      double sum = 0;
      for (int k = 0; k < kSamples; ++k) {
        const double a = (k + 0.5) / kSamples;
        const double b = ((5 * k) % kSamples + 0.5) / kSamples;
        const Eigen::Vector3d plane = (1 - b) * ((1 - a) * top_left + a * top_right) +
                                      b * ((1 - a) * bottom_left + a * bottom_right);
        const double col = plane.x() / plane.z() / kSquare;
        const double row = plane.y() / plane.z() / kSquare;
        double value = 110;  // Background.
        if (plane.z() > 0 && col >= -2 && col < kCols + 1 && row >= -2 && row < kRows + 1) {
          const bool in_board = col >= -1 && col < kCols && row >= -1 && row < kRows;
          const bool black =
              in_board &&
              (static_cast<int>(std::floor(col)) + static_cast<int>(std::floor(row))) % 2 == 0;
          value = black ? 25 : 235;
        }
        sum += value;
      }
      image.at<float>(y, x) = static_cast<float>(sum / kSamples);
    }
  }
  // Lens blur. Without it, gradient-based refinement "pixel-locks" on the one-pixel-wide edges
  // (errors up to 0.1 px on an axis-aligned board); real photos are never that sharp.
  cv::GaussianBlur(image, image, cv::Size(), 1.0);
  cv::Mat gray;
  image.convertTo(gray, CV_8UC1);
  return gray;
}

CheckerboardCalibrationOptions MakeOptions() {
  CheckerboardCalibrationOptions options;
  options.pattern_cols = kCols;
  options.pattern_rows = kRows;
  options.square_size = kSquare;
  return options;
}

std::filesystem::path TempDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

TEST(CheckerboardCalibration, OptionsCheck) {
  EXPECT_NO_THROW(MakeOptions().Check());
  CheckerboardCalibrationOptions options = MakeOptions();
  options.pattern_cols = 1;
  EXPECT_THROW(options.Check(), CheckError);
  options = MakeOptions();
  options.square_size = 0;
  EXPECT_THROW(options.Check(), CheckError);
  options = MakeOptions();
  options.required_width = 640;
  EXPECT_THROW(options.Check(), CheckError);
}

TEST(CheckerboardCalibration, RecoversExactIntrinsicsFromExactCorners) {
  // Corners projected with the COLMAP OPENCV model: recovering them also checks that OpenCV's
  // distortion model is the same one.
  const Camera truth = MakeTrueCamera(640, 480);
  std::vector<std::vector<Eigen::Vector2d>> corners;
  for (int i = 0; i < 10; ++i) corners.push_back(ProjectCorners(truth, RandomBoardPose(truth)));
  std::vector<double> view_rms;
  const CheckerboardCalibrationResult result =
      CalibrateFromCheckerboardCorners(MakeOptions(), 640, 480, corners, &view_rms);
  ASSERT_TRUE(result.success) << result.message;
  EXPECT_EQ(result.num_used_images, 10);
  EXPECT_LT(result.rms_error, 1e-3);  // Corners pass through float in OpenCV.
  ASSERT_EQ(view_rms.size(), 10u);
  for (double rms : view_rms) EXPECT_LT(rms, 1e-3);
  ASSERT_EQ(result.camera.params.size(), 8u);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(result.camera.params[i], truth.params[i], 2e-3) << i;
  for (int i = 4; i < 8; ++i) EXPECT_NEAR(result.camera.params[i], truth.params[i], 1e-4) << i;
  EXPECT_EQ(result.fx, result.camera.params[0]);
  EXPECT_EQ(result.distortion[4], 0);  // k3 held at zero.
  EXPECT_EQ(result.camera.model_id, CameraModelId::kOpenCV);
  EXPECT_TRUE(result.camera.has_prior_focal_length);

  const CalibratedCamera calibrated = CalibratedCameraFromResult(result);
  EXPECT_EQ(calibrated.camera.params, result.camera.params);
  EXPECT_EQ(calibrated.num_images, 10);
  EXPECT_EQ(calibrated.rms_error, result.rms_error);
}

TEST(CheckerboardCalibration, NoisyCornersGiveMatchingRmsAndAccurateIntrinsics) {
  const Camera truth = MakeTrueCamera(640, 480);
  constexpr double kNoise = 0.1;
  std::vector<std::vector<Eigen::Vector2d>> corners;
  for (int i = 0; i < 20; ++i) {
    corners.push_back(ProjectCorners(truth, RandomBoardPose(truth)));
    for (Eigen::Vector2d& corner : corners.back()) {
      corner += Eigen::Vector2d(RandomGaussian(0, kNoise), RandomGaussian(0, kNoise));
    }
  }
  const CheckerboardCalibrationResult result =
      CalibrateFromCheckerboardCorners(MakeOptions(), 640, 480, corners);
  ASSERT_TRUE(result.success) << result.message;
  // RMS of 2D residuals of isotropic noise: sigma * sqrt(2), less the fitted degrees of freedom.
  EXPECT_GT(result.rms_error, 0.8 * kNoise * std::sqrt(2.0));
  EXPECT_LT(result.rms_error, 1.1 * kNoise * std::sqrt(2.0));
  EXPECT_NEAR(result.fx, truth.params[0], 0.005 * truth.params[0]);
  EXPECT_NEAR(result.fy, truth.params[1], 0.005 * truth.params[1]);
  EXPECT_NEAR(result.cx, truth.params[2], 3);
  EXPECT_NEAR(result.cy, truth.params[3], 3);
  // The reported standard deviations are consistent with the actual errors.
  EXPECT_GT(result.fx_std_dev, 0);
  EXPECT_LT(std::abs(result.fx - truth.params[0]), 5 * result.fx_std_dev);
  EXPECT_LT(std::abs(result.cx - truth.params[2]), 5 * result.cx_std_dev);
  EXPECT_LT(std::abs(result.cy - truth.params[3]), 5 * result.cy_std_dev);
}

TEST(CheckerboardCalibration, FitK3FreesTheSixthOrderTerm) {
  const Camera truth = MakeTrueCamera(640, 480);
  std::vector<std::vector<Eigen::Vector2d>> corners;
  constexpr double kK3 = 0.3;
  for (int i = 0; i < 10; ++i) {
    corners.push_back(ProjectCorners(truth, RandomBoardPose(truth), kK3));
  }
  CheckerboardCalibrationOptions options = MakeOptions();
  const CheckerboardCalibrationResult without_k3 =
      CalibrateFromCheckerboardCorners(options, 640, 480, corners);
  options.fit_k3 = true;
  const CheckerboardCalibrationResult with_k3 =
      CalibrateFromCheckerboardCorners(options, 640, 480, corners);
  ASSERT_TRUE(without_k3.success && with_k3.success);
  EXPECT_EQ(without_k3.distortion[4], 0);
  EXPECT_GT(without_k3.rms_error, 10 * with_k3.rms_error);
  EXPECT_LT(with_k3.rms_error, 1e-3);
  EXPECT_NEAR(with_k3.distortion[4], kK3, 1e-3);
  for (int i = 0; i < 8; ++i) EXPECT_NEAR(with_k3.camera.params[i], truth.params[i], 2e-3) << i;
  EXPECT_EQ(CalibratedCameraFromResult(with_k3).k3, with_k3.distortion[4]);
}

TEST(CheckerboardCalibration, TooFewViewsFail) {
  const Camera truth = MakeTrueCamera(640, 480);
  const std::vector<std::vector<Eigen::Vector2d>> corners = {
      ProjectCorners(truth, RandomBoardPose(truth)), ProjectCorners(truth, RandomBoardPose(truth))};
  const CheckerboardCalibrationResult result =
      CalibrateFromCheckerboardCorners(MakeOptions(), 640, 480, corners);
  EXPECT_FALSE(result.success);
  EXPECT_NE(result.message.find("at least 3"), std::string::npos) << result.message;
  EXPECT_THROW(CalibratedCameraFromResult(result), CheckError);
}

struct CornerErrors {
  double mean = 0;
  double max = 0;
};

// Distances between detected and true corners; the detector may number the corners from
// either end of the board.
CornerErrors MeasureCornerErrors(const std::vector<Eigen::Vector2d>& detected,
                                 const std::vector<Eigen::Vector2d>& expected) {
  PARALLAX_CHECK_EQ(detected.size(), expected.size());
  const bool reversed = (detected[0] - expected[0]).norm() > 5;
  CornerErrors errors;
  for (size_t i = 0; i < expected.size(); ++i) {
    const double error = (detected[reversed ? expected.size() - 1 - i : i] - expected[i]).norm();
    errors.mean += error / expected.size();
    errors.max = std::max(errors.max, error);
  }
  return errors;
}

TEST(CheckerboardCalibration, DetectsRenderedCornersToSubPixelAccuracy) {
  const Camera truth = MakeTrueCamera(640, 480);
  const std::vector<Eigen::Vector2d> rays = PixelCornerRays(truth);
  constexpr int kNumViews = 4;
  for (const bool sector_based : {false, true}) {
    CheckerboardCalibrationOptions options = MakeOptions();
    options.use_sector_based_detector = sector_based;
    double mean_of_means = 0;
    for (int view = 0; view < kNumViews; ++view) {
      const Rigid3d cam_from_board = RandomBoardPose(truth);
      const auto corners =
          DetectCheckerboardCorners(options, RenderBoard(truth, rays, cam_from_board));
      ASSERT_TRUE(corners.has_value()) << "sector_based " << sector_based << " view " << view;
      const CornerErrors errors =
          MeasureCornerErrors(*corners, ProjectCorners(truth, cam_from_board));
      // Measured over 30 random poses: mean error 0.022 px; the most tilted boards reach a
      // mean of 0.08 px and a maximum of 0.16 px (cornerSubPix's own limit).
      EXPECT_LT(errors.mean, 0.1) << "sector_based " << sector_based << " view " << view;
      EXPECT_LT(errors.max, 0.25) << "sector_based " << sector_based << " view " << view;
      mean_of_means += errors.mean / kNumViews;
    }
    EXPECT_LT(mean_of_means, 0.05) << "sector_based " << sector_based;
  }
  cv::Mat blank(480, 640, CV_8UC1, cv::Scalar(200));
  EXPECT_FALSE(DetectCheckerboardCorners(MakeOptions(), blank).has_value());
}

TEST(CheckerboardCalibration, DownscaledDetectionIsRefinedAtFullResolution) {
  const Camera truth = MakeTrueCamera(960, 720);
  const std::vector<Eigen::Vector2d> rays = PixelCornerRays(truth);
  const Rigid3d cam_from_board = RandomBoardPose(truth);
  const cv::Mat image = RenderBoard(truth, rays, cam_from_board);
  CheckerboardCalibrationOptions options = MakeOptions();
  options.detection_max_image_size = 0;
  const auto full = DetectCheckerboardCorners(options, image);
  options.detection_max_image_size = 400;
  const auto downscaled = DetectCheckerboardCorners(options, image);
  ASSERT_TRUE(full.has_value() && downscaled.has_value());
  // Same corners as a full-resolution detection, hence as accurate.
  EXPECT_LT(MeasureCornerErrors(*downscaled, *full).max, 0.01);
  EXPECT_LT(MeasureCornerErrors(*downscaled, ProjectCorners(truth, cam_from_board)).mean, 0.1);
}

TEST(CheckerboardCalibration, EndToEndOnRenderedPhotosGroupsBySize) {
  const auto dir = TempDir("parallax_checkerboard_test");
  std::vector<std::filesystem::path> paths;
  const Camera truth = MakeTrueCamera(640, 480);
  const std::vector<Eigen::Vector2d> rays = PixelCornerRays(truth);
  for (int i = 0; i < 8; ++i) {
    paths.push_back(dir / ("large" + std::to_string(i) + ".png"));
    cv::imwrite(paths.back().string(), RenderBoard(truth, rays, RandomBoardPose(truth)));
  }
  const Camera small = MakeTrueCamera(480, 360);
  const std::vector<Eigen::Vector2d> small_rays = PixelCornerRays(small);
  for (int i = 0; i < 3; ++i) {
    paths.push_back(dir / ("small" + std::to_string(i) + ".png"));
    cv::imwrite(paths.back().string(), RenderBoard(small, small_rays, RandomBoardPose(small)));
  }
  paths.push_back(dir / "blank.png");
  cv::imwrite(paths.back().string(), cv::Mat(480, 640, CV_8UC1, cv::Scalar(128)));
  paths.push_back(dir / "garbage.png");
  WriteTextFileAtomically(paths.back(), "not an image");
  paths.push_back(dir / "missing.png");

  const CheckerboardCalibrationResult result = CalibrateFromCheckerboards(MakeOptions(), paths);
  ASSERT_TRUE(result.success) << result.message;
  ASSERT_EQ(result.images.size(), paths.size());
  EXPECT_EQ(result.width, 640);
  EXPECT_EQ(result.height, 480);
  EXPECT_EQ(result.num_used_images, 8);
  for (size_t i = 0; i < paths.size(); ++i) {
    const CheckerboardImageResult& image = result.images[i];
    EXPECT_EQ(image.path, paths[i]);
    const std::string name = paths[i].stem().string();
    if (name.rfind("large", 0) == 0) {
      EXPECT_EQ(image.status, CheckerboardImageStatus::kUsed) << name << ": " << image.reason;
      EXPECT_EQ(image.corners.size(), static_cast<size_t>(kCols * kRows));
      // Corner detection errors (up to 0.08 px mean on the most tilted boards) dominate.
      EXPECT_GT(image.rms_error, 0);
      EXPECT_LT(image.rms_error, 0.15);
    } else if (name.rfind("small", 0) == 0) {
      EXPECT_EQ(image.status, CheckerboardImageStatus::kWrongSize) << name;
      EXPECT_EQ(image.reason, "480x360 differs from the calibrated size 640x480");
    } else if (name == "blank") {
      EXPECT_EQ(image.status, CheckerboardImageStatus::kBoardNotFound);
      EXPECT_EQ(image.reason, "no complete 8x6 board found");
    } else {
      EXPECT_EQ(image.status, CheckerboardImageStatus::kUnreadable) << name;
      EXPECT_FALSE(image.reason.empty());
    }
  }
  EXPECT_LT(result.rms_error, 0.1);
  EXPECT_NEAR(result.fx, truth.params[0], 0.003 * truth.params[0]);
  EXPECT_NEAR(result.fy, truth.params[1], 0.003 * truth.params[1]);
  EXPECT_NEAR(result.cx, truth.params[2], 1.5);
  EXPECT_NEAR(result.cy, truth.params[3], 1.5);
  EXPECT_NEAR(result.distortion[0], truth.params[4], 0.01);

  // Asking for the other size calibrates the three small photos instead.
  CheckerboardCalibrationOptions options = MakeOptions();
  options.required_width = 480;
  options.required_height = 360;
  const CheckerboardCalibrationResult small_result = CalibrateFromCheckerboards(options, paths);
  ASSERT_TRUE(small_result.success) << small_result.message;
  EXPECT_EQ(small_result.num_used_images, 3);
  EXPECT_EQ(small_result.images[0].status, CheckerboardImageStatus::kWrongSize);
  EXPECT_NEAR(small_result.fx, small.params[0], 0.02 * small.params[0]);

  options.required_width = 100;
  options.required_height = 100;
  const CheckerboardCalibrationResult none = CalibrateFromCheckerboards(options, paths);
  EXPECT_FALSE(none.success);
  EXPECT_EQ(none.message, "no image is 100x100");
  EXPECT_FALSE(CalibrateFromCheckerboards(MakeOptions(), {}).success);
  std::filesystem::remove_all(dir);
}

// The shared photos: 12 of 1280x960 (c4, c5, c7-c16) and 16 cropped or resized ones.
TEST(CheckerboardCalibration, CheckerboardDataset) {
  const auto image_dir = DataRoot() / "checkerboard" / "images";
  if (!std::filesystem::is_directory(image_dir)) GTEST_SKIP() << image_dir << " missing";
  std::vector<std::filesystem::path> paths;
  for (const auto& entry : std::filesystem::directory_iterator(image_dir)) {
    if (entry.path().extension() == ".jpg") paths.push_back(entry.path());
  }
  std::sort(paths.begin(), paths.end());
  ASSERT_EQ(paths.size(), 28u);

  CheckerboardCalibrationOptions options;
  options.pattern_cols = 8;
  options.pattern_rows = 6;
  const CheckerboardCalibrationResult result = CalibrateFromCheckerboards(options, paths);
  ASSERT_TRUE(result.success) << result.message;
  EXPECT_EQ(result.width, 1280);
  EXPECT_EQ(result.height, 960);
  const std::set<std::string> expected_used = {"c4",  "c5",  "c7",  "c8",  "c9",  "c10",
                                               "c11", "c12", "c13", "c14", "c15", "c16"};
  std::vector<std::vector<cv::Point2f>> independent_corners;
  for (const CheckerboardImageResult& image : result.images) {
    const std::string name = image.path.stem().string();
    if (expected_used.count(name)) {
      EXPECT_EQ(image.status, CheckerboardImageStatus::kUsed) << name << ": " << image.reason;
      EXPECT_LT(image.rms_error, 1.0) << name;
    } else {
      EXPECT_EQ(image.status, CheckerboardImageStatus::kWrongSize) << name;
      EXPECT_NE(image.reason.find("differs from the calibrated size 1280x960"), std::string::npos);
    }
  }
  EXPECT_EQ(result.num_used_images, 12);
  EXPECT_LE(result.rms_error, 0.6);

  // An independent plain OpenCV calibration of the same 12 photos (default flags, k3 free).
  std::vector<std::vector<cv::Point3f>> object_points;
  std::vector<std::vector<cv::Point2f>> image_points;
  std::vector<cv::Point3f> board;
  for (int row = 0; row < 6; ++row) {
    for (int col = 0; col < 8; ++col) board.emplace_back(col, row, 0);
  }
  for (const std::string& name : expected_used) {
    const cv::Mat gray = cv::imread((image_dir / (name + ".jpg")).string(), cv::IMREAD_GRAYSCALE);
    std::vector<cv::Point2f> corners;
    ASSERT_TRUE(
        cv::findChessboardCorners(gray, cv::Size(8, 6), corners,
                                  cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE));
    cv::cornerSubPix(gray, corners, cv::Size(11, 11), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 0.001));
    image_points.push_back(corners);
    object_points.push_back(board);
  }
  cv::Mat camera_matrix, distortion;
  std::vector<cv::Mat> rotations, translations;
  const double opencv_rms = cv::calibrateCamera(object_points, image_points, cv::Size(1280, 960),
                                                camera_matrix, distortion, rotations, translations);
  const double opencv_fx = camera_matrix.at<double>(0, 0);
  const double opencv_fy = camera_matrix.at<double>(1, 1);
  EXPECT_NEAR(opencv_fx, 1037, 10);
  EXPECT_NEAR(result.fx, opencv_fx, 0.01 * opencv_fx);
  EXPECT_NEAR(result.fy, opencv_fy, 0.01 * opencv_fy);
  EXPECT_NEAR(result.cx, camera_matrix.at<double>(0, 2), 10);
  EXPECT_NEAR(result.cy, camera_matrix.at<double>(1, 2), 10);
  std::cerr << "parallax: rms " << result.rms_error << " fx " << result.fx << " fy " << result.fy
            << " cx " << result.cx << " cy " << result.cy << " k1 " << result.distortion[0]
            << " k2 " << result.distortion[1] << " p1 " << result.distortion[2] << " p2 "
            << result.distortion[3] << "\nopencv:   rms " << opencv_rms << " K "
            << camera_matrix.reshape(1, 1) << " dist " << distortion.reshape(1, 1) << std::endl;
}

}  // namespace
}  // namespace parallax
