#include "parallax/geometry/camera_models.h"

#include <gtest/gtest.h>

#include "parallax/util/check.h"

namespace parallax {
namespace {

std::vector<double> TestParams(CameraModelId id) {
  std::vector<double> params = CameraModelInitialParams(id, 800, 320, 240);
  const auto extra = CameraModelExtraIdxs(id);
  const double values[] = {-0.08, 0.01, 0.001, -0.002};
  for (size_t i = 0; i < extra.size(); ++i) params[extra[i]] = values[i];
  if (id == CameraModelId::kPinhole || id == CameraModelId::kOpenCV) params[1] = 790;
  return params;
}

TEST(CameraModels, NamesAndParamCountsMatchColmap) {
  EXPECT_EQ(CameraModelName(CameraModelId::kSimplePinhole), "SIMPLE_PINHOLE");
  EXPECT_EQ(CameraModelName(CameraModelId::kOpenCV), "OPENCV");
  EXPECT_EQ(CameraModelIdFromName("SIMPLE_RADIAL"), CameraModelId::kSimpleRadial);
  EXPECT_EQ(CameraModelIdFromName("FISHEYE"), CameraModelId::kInvalid);
  EXPECT_EQ(CameraModelNumParams(CameraModelId::kRadial), 5);
  EXPECT_EQ(CameraModelNumParams(CameraModelId::kOpenCV), 8);
  EXPECT_THROW(CameraModelNumParams(static_cast<CameraModelId>(17)), CheckError);
}

TEST(CameraModels, CamFromImgInvertsImgFromCam) {
  for (int id = 0; id <= 4; ++id) {
    const auto model = static_cast<CameraModelId>(id);
    const auto params = TestParams(model);
    for (double u = -0.35; u <= 0.35; u += 0.1) {
      for (double v = -0.25; v <= 0.25; v += 0.1) {
        const Eigen::Vector3d point(2 * u, 2 * v, 2);
        const Eigen::Vector2d xy = CameraModelImgFromCam(model, params, point);
        const Eigen::Vector2d uv = CameraModelCamFromImg(model, params, xy);
        EXPECT_NEAR(uv.x(), u, 1e-10) << CameraModelName(model);
        EXPECT_NEAR(uv.y(), v, 1e-10) << CameraModelName(model);
      }
    }
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
