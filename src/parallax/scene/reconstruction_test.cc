#include "parallax/scene/reconstruction.h"

#include <gtest/gtest.h>

#include "parallax/util/check.h"

namespace parallax {
namespace {

Reconstruction TwoImageScene() {
  Reconstruction reconstruction;
  reconstruction.AddCamera(Camera::Create(1, CameraModelId::kPinhole, 500, 640, 480));
  for (image_t id = 1; id <= 3; ++id) {
    Image image;
    image.image_id = id;
    image.camera_id = 1;
    image.name = "image" + std::to_string(id);
    image.cam_from_world.translation = Eigen::Vector3d(-0.5 * id, 0, 0);
    image.points2D.resize(4);
    reconstruction.AddImage(image);
    reconstruction.RegisterImage(id);
  }
  return reconstruction;
}

TEST(Reconstruction, ObservationsStayConsistent) {
  Reconstruction reconstruction = TwoImageScene();
  Track track;
  track.AddElement(1, 0);
  track.AddElement(2, 1);
  const point3D_t id = reconstruction.AddPoint3D(Eigen::Vector3d(0, 0, 5), track);
  EXPECT_EQ(reconstruction.GetImage(1).num_points3D, 1u);
  EXPECT_EQ(reconstruction.GetImage(2).points2D[1].point3D_id, id);
  reconstruction.AddObservation(id, {3, 2});
  EXPECT_EQ(reconstruction.GetPoint3D(id).track.Length(), 3u);
  EXPECT_THROW(reconstruction.AddObservation(id, {3, 2}), CheckError);
  reconstruction.DeleteObservation(3, 2);
  EXPECT_EQ(reconstruction.GetPoint3D(id).track.Length(), 2u);
  // Deleting one of the last two observations removes the point.
  reconstruction.DeleteObservation(1, 0);
  EXPECT_FALSE(reconstruction.ExistsPoint3D(id));
  EXPECT_EQ(reconstruction.GetImage(2).num_points3D, 0u);
  EXPECT_FALSE(reconstruction.GetImage(2).points2D[1].HasPoint3D());
}

TEST(Reconstruction, MergeAndDeregister) {
  Reconstruction reconstruction = TwoImageScene();
  Track track1, track2;
  track1.AddElement(1, 0);
  track1.AddElement(2, 0);
  track2.AddElement(3, 0);
  track2.AddElement(2, 3);
  const point3D_t a = reconstruction.AddPoint3D(Eigen::Vector3d(0, 0, 4), track1);
  const point3D_t b = reconstruction.AddPoint3D(Eigen::Vector3d(0, 0, 6), track2);
  const point3D_t merged = reconstruction.MergePoints3D(a, b);
  EXPECT_EQ(reconstruction.NumPoints3D(), 1u);
  EXPECT_EQ(reconstruction.GetPoint3D(merged).track.Length(), 4u);
  EXPECT_NEAR(reconstruction.GetPoint3D(merged).xyz.z(), 5.0, 1e-12);
  reconstruction.DeRegisterImage(2);
  EXPECT_FALSE(reconstruction.IsImageRegistered(2));
  EXPECT_EQ(reconstruction.GetPoint3D(merged).track.Length(), 2u);
  EXPECT_EQ(reconstruction.NumRegImages(), 2u);
}

TEST(Reconstruction, ReprojectionErrorAndTransform) {
  Reconstruction reconstruction = TwoImageScene();
  const Eigen::Vector3d xyz(0.2, -0.1, 5);
  for (image_t id = 1; id <= 2; ++id) {
    Image& image = reconstruction.GetImage(id);
    image.points2D[0].xy =
        reconstruction.GetCamera(1).ImgFromCam(image.cam_from_world * xyz) + Eigen::Vector2d(3, 4);
  }
  Track track;
  track.AddElement(1, 0);
  track.AddElement(2, 0);
  reconstruction.AddPoint3D(xyz, track);
  EXPECT_NEAR(reconstruction.UpdatePointErrors(), 5.0, 1e-9);
  reconstruction.Transform(Sim3d(3.0, Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY())),
                                 Eigen::Vector3d(1, 2, 3)));
  EXPECT_NEAR(reconstruction.UpdatePointErrors(), 5.0, 1e-9);
}

}  // namespace
}  // namespace parallax
