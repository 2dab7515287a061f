#include "parallax/geometry/camera_models.h"

#include <gtest/gtest.h>

#include <set>

#include "parallax/util/check.h"

namespace parallax {
namespace {

std::vector<double> TestParams(CameraModelId id) {
  std::vector<double> params = CameraModelInitialParams(id, 800, 320, 240);
  const auto extra = CameraModelExtraIdxs(id);
  const double values[] = {-0.08, 0.01, 0.001, -0.002};
  for (size_t i = 0; i < extra.size(); ++i) params[extra[i]] = values[i];
  const auto focal = CameraModelFocalIdxs(id);
  if (focal.size() == 2) params[focal[1]] = 790;
  return params;
}

// COLMAP's table (src/colmap/sensor/models.h): id, name, parameter names.
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
    // The parameter groups partition the parameters.
    std::vector<int> all = CameraModelFocalIdxs(id);
    for (int idx : CameraModelPrincipalPointIdxs(id)) all.push_back(idx);
    for (int idx : CameraModelExtraIdxs(id)) all.push_back(idx);
    EXPECT_EQ(std::set<int>(all.begin(), all.end()).size(), all.size());
    EXPECT_EQ(static_cast<int>(all.size()), colmap.num_params);
  }
  EXPECT_EQ(std::size(kCameraModelIds), std::size(kColmapModels));
  EXPECT_EQ(CameraModelIdFromName("FISHEYE"), CameraModelId::kInvalid);
  EXPECT_FALSE(ExistsCameraModel(-1));
  EXPECT_FALSE(ExistsCameraModel(17));
  EXPECT_THROW(CameraModelNumParams(static_cast<CameraModelId>(17)), CheckError);
  EXPECT_THROW(CameraModelParamsInfo(CameraModelId::kInvalid), CheckError);
}

TEST(CameraModels, ParameterGroupsAreColmaps) {
  EXPECT_EQ(CameraModelFocalIdxs(CameraModelId::kSimpleRadial), std::vector<int>({0}));
  EXPECT_EQ(CameraModelPrincipalPointIdxs(CameraModelId::kSimpleRadial), std::vector<int>({1, 2}));
  EXPECT_EQ(CameraModelExtraIdxs(CameraModelId::kSimpleRadial), std::vector<int>({3}));
  EXPECT_EQ(CameraModelFocalIdxs(CameraModelId::kOpenCV), std::vector<int>({0, 1}));
  EXPECT_EQ(CameraModelPrincipalPointIdxs(CameraModelId::kOpenCV), std::vector<int>({2, 3}));
  EXPECT_EQ(CameraModelExtraIdxs(CameraModelId::kOpenCV), std::vector<int>({4, 5, 6, 7}));
  EXPECT_TRUE(CameraModelExtraIdxs(CameraModelId::kPinhole).empty());
  EXPECT_EQ(CameraModelInitialParams(CameraModelId::kRadial, 500, 320, 240),
            std::vector<double>({500, 320, 240, 0, 0}));
}

// Every registered model: CamFromImg inverts ImgFromCam over the image.
TEST(CameraModels, EveryModelRoundTrips) {
  for (const CameraModelId model : kCameraModelIds) {
    SCOPED_TRACE(CameraModelName(model));
    const auto params = TestParams(model);
    for (double u = -0.35; u <= 0.35; u += 0.1) {
      for (double v = -0.25; v <= 0.25; v += 0.1) {
        const Eigen::Vector3d point(2 * u, 2 * v, 2);
        const Eigen::Vector2d xy = CameraModelImgFromCam(model, params, point);
        const Eigen::Vector2d uv = CameraModelCamFromImg(model, params, xy);
        EXPECT_NEAR(uv.x(), u, 1e-10);
        EXPECT_NEAR(uv.y(), v, 1e-10);
      }
    }
  }
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
