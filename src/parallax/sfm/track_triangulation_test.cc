#include "parallax/sfm/track_triangulation.h"

#include <gtest/gtest.h>

#include "parallax/util/eigen_matchers.h"

#include "parallax/scene/synthetic_dataset.h"
#include "parallax/sfm/testing/synthetic_mapper_input.h"

namespace parallax {
namespace {

using test::EigenMatrixNear;

// Triangulation on a ring of exact views (PosedSyntheticScene).
class TrackTriangulationTest : public ::testing::Test {
 protected:
  void Register(image_t first, image_t last) { scene_.Register(first, last); }

  // The true point of a track (through its first element's keypoint in the truth).
  Eigen::Vector3d TruePoint(track_t track_id) const {
    return truth_
        .GetPoint3D(scene_.TruePointOf(input_.correspondence_graph.TrackElements(track_id).front()))
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

  PosedSyntheticScene scene_;
  const Reconstruction& truth_ = scene_.truth;
  const MapperInput& input_ = scene_.input;
  Reconstruction& model_ = scene_.model;
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

TEST_F(TrackTriangulationTest, ATrackWhoseElementsDisagreeHoldsTwoPoints) {
  Register(1, 8);
  track_t track_id = kInvalidTrackId;
  for (track_t t = 0; t < input_.correspondence_graph.NumTracks(); ++t) {
    if (input_.correspondence_graph.TrackElements(t).size() >= 6) {
      track_id = t;
      break;
    }
  }
  ASSERT_NE(track_id, kInvalidTrackId);
  // Two of its keypoints see another point, a unit to the side (a repeated structure).
  const std::vector<TrackElement>& elements = input_.correspondence_graph.TrackElements(track_id);
  const Eigen::Vector3d other = TruePoint(track_id) + Eigen::Vector3d(1, 0, 0);
  for (size_t i = 0; i < 2; ++i) {
    Image& image = model_.GetImage(elements[i].image_id);
    image.points2D[elements[i].point2D_idx].xy =
        model_.GetCamera(image.camera_id).ImgFromCam(image.cam_from_world * other);
  }
  TrackedReconstruction tracked(input_.correspondence_graph, &model_);
  const point3D_t first = TriangulateTrack(TrackTriangulationOptions(), track_id, &tracked);
  const point3D_t second = TriangulateTrack(TrackTriangulationOptions(), track_id, &tracked);
  ASSERT_NE(first, kInvalidPoint3DId);
  ASSERT_NE(second, kInvalidPoint3DId);
  EXPECT_THAT(model_.GetPoint3D(first).xyz, EigenMatrixNear(TruePoint(track_id), 1e-9));
  EXPECT_EQ(model_.GetPoint3D(first).track.Length(), elements.size() - 2);
  EXPECT_THAT(model_.GetPoint3D(second).xyz, EigenMatrixNear(other, 1e-9));
  EXPECT_EQ(model_.GetPoint3D(second).track.Length(), 2u);
  EXPECT_EQ(tracked.PointsOfTrack(track_id).size(), 2u);
  // Every element has its point now: nothing is left for a third.
  EXPECT_EQ(TriangulateTrack(TrackTriangulationOptions(), track_id, &tracked), kInvalidPoint3DId);
}

TEST(TwoViewTracks, AreLeftWithoutAPointUnlessAsked) {
  PosedSyntheticScene scene;
  scene.Register(1, 3);
  // Only the true matches of images 1 and 2, and one keypoint of image 2 matched on into
  // image 3: every track but that one is two-view.
  const CorrespondenceGraph& full = scene.input.correspondence_graph;
  CorrespondenceGraph graph;
  for (const auto& [image_id, image] : scene.input.images) {
    graph.AddImage(image_id, image.points2D.size());
  }
  graph.AddCorrespondences(1, 2, full.PairMatches().at(ImagePairToPairId(1, 2)));
  const FeatureMatch onward = full.PairMatches().at(ImagePairToPairId(2, 3)).front();
  graph.AddCorrespondences(2, 3, {onward});
  graph.Finalize();
  ASSERT_GT(graph.NumTracks(), 10u);

  TrackedReconstruction tracked(graph, &scene.model);
  TrackTriangulationOptions keep_two_view;
  keep_two_view.ignore_two_view_tracks = false;
  const track_t longer = graph.TrackOf(2, onward.point2D_idx1);
  for (track_t track_id = 0; track_id < graph.NumTracks(); ++track_id) {
    if (track_id == longer) continue;
    ASSERT_TRUE(graph.IsTwoViewTrack(track_id));
    EXPECT_EQ(TriangulateTrack(TrackTriangulationOptions(), track_id, &tracked), kInvalidPoint3DId);
    EXPECT_NE(TriangulateTrack(keep_two_view, track_id, &tracked), kInvalidPoint3DId);
  }
  // Seen by three images: not two-view.
  ASSERT_NE(longer, kInvalidTrackId);
  EXPECT_FALSE(graph.IsTwoViewTrack(longer));
}

}  // namespace
}  // namespace parallax
