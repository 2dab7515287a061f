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

TEST(Reconstruction, TrackLengthHistogramCountsPointsByImagesPerPoint) {
  Reconstruction reconstruction = TwoImageScene();
  EXPECT_TRUE(reconstruction.ComputeTrackLengthHistogram().empty());
  for (point2D_t idx = 0; idx < 3; ++idx) {
    Track track;
    track.AddElement(1, idx);
    track.AddElement(2, idx);
    if (idx == 0) track.AddElement(3, idx);
    reconstruction.AddPoint3D(Eigen::Vector3d(0, 0, 5), track);
  }
  const std::map<size_t, size_t> expected = {{2, 2}, {3, 1}};
  EXPECT_EQ(reconstruction.ComputeTrackLengthHistogram(), expected);
  EXPECT_DOUBLE_EQ(reconstruction.ComputeMeanTrackLength(), 7.0 / 3.0);
}

// Lookups by id stay right through additions, deletions, copies, moves, preset ids (small and
// far beyond the points added) and many points (the index grows).
TEST(Reconstruction, PointLookupsByIdSurviveEditsAndCopies) {
  Reconstruction reconstruction = TwoImageScene();
  std::vector<point3D_t> ids;
  for (point2D_t idx = 0; idx < 4; ++idx) {
    Track track;
    track.AddElement(1, idx);
    track.AddElement(2, idx);
    ids.push_back(reconstruction.AddPoint3D(Eigen::Vector3d(idx, 0, 5), track));
  }
  reconstruction.DeletePoint3D(ids[1]);
  Point3D far;
  far.xyz = Eigen::Vector3d(7, 7, 7);
  far.track.AddElement(3, 0);
  far.track.AddElement(2, 1);
  const point3D_t far_id = 4000000000u;
  reconstruction.AddPoint3DWithId(far_id, far);
  Point3D near = far;
  near.xyz = Eigen::Vector3d(8, 8, 8);
  near.track.elements = {{3, 1}, {1, 1}};
  reconstruction.AddPoint3DWithId(100, near);

  const auto expect_points = [&](const Reconstruction& model) {
    EXPECT_TRUE(model.ExistsPoint3D(ids[0]));
    EXPECT_FALSE(model.ExistsPoint3D(ids[1]));
    EXPECT_EQ(model.GetPoint3D(ids[3]).xyz.x(), 3.0);
    EXPECT_EQ(model.GetPoint3D(far_id).xyz.x(), 7.0);
    EXPECT_EQ(model.GetPoint3D(100).xyz.x(), 8.0);
    EXPECT_FALSE(model.ExistsPoint3D(99));
    EXPECT_FALSE(model.ExistsPoint3D(far_id - 1));
    EXPECT_THROW(model.GetPoint3D(ids[1]), CheckError);
    // Ids handed out after a preset one continue above it.
    EXPECT_EQ(model.NumPoints3D(), 5u);
  };
  expect_points(reconstruction);
  Reconstruction copy = reconstruction;
  reconstruction.DeletePoint3D(ids[0]);  // The copy keeps its own.
  expect_points(copy);
  Reconstruction assigned;
  assigned = copy;
  expect_points(assigned);
  const Reconstruction moved = std::move(copy);
  expect_points(moved);
  // The copy's lookups point into the copy: editing it leaves the original alone.
  assigned.GetPoint3D(ids[3]).xyz.x() = -1;
  EXPECT_EQ(moved.GetPoint3D(ids[3]).xyz.x(), 3.0);

  // Thousands of points: the index grows past its first sizes.
  Reconstruction many = TwoImageScene();
  for (image_t id = 4; id <= 3000; ++id) {
    Image image;
    image.image_id = id;
    image.camera_id = 1;
    image.name = "image" + std::to_string(id);
    image.points2D.resize(1);
    many.AddImage(image);
  }
  std::vector<point3D_t> many_ids;
  for (image_t id = 4; id < 3000; id += 2) {
    Track track;
    track.AddElement(id, 0);
    track.AddElement(id + 1, 0);
    many_ids.push_back(many.AddPoint3D(Eigen::Vector3d(id, 0, 1), track));
  }
  for (size_t i = 0; i < many_ids.size(); i += 3) many.DeletePoint3D(many_ids[i]);
  for (size_t i = 0; i < many_ids.size(); ++i) {
    ASSERT_EQ(many.ExistsPoint3D(many_ids[i]), i % 3 != 0) << i;
    if (i % 3 != 0) {
      EXPECT_EQ(many.GetPoint3D(many_ids[i]).xyz.x(), 4.0 + 2 * i);
    }
  }
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
  reconstruction.Transform(
      Sim3d(3.0, Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY())),
            Eigen::Vector3d(1, 2, 3)));
  EXPECT_NEAR(reconstruction.UpdatePointErrors(), 5.0, 1e-9);
}

}  // namespace
}  // namespace parallax
