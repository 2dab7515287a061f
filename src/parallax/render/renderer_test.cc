#include "parallax/render/renderer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "parallax/geometry/look_at.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

Rigid3d RingPose(double azimuth_degrees) {
  const double azimuth = azimuth_degrees * M_PI / 180.0;
  return LookAt(Eigen::Vector3d(21 * std::cos(azimuth), 21 * std::sin(azimuth), 9.5),
                Eigen::Vector3d(0, 0, 3));
}

TEST(RenderView, DeterministicWhateverTheThreads) {
  const SceneModel scene;
  const Camera camera = Camera::Create(1, CameraModelId::kPinhole, 150, 160, 120);
  RenderOptions options;
  options.noise_stddev = 2.0;
  options.noise_seed = 9;
  options.num_threads = 1;
  const cv::Mat a = RenderView(scene, camera, RingPose(30), options);
  options.num_threads = 3;
  const cv::Mat b = RenderView(scene, camera, RingPose(30), options);
  ASSERT_EQ(a.type(), CV_8UC3);
  ASSERT_EQ(a.size(), cv::Size(160, 120));
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  options.noise_seed = 10;
  const cv::Mat c = RenderView(scene, camera, RingPose(30), options);
  EXPECT_GT(cv::norm(a, c, cv::NORM_L1), 0.0);
}

// A known 3D point projects onto the pixel whose depth is the point's depth, for pinhole and
// distorting cameras: the renderer draws the scene where Camera::ImgFromCam says it is.
TEST(RenderView, KnownPointsLandWhereTheyProject) {
  const SceneModel scene;
  RenderOptions options;
  options.antialiasing = Antialiasing::kNone;
  Camera distorted = Camera::Create(1, CameraModelId::kSimpleRadial, 300, 320, 240);
  distorted.params[3] = -0.08;
  // A 190-degree fisheye (it sees the ground behind its image plane) and a full sphere.
  Camera fisheye =
      Camera::Create(1, CameraModelId::kOpenCVFisheye, 160 / (95 * M_PI / 180), 320, 320);
  fisheye.params[4] = 0.02;
  fisheye.params[5] = -0.005;
  const Camera sphere = Camera::Create(1, CameraModelId::kEquirectangular, 0, 320, 160);
  for (const Camera& camera :
       {Camera::Create(1, CameraModelId::kPinhole, 300, 320, 240), distorted, fisheye, sphere}) {
    SCOPED_TRACE(camera.ModelName());
    const bool perspective = camera.Projection() == CameraProjection::kPerspective;
    // From the -y side and above: points of the roof's near slope (ridge at y = 0, z = 7.4,
    // eaves at y = -3.7, z = 5.6) and of the ground between the camera and the plaza, where
    // nothing can hide them.
    const Rigid3d cam_from_world = LookAt(Eigen::Vector3d(3, -20, 12), Eigen::Vector3d(0, 0, 2.5));
    cv::Mat depth;
    RenderView(scene, camera, cam_from_world, options, &depth);
    std::vector<Eigen::Vector3d> points;
    for (double x = -5; x <= 5; x += 1.0) {
      for (const double y : {-0.9, -1.85, -2.8})
        points.emplace_back(x, y, 5.6 + 1.8 * (3.7 + y) / 3.7);
      points.emplace_back(x, -12, 0.0);
      // For the wide lenses, the ground below and behind the camera, 70 to 100 degrees off
      // its axis (a perspective lens cannot see it; with distortion folding back it might
      // show it at a wrong pixel).
      if (!perspective) {
        for (const double y : {-21.5, -23.0, -24.5, -26.0, -27.0}) points.emplace_back(x, y, 0.0);
      }
    }
    int num_checked = 0, num_behind = 0;
    for (const Eigen::Vector3d& point : points) {
      const Eigen::Vector3d point_in_cam = cam_from_world * point;
      if (perspective && point_in_cam.z() <= 0) continue;
      const Eigen::Vector2d xy = camera.ImgFromCam(point_in_cam);
      const int col = static_cast<int>(std::floor(xy.x())),
                row = static_cast<int>(std::floor(xy.y()));
      if (col < 0 || row < 0 || col >= depth.cols || row >= depth.rows) continue;
      // Half a pixel of offset changes the depth by well under 1% on these surfaces (2% for
      // the coarse sphere, whose pixel spans 1.1 degrees).
      const double expected = perspective ? point_in_cam.z() : point_in_cam.norm();
      const double tolerance = camera.Projection() == CameraProjection::kSpherical ? 0.02 : 0.01;
      EXPECT_NEAR(depth.at<float>(row, col), expected, tolerance * expected) << point.transpose();
      ++num_checked;
      num_behind += point_in_cam.z() < 0;
    }
    EXPECT_GT(num_checked, 25);
    if (!perspective) EXPECT_GE(num_behind, 4);
  }
}

// Two views 3 degrees apart show the same texture around corresponding points, and less so
// one pixel off: the renderer draws the scene exactly where the cameras project it.
TEST(RenderView, CorrespondingPatchesLookAlike) {
  const SceneModel scene;
  const Camera camera = Camera::Create(1, CameraModelId::kPinhole, 576, 640, 480);
  RenderOptions options;
  const Rigid3d pose1 = RingPose(-60), pose2 = RingPose(-57);
  cv::Mat depth1, depth2, image1, image2;
  cv::cvtColor(RenderView(scene, camera, pose1, options, &depth1), image1, cv::COLOR_BGR2GRAY);
  cv::cvtColor(RenderView(scene, camera, pose2, options, &depth2), image2, cv::COLOR_BGR2GRAY);
  image1.convertTo(image1, CV_32F);
  image2.convertTo(image2, CV_32F);
  const cv::Size patch_size(7, 7);
  const std::vector<Eigen::Vector2d> offsets = {{0, 0}, {1, 0}, {0, 1}, {-1, 0}, {0, -1}};
  std::vector<std::vector<double>> scores(offsets.size());
  for (int row = 40; row < 440; row += 16) {
    for (int col = 40; col < 600; col += 16) {
      const float z1 = depth1.at<float>(row, col);
      if (z1 <= 0) continue;
      const Eigen::Vector2d xy1(col + 0.5, row + 0.5);
      const Eigen::Vector3d point = pose1.Inverse() * (z1 * camera.CamFromImg(xy1).homogeneous());
      const Eigen::Vector3d point_in_cam2 = pose2 * point;
      const Eigen::Vector2d xy2 = camera.ImgFromCam(point_in_cam2);
      if (xy2.x() < 20 || xy2.y() < 20 || xy2.x() > 620 || xy2.y() > 460) continue;
      // Visible in view 2 (not occluded) and not on a depth edge.
      const float z2 = depth2.at<float>(static_cast<int>(xy2.y()), static_cast<int>(xy2.x()));
      if (std::abs(z2 - point_in_cam2.z()) > 0.005 * point_in_cam2.z()) continue;
      // OpenCV puts pixel centres at integers, COLMAP at +0.5.
      cv::Mat patch1, patch2;
      cv::getRectSubPix(image1, patch_size, cv::Point2f(col, row), patch1);
      for (size_t k = 0; k < offsets.size(); ++k) {
        const Eigen::Vector2d center = xy2 + offsets[k] - Eigen::Vector2d(0.5, 0.5);
        cv::getRectSubPix(image2, patch_size, cv::Point2f(center.x(), center.y()), patch2);
        cv::Mat result;
        cv::matchTemplate(patch1, patch2, result, cv::TM_CCOEFF_NORMED);
        scores[k].push_back(result.at<float>(0, 0));
      }
    }
  }
  ASSERT_GT(scores[0].size(), 300u);
  std::vector<double> medians;
  for (std::vector<double>& values : scores) {
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    medians.push_back(values[values.size() / 2]);
  }
  EXPECT_GT(medians[0], 0.95);
  for (size_t k = 1; k < offsets.size(); ++k) EXPECT_LT(medians[k], medians[0] - 0.05) << k;
}

TEST(RenderView, RichTextureEverywhere) {
  const SceneModel scene;
  const Camera camera = Camera::Create(1, CameraModelId::kPinhole, 576, 640, 480);
  cv::Mat gray;
  cv::cvtColor(RenderView(scene, camera, RingPose(0), RenderOptions()), gray, cv::COLOR_BGR2GRAY);
  std::vector<cv::KeyPoint> keypoints;
  cv::SIFT::create()->detect(gray, keypoints);
  EXPECT_GT(keypoints.size(), 1500u);
  // Keypoints in most cells of a 4x4 grid (the sky takes part of the top row).
  std::vector<int> cells(16, 0);
  for (const cv::KeyPoint& keypoint : keypoints) {
    ++cells[4 * std::min(3, static_cast<int>(keypoint.pt.y / 120)) +
            std::min(3, static_cast<int>(keypoint.pt.x / 160))];
  }
  EXPECT_GE(std::count_if(cells.begin(), cells.end(), [](int count) { return count >= 20; }), 12);
  // At several scales: SIFT octaves 0 to 2 (sigma about 1.6 to 13 pixels).
  int small = 0, medium = 0, large = 0;
  for (const cv::KeyPoint& keypoint : keypoints) {
    if (keypoint.size < 6)
      ++small;
    else if (keypoint.size < 12)
      ++medium;
    else
      ++large;
  }
  EXPECT_GT(small, 300);
  EXPECT_GT(medium, 150);
  EXPECT_GT(large, 50);
}

TEST(RenderView, NoiseBlurAndExposure) {
  const SceneModel scene;
  const Camera camera = Camera::Create(1, CameraModelId::kPinhole, 150, 160, 120);
  RenderOptions options;
  const cv::Mat clean = RenderView(scene, camera, RingPose(100), options);
  cv::Mat clean_float, noisy_float;
  clean.convertTo(clean_float, CV_32F);

  options.noise_stddev = 4.0;
  RenderView(scene, camera, RingPose(100), options).convertTo(noisy_float, CV_32F);
  cv::Scalar mean, stddev;
  cv::meanStdDev(noisy_float - clean_float, mean, stddev);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(mean[c], 0.0, 0.2);
    EXPECT_NEAR(stddev[c], 4.0, 0.3);  // rounding to integers adds about 1/12 of variance
  }

  options.noise_stddev = 0.0;
  options.blur_sigma = 1.5;
  cv::Mat blurred, gradient_clean, gradient_blurred;
  cv::Laplacian(clean, gradient_clean, CV_32F);
  cv::Laplacian(RenderView(scene, camera, RingPose(100), options), gradient_blurred, CV_32F);
  EXPECT_LT(cv::norm(gradient_blurred), 0.5 * cv::norm(gradient_clean));

  options.blur_sigma = 0.0;
  options.exposure = 0.8;
  const cv::Mat darker = RenderView(scene, camera, RingPose(100), options);
  EXPECT_NEAR(cv::mean(darker)[1] / cv::mean(clean)[1], 0.8, 0.02);

  options.exposure = 1.0;
  options.sun_direction = Eigen::Vector3d(-0.5, 0.4, 0.77).normalized();
  const cv::Mat other_light = RenderView(scene, camera, RingPose(100), options);
  EXPECT_GT(cv::norm(other_light, clean, cv::NORM_L1) / clean.total(), 10.0);

  options.exposure = -1.0;
  EXPECT_THROW(RenderView(scene, camera, RingPose(100), options), CheckError);
}

}  // namespace
}  // namespace parallax
