#include "parallax/scene/principal_plane.h"

#include <gtest/gtest.h>

#include <random>

#include "parallax/geometry/rigid3.h"

namespace parallax {
namespace {

// Points on a tilted, offset plane and cameras on one side of it: afterwards the points lie
// on z = 0 around the origin and the cameras above.
TEST(PrincipalPlaneAlignment, LaysThePointsOnZeroWithTheCamerasAbove) {
  const Eigen::Quaterniond tilt(Eigen::AngleAxisd(0.8, Eigen::Vector3d(1, -2, 0.5).normalized()));
  const Eigen::Vector3d offset(3, -4, 7);
  Reconstruction model;
  std::mt19937 engine(4);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (int i = 0; i < 200; ++i) {
    // Three times wider in x than in y, flat in z.
    const Eigen::Vector3d local(3 * uniform(engine), uniform(engine), 0.0);
    model.AddPoint3D(tilt * local + offset, Track());
  }
  model.AddCamera(Camera::Create(1, CameraModelId::kSimplePinhole, 100, 64, 48));
  for (image_t image_id = 1; image_id <= 3; ++image_id) {
    Image image;
    image.image_id = image_id;
    image.camera_id = 1;
    image.name = "image" + std::to_string(image_id);
    // Centres 5 above the plane (local +z, then tilted), looking anywhere.
    const Eigen::Vector3d center = tilt * Eigen::Vector3d(image_id, 0, 5) + offset;
    image.cam_from_world = Rigid3d(Eigen::Quaterniond::Identity(), -center);
    model.AddImage(image);
    model.RegisterImage(image_id);
  }
  const Sim3d aligned_from_model = PrincipalPlaneAlignment(model);
  EXPECT_DOUBLE_EQ(aligned_from_model.scale, 1.0);
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& [point3D_id, point] : model.Points3D()) {
    const Eigen::Vector3d aligned = aligned_from_model * point.xyz;
    EXPECT_NEAR(aligned.z(), 0.0, 1e-9);
    centroid += aligned / model.NumPoints3D();
  }
  EXPECT_LT(centroid.norm(), 1e-9);
  for (const image_t image_id : model.RegImageIds()) {
    const Eigen::Vector3d center = aligned_from_model * model.GetImage(image_id).ProjectionCenter();
    EXPECT_NEAR(center.z(), 5.0, 1e-9) << image_id;
  }
  // The widest spread along x: about the local x axis (either way round; the sample is finite).
  const Eigen::Vector3d local_x = aligned_from_model.rotation * (tilt * Eigen::Vector3d::UnitX());
  EXPECT_GT(std::abs(local_x.x()), 0.99);
}

TEST(PrincipalPlaneAlignment, FewerThanThreePointsLeaveTheModelAsItIs) {
  Reconstruction model;
  model.AddPoint3D(Eigen::Vector3d(1, 2, 3), Track());
  const Sim3d identity = PrincipalPlaneAlignment(model);
  EXPECT_EQ(identity.scale, 1.0);
  EXPECT_TRUE(identity.translation.isZero());
  EXPECT_TRUE(identity.rotation.coeffs().isApprox(Eigen::Quaterniond::Identity().coeffs()));
}

}  // namespace
}  // namespace parallax
