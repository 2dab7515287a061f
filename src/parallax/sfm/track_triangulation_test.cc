#include "parallax/sfm/track_triangulation.h"

#include <gtest/gtest.h>

#include "parallax/util/eigen_matchers.h"

#include "parallax/scene/synthetic_dataset.h"
#include "parallax/sfm/testing/synthetic_mapper_input.h"

namespace parallax {
namespace {

using test::EigenMatrixNear;

// A ring of exact views and the mapper's input for it; `model` holds every image with its
// true pose, the first `num_registered` registered, and no points yet.
class TrackTriangulationTest : public ::testing::Test {
 protected:
  void SetUp() override {
    SyntheticDatasetOptions options;
    options.num_images = 8;
    options.num_points3D = 300;
    options.min_track_length = 3;
    options.seed = 21;
    SynthesizeDataset(options, &truth_);
    input_ = InputFromTruth(truth_);
    for (const auto& [camera_id, camera] : truth_.Cameras()) model_.AddCamera(camera);
    for (const auto& [image_id, image] : input_.images) {
      Image posed = image;
      posed.cam_from_world = truth_.GetImage(image_id).cam_from_world;
      model_.AddImage(posed);
    }
  }

  void Register(image_t first, image_t last) {
    for (image_t image_id = first; image_id <= last; ++image_id) model_.RegisterImage(image_id);
  }

  // The true point of a track (through its first element's keypoint in the truth).
  Eigen::Vector3d TruePoint(track_t track_id) const {
    const TrackElement& element = input_.correspondence_graph.TrackElements(track_id).front();
    return truth_
        .GetPoint3D(truth_.GetImage(element.image_id).points2D[element.point2D_idx].point3D_id)
        .xyz;
  }

  // A track with elements in at least `min_registered` of images 1..4.
  track_t TrackSeenInFirstFour(size_t min_registered) const {
    for (track_t track_id = 0; track_id < input_.correspondence_graph.NumTracks(); ++track_id) {
      size_t count = 0;
      for (const TrackElement& element : input_.correspondence_graph.TrackElements(track_id)) {
        count += element.image_id <= 4;
      }
      if (count >= min_registered) return track_id;
    }
    ADD_FAILURE() << "no track";
    return 0;
  }

  Reconstruction truth_;
  MapperInput input_;
  Reconstruction model_;
};

TEST_F(TrackTriangulationTest, ExactViewsGiveTheTruePoint) {
  Register(1, 4);
  TrackedReconstruction tracked(input_.correspondence_graph, &model_);
  const track_t track_id = TrackSeenInFirstFour(3);
  const point3D_t point3D_id = TriangulateTrack(TrackTriangulationOptions(), track_id, &tracked);
  ASSERT_NE(point3D_id, kInvalidPoint3DId);
  EXPECT_EQ(tracked.PointOfTrack(track_id), point3D_id);
  EXPECT_THAT(model_.GetPoint3D(point3D_id).xyz, EigenMatrixNear(TruePoint(track_id), 1e-9));
  // Only registered views join the point.
  for (const TrackElement& element : model_.GetPoint3D(point3D_id).track.elements) {
    EXPECT_LE(element.image_id, 4u);
  }
}

TEST_F(TrackTriangulationTest, AViewThatDisagreesIsLeftOut) {
  Register(1, 4);
  const track_t track_id = TrackSeenInFirstFour(4);
  const TrackElement moved = input_.correspondence_graph.TrackElements(track_id).front();
  model_.GetImage(moved.image_id).points2D[moved.point2D_idx].xy += Eigen::Vector2d(25, -18);
  TrackedReconstruction tracked(input_.correspondence_graph, &model_);
  const point3D_t point3D_id = TriangulateTrack(TrackTriangulationOptions(), track_id, &tracked);
  ASSERT_NE(point3D_id, kInvalidPoint3DId);
  const Point3D& point = model_.GetPoint3D(point3D_id);
  EXPECT_EQ(point.track.Length(), 3u);
  for (const TrackElement& element : point.track.elements) EXPECT_FALSE(element == moved);
  EXPECT_THAT(point.xyz, EigenMatrixNear(TruePoint(track_id), 1e-9));
}

TEST_F(TrackTriangulationTest, TooSmallAnAngleGivesNoPoint) {
  Register(1, 4);
  TrackedReconstruction tracked(input_.correspondence_graph, &model_);
  TrackTriangulationOptions options;
  options.min_angle_deg = 120;  // The ring's views are at most 3 x 45 degrees apart.
  EXPECT_EQ(TriangulateTrack(options, TrackSeenInFirstFour(3), &tracked), kInvalidPoint3DId);
  EXPECT_EQ(model_.NumPoints3D(), 0u);
}

TEST_F(TrackTriangulationTest, NewlyRegisteredViewsContinueTheirTracks) {
  Register(1, 3);
  TrackedReconstruction tracked(input_.correspondence_graph, &model_);
  const size_t num_first = CompleteAllTracks(TrackTriangulationOptions(), &tracked);
  EXPECT_EQ(num_first, model_.NumObservations());
  const size_t num_points = model_.NumPoints3D();
  EXPECT_GT(num_points, 50u);

  Register(4, 4);
  const size_t num_added = TriangulateImage(TrackTriangulationOptions(), 4, &tracked);
  EXPECT_EQ(model_.NumObservations(), num_first + num_added);
  // Every track image 4 shares with a triangulated one now has its observation.
  size_t num_seen = 0;
  for (const Point2D& point2D : model_.GetImage(4).points2D) num_seen += point2D.HasPoint3D();
  EXPECT_GT(num_seen, 0u);
  for (const auto& [point3D_id, point] : model_.Points3D()) {
    EXPECT_LT(model_.ReprojectionError(point.track.elements.front().image_id,
                                       point.track.elements.front().point2D_idx),
              1e-6);
  }
  // Nothing is left to do.
  EXPECT_EQ(CompleteAllTracks(TrackTriangulationOptions(), &tracked), 0u);
}

}  // namespace
}  // namespace parallax
