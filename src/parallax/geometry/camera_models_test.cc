#include "parallax/geometry/camera_models.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "parallax/geometry/testing/camera_model_params.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

// COLMAP 4.2's table (src/colmap/sensor/models.h): id, name, parameter names. The ids and
// parameter orders are also read from files COLMAP 4.2 wrote (scene/colmap_io_test.cc).
struct ColmapModel {
  int id;
  const char* name;
  const char* params_info;
  int num_params;
};
constexpr ColmapModel kColmapModels[] = {
    {0, "SIMPLE_PINHOLE", "f, cx, cy", 3},
    {1, "PINHOLE", "fx, fy, cx, cy", 4},
    {2, "SIMPLE_RADIAL", "f, cx, cy, k", 4},
    {3, "RADIAL", "f, cx, cy, k1, k2", 5},
    {4, "OPENCV", "fx, fy, cx, cy, k1, k2, p1, p2", 8},
    {5, "OPENCV_FISHEYE", "fx, fy, cx, cy, k1, k2, k3, k4", 8},
    {6, "FULL_OPENCV", "fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6", 12},
    {7, "FOV", "fx, fy, cx, cy, omega", 5},
    {8, "SIMPLE_RADIAL_FISHEYE", "f, cx, cy, k", 4},
    {9, "RADIAL_FISHEYE", "f, cx, cy, k1, k2", 5},
    {10, "THIN_PRISM_FISHEYE", "fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, sx1, sy1", 12},
    {11, "RAD_TAN_THIN_PRISM_FISHEYE",
     "fx, fy, cx, cy, k0, k1, k2, k3, k4, k5, p0, p1, s0, s1, s2, s3", 16},
    {12, "SIMPLE_DIVISION", "f, cx, cy, k", 4},
    {13, "DIVISION", "fx, fy, cx, cy, k", 5},
    {14, "SIMPLE_FISHEYE", "f, cx, cy", 3},
    {15, "FISHEYE", "fx, fy, cx, cy", 4},
    {16, "EUCM", "fx, fy, cx, cy, alpha, beta", 6},
    {17, "EQUIRECTANGULAR", "w, h", 2},
};

TEST(CameraModels, IdsNamesAndParametersMatchColmap) {
  for (const ColmapModel& colmap : kColmapModels) {
    SCOPED_TRACE(colmap.name);
    ASSERT_TRUE(ExistsCameraModel(colmap.id));
    const auto id = static_cast<CameraModelId>(colmap.id);
    EXPECT_EQ(CameraModelName(id), colmap.name);
    EXPECT_EQ(CameraModelIdFromName(colmap.name), id);
    EXPECT_EQ(CameraModelParamsInfo(id), colmap.params_info);
    EXPECT_EQ(CameraModelNumParams(id), colmap.num_params);
    // The parameter groups are disjoint; with a spherical model's image size they are all.
    std::vector<int> all = CameraModelFocalIdxs(id);
    for (int idx : CameraModelPrincipalPointIdxs(id)) all.push_back(idx);
    for (int idx : CameraModelExtraIdxs(id)) all.push_back(idx);
    EXPECT_EQ(std::set<int>(all.begin(), all.end()).size(), all.size());
    const int metadata = CameraModelProjection(id) == CameraProjection::kSpherical ? 2 : 0;
    EXPECT_EQ(static_cast<int>(all.size()) + metadata, colmap.num_params);
  }
  EXPECT_EQ(std::size(kCameraModelIds), std::size(kColmapModels));
  EXPECT_EQ(kMaxCameraModelNumParams, 16);
  EXPECT_EQ(CameraModelIdFromName("SPHERICAL"), CameraModelId::kInvalid);
  EXPECT_FALSE(ExistsCameraModel(-1));
  EXPECT_FALSE(ExistsCameraModel(18));
  EXPECT_THROW(CameraModelNumParams(static_cast<CameraModelId>(18)), CheckError);
  EXPECT_THROW(CameraModelParamsInfo(CameraModelId::kInvalid), CheckError);
}

TEST(CameraModels, ParameterGroupsAreColmaps) {
  EXPECT_EQ(CameraModelFocalIdxs(CameraModelId::kSimpleRadial), std::vector<int>({0}));
  EXPECT_EQ(CameraModelPrincipalPointIdxs(CameraModelId::kSimpleRadial), std::vector<int>({1, 2}));
  EXPECT_EQ(CameraModelExtraIdxs(CameraModelId::kSimpleRadial), std::vector<int>({3}));
  EXPECT_EQ(CameraModelFocalIdxs(CameraModelId::kOpenCV), std::vector<int>({0, 1}));
  EXPECT_EQ(CameraModelPrincipalPointIdxs(CameraModelId::kOpenCV), std::vector<int>({2, 3}));
  EXPECT_EQ(CameraModelExtraIdxs(CameraModelId::kOpenCV), std::vector<int>({4, 5, 6, 7}));
  EXPECT_EQ(CameraModelExtraIdxs(CameraModelId::kRadTanThinPrismFisheye).size(), 12u);
  EXPECT_TRUE(CameraModelExtraIdxs(CameraModelId::kPinhole).empty());
  EXPECT_TRUE(CameraModelExtraIdxs(CameraModelId::kFisheye).empty());
  EXPECT_TRUE(CameraModelFocalIdxs(CameraModelId::kEquirectangular).empty());
  EXPECT_TRUE(CameraModelExtraIdxs(CameraModelId::kEquirectangular).empty());
  EXPECT_EQ(CameraModelInitialParams(CameraModelId::kRadial, 500, 320, 240),
            std::vector<double>({500, 320, 240, 0, 0}));
  // COLMAP's starting points where zero would stall refinement, and the sphere's size.
  EXPECT_EQ(CameraModelInitialParams(CameraModelId::kFOV, 500, 320, 240),
            std::vector<double>({500, 500, 320, 240, 1e-2}));
  EXPECT_EQ(CameraModelInitialParams(CameraModelId::kEUCM, 500, 320, 240),
            std::vector<double>({500, 500, 320, 240, 0, 1}));
  EXPECT_EQ(CameraModelInitialParams(CameraModelId::kEquirectangular, 0, 1024, 512),
            std::vector<double>({2048, 1024}));
  EXPECT_EQ(CameraModelProjection(CameraModelId::kOpenCVFisheye), CameraProjection::kFisheye);
  EXPECT_EQ(CameraModelProjection(CameraModelId::kFOV), CameraProjection::kPerspective);
}

double AngleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// Every registered model: CamRayFromImg inverts ImgFromCam over the model's field of view,
// a 190-degree one for fisheyes and EUCM and the whole sphere for EQUIRECTANGULAR; and
// CamFromImg is the ray on the plane w = 1.
TEST(CameraModels, EveryModelRoundTripsOverItsFieldOfView) {
  for (const CameraModelId model : kCameraModelIds) {
    SCOPED_TRACE(CameraModelName(model));
    const std::vector<double> params = TestCameraParams(model);
    for (const Eigen::Vector3d& ray : TestRays(model)) {
      SCOPED_TRACE(ray.transpose());
      Eigen::Vector2d xy;
      ASSERT_TRUE(CameraModelProjects(model, params, 3.0 * ray, &xy));
      const Eigen::Vector3d back = CameraModelCamRayFromImg(model, params, xy);
      EXPECT_NEAR(back.norm(), 1.0, 1e-12);
      EXPECT_LT(AngleBetween(back, ray), 1e-9);
      if (ray.z() > 0.1) {
        const Eigen::Vector2d uv = CameraModelCamFromImg(model, params, xy);
        EXPECT_LT((uv - ray.hnormalized()).norm(), 1e-9 * (1.0 + uv.norm()));
      }
    }
  }
}

// And the other way: every pixel of the image maps to a ray that projects back onto it.
TEST(CameraModels, EveryModelRoundTripsOverTheImage) {
  for (const CameraModelId model : kCameraModelIds) {
    SCOPED_TRACE(CameraModelName(model));
    const std::vector<double> params = TestCameraParams(model);
    const bool sphere = model == CameraModelId::kEquirectangular;
    const double width = sphere ? 2048 : 640, height = sphere ? 1024 : 480;
    for (double x = 0.5; x < width; x += width / 9) {
      for (double y = 0.5; y < height; y += height / 7) {
        const Eigen::Vector3d ray = CameraModelCamRayFromImg(model, params, {x, y});
        Eigen::Vector2d xy;
        ASSERT_TRUE(CameraModelProjects(model, params, 2.0 * ray, &xy)) << x << " " << y;
        EXPECT_NEAR(xy.x(), x, 1e-7);
        EXPECT_NEAR(xy.y(), y, 1e-7);
      }
    }
  }
}

// Known values, each from the lens's definition rather than from the code above.
TEST(CameraModels, WideLensesPlaceKnownRaysWhereTheirDefinitionSays) {
  const double f = 300;
  const auto project = [](CameraModelId model, const std::vector<double>& params,
                          const Eigen::Vector3d& point) {
    return CameraModelImgFromCam(model, params, point);
  };
  // Equidistant: radius f theta, also 95 degrees off the axis, behind the image plane.
  const double theta = 95 * M_PI / 180;
  const Eigen::Vector2d behind =
      project(CameraModelId::kSimpleFisheye, {f, 320, 240}, {std::sin(theta), 0, std::cos(theta)});
  EXPECT_NEAR(behind.x(), 320 + f * theta, 1e-9);
  EXPECT_NEAR(behind.y(), 240, 1e-9);
  Eigen::Vector2d unused;
  EXPECT_FALSE(CameraModelProjects(CameraModelId::kPinhole, {f, f, 320, 240},
                                   {std::sin(theta), 0, std::cos(theta)}, &unused));
  // OpenCV's fisheye: radius f theta (1 + k1 theta^2 + ... + k4 theta^8).
  const std::vector<double> opencv_fisheye = {f, f, 320, 240, 0.1, 0.01, 0.001, 0.0001};
  const double t = 0.8;
  const double distorted = t * (1 + 0.1 * std::pow(t, 2) + 0.01 * std::pow(t, 4) +
                                0.001 * std::pow(t, 6) + 0.0001 * std::pow(t, 8));
  EXPECT_NEAR(
      project(CameraModelId::kOpenCVFisheye, opencv_fisheye, {0, std::sin(t), std::cos(t)}).y(),
      240 + f * distorted, 1e-9);
  // EUCM with alpha = 1/2, beta = 1 is the unified (stereographic-like) model: a ray at 90
  // degrees lands at 2 f from the centre. With alpha = 0 it is a pinhole.
  EXPECT_NEAR(project(CameraModelId::kEUCM, {f, f, 320, 240, 0.5, 1.0}, {1, 0, 0}).x(), 320 + 2 * f,
              1e-9);
  EXPECT_NEAR(project(CameraModelId::kEUCM, {f, f, 320, 240, 0.0, 1.0}, {1, 0, 2}).x(), 320 + f / 2,
              1e-9);
  // Division with k = 0 is a pinhole; with k < 0 a pixel's ray is (x, y, 1 + k r^2).
  EXPECT_NEAR(project(CameraModelId::kDivision, {f, f, 320, 240, 0.0}, {1, 0, 2}).x(), 320 + f / 2,
              1e-9);
  const Eigen::Vector3d division_ray = CameraModelCamRayFromImg(
      CameraModelId::kSimpleDivision, {f, 320, 240, -0.5}, {320 + 2 * f, 240});
  EXPECT_LT(AngleBetween(division_ray, Eigen::Vector3d(2, 0, -1)), 1e-12);
  // The sphere: the optical axis at the centre, +x at three quarters of the width, the
  // camera's up (-y) on the top row, the back at the left and right edges.
  const std::vector<double> sphere = {2048, 1024};
  EXPECT_LT(
      (project(CameraModelId::kEquirectangular, sphere, {0, 0, 1}) - Eigen::Vector2d(1024, 512))
          .norm(),
      1e-9);
  EXPECT_LT(
      (project(CameraModelId::kEquirectangular, sphere, {1, 0, 0}) - Eigen::Vector2d(1536, 512))
          .norm(),
      1e-9);
  EXPECT_NEAR(project(CameraModelId::kEquirectangular, sphere, {0, -1, 0.001}).y(), 0, 1);
  EXPECT_NEAR(project(CameraModelId::kEquirectangular, sphere, {-1e-9, 0, -1}).x(), 0, 1e-6);
  // FOV: radius atan(2 r tan(omega / 2)) / omega of the normalised radius r.
  const double omega = 0.9, r = 0.7;
  EXPECT_NEAR(project(CameraModelId::kFOV, {f, f, 320, 240, omega}, {r, 0, 1}).x(),
              320 + f * std::atan(2 * r * std::tan(omega / 2)) / omega, 1e-9);
}

TEST(CameraModels, ThresholdsInPixelsBecomeAnglesPerCamera) {
  EXPECT_DOUBLE_EQ(CameraModelCamFromImgThreshold(CameraModelId::kPinhole, {800, 600, 0, 0}, 7),
                   7.0 / 700);
  EXPECT_DOUBLE_EQ(CameraModelCamFromImgThreshold(CameraModelId::kFisheye, {300, 300, 0, 0}, 3),
                   0.01);
  EXPECT_DOUBLE_EQ(CameraModelCamFromImgThreshold(CameraModelId::kEquirectangular, {2048, 1024}, 4),
                   4 * 2 * M_PI / 2048);
}

// The projection's operations in their order: f u / w + c without distortion (exactly: no
// product in it may fuse with a sum), u / w first and f (u + du) + c with it (to 4 ulps: the
// compiler may fuse these products and sums differently here). The model digests of
// TempleRingTest.KnownIntrinsics check the bits end to end.
TEST(CameraModels, ProjectionIsTheFormula) {
  const double u = 0.3, v = -0.7, w = 1.9;
  {
    const std::vector<double> params = {800, 700, 320, 240};
    const Eigen::Vector2d xy = CameraModelImgFromCam(CameraModelId::kPinhole, params, {u, v, w});
    EXPECT_EQ(xy.x(), 800 * u / w + 320);
    EXPECT_EQ(xy.y(), 700 * v / w + 240);
  }
  {
    const std::vector<double> params = {800, 320, 240, -0.05};
    const Eigen::Vector2d xy =
        CameraModelImgFromCam(CameraModelId::kSimpleRadial, params, {u, v, w});
    const double un = u / w, vn = v / w;
    const double radial = -0.05 * (un * un + vn * vn);
    EXPECT_DOUBLE_EQ(xy.x(), 800 * (un + un * radial) + 320);
    EXPECT_DOUBLE_EQ(xy.y(), 800 * (vn + vn * radial) + 240);
  }
}

TEST(CameraModels, PinholeProjection) {
  const std::vector<double> params = {800, 700, 320, 240};
  const Eigen::Vector2d xy = CameraModelImgFromCam(CameraModelId::kPinhole, params, {1, -2, 4});
  EXPECT_DOUBLE_EQ(xy.x(), 800 * 0.25 + 320);
  EXPECT_DOUBLE_EQ(xy.y(), 700 * -0.5 + 240);
}

}  // namespace
}  // namespace parallax
