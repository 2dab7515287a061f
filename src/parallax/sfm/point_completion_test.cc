#include "parallax/sfm/point_completion.h"

#include <gtest/gtest.h>

#include <set>

#include "parallax/util/eigen_matchers.h"

#include "parallax/sfm/retriangulation.h"
#include "parallax/sfm/testing/synthetic_mapper_input.h"

namespace parallax {
namespace {

using test::EigenMatrixNear;

// COLMAP's values (completion, merging and re-triangulation are off by default).
TrackTriangulationOptions Enabled() {
  TrackTriangulationOptions options;
  options.complete_max_transitivity = 5;
  options.merge_points = true;
  options.retriangulate_min_ratio = 0.2;
  return options;
}

// Completion and merging on a ring of exact views, all registered.
class PointCompletionTest : public ::testing::Test {
 protected:
  void SetUp() override { scene_.Register(1, 8); }

  // A point on the first `count` elements of the track at its true position.
  point3D_t AddPointOn(const std::vector<TrackElement>& elements, size_t begin, size_t end,
                       TrackedReconstruction* tracked) {
    Track track;
    track.elements.assign(elements.begin() + begin, elements.begin() + end);
    return tracked->AddPoint3D(TruePoint(elements.front()), track);
  }

  Eigen::Vector3d TruePoint(const TrackElement& element) const {
    return scene_.truth.GetPoint3D(scene_.TruePointOf(element)).xyz;
  }

  // Every point holds keypoints of one true point only.
  void ExpectEveryPointPure() const {
    for (const auto& [point3D_id, point] : scene_.model.Points3D()) {
      std::set<point3D_t> truths;
      for (const TrackElement& element : point.track.elements) {
        truths.insert(scene_.TruePointOf(element));
      }
      EXPECT_EQ(truths.size(), 1u) << "point " << point3D_id << " mixes true points";
    }
  }

  PosedSyntheticScene scene_;
  const CorrespondenceGraph& graph_ = scene_.input.correspondence_graph;
};

TEST_F(PointCompletionTest, CompletionAndMergingRecoverTracksSplitOnPurpose) {
  TrackedReconstruction tracked(graph_, &scene_.model);
  // Every track of four or more views becomes two points of two views each; the rest of
  // its views belong to neither.
  size_t num_split = 0;
  for (track_t track_id = 0; track_id < graph_.NumTracks(); ++track_id) {
    const std::vector<TrackElement>& elements = graph_.TrackElements(track_id);
    if (elements.size() < 4) continue;
    AddPointOn(elements, 0, 2, &tracked);
    AddPointOn(elements, 2, 4, &tracked);
    ++num_split;
  }
  ASSERT_GT(num_split, 50u);
  ASSERT_EQ(scene_.model.NumPoints3D(), 2 * num_split);

  EXPECT_GT(CompleteAndMergeAllPoints(Enabled(), &tracked), 0u);
  EXPECT_EQ(scene_.model.NumPoints3D(), num_split);
  for (track_t track_id = 0; track_id < graph_.NumTracks(); ++track_id) {
    const std::vector<TrackElement>& elements = graph_.TrackElements(track_id);
    if (elements.size() < 4) continue;
    const std::vector<point3D_t> points = tracked.PointsOfTrack(track_id);
    ASSERT_EQ(points.size(), 1u) << "track " << track_id;
    const Point3D& point = scene_.model.GetPoint3D(points.front());
    EXPECT_EQ(point.track.Length(), elements.size()) << "track " << track_id;
    EXPECT_THAT(point.xyz, EigenMatrixNear(TruePoint(elements.front()), 1e-9));
  }
  ExpectEveryPointPure();
}

TEST_F(PointCompletionTest, AnObservationFarFromItsPointIsNotAdded) {
  track_t track_id = 0;
  while (graph_.TrackElements(track_id).size() < 4) ++track_id;
  const std::vector<TrackElement>& elements = graph_.TrackElements(track_id);
  const TrackElement moved = elements[3];
  scene_.model.GetImage(moved.image_id).points2D[moved.point2D_idx].xy += Eigen::Vector2d(25, -18);
  TrackedReconstruction tracked(graph_, &scene_.model);
  const point3D_t point3D_id = AddPointOn(elements, 0, 2, &tracked);
  EXPECT_EQ(CompletePoint(Enabled(), point3D_id, &tracked), elements.size() - 3);
  const Point3D& point = scene_.model.GetPoint3D(point3D_id);
  EXPECT_EQ(point.track.Length(), elements.size() - 1);
  for (const TrackElement& element : point.track.elements) EXPECT_FALSE(element == moved);
  EXPECT_FALSE(scene_.model.GetImage(moved.image_id).points2D[moved.point2D_idx].HasPoint3D());
}

TEST(PointMerging, TwoDifferentPointsAreNeverMerged) {
  PosedSyntheticScene scene;
  scene.Register(1, 8);
  // The true matches, plus wrong ones: the first keypoint of image 1 that sees a point is
  // matched with a keypoint of image 2 that sees another, for many such pairs.
  CorrespondenceGraph graph;
  for (const auto& [image_id, image] : scene.input.images) {
    graph.AddImage(image_id, image.points2D.size());
  }
  for (const auto& [pair_id, matches] : scene.input.correspondence_graph.PairMatches()) {
    const auto [image_id1, image_id2] = PairIdToImagePair(pair_id);
    graph.AddCorrespondences(image_id1, image_id2, matches);
  }
  const FeatureMatches& true_matches =
      scene.input.correspondence_graph.PairMatches().at(ImagePairToPairId(1, 2));
  FeatureMatches wrong;
  for (size_t i = 0; i + 1 < true_matches.size(); i += 2) {
    wrong.push_back({true_matches[i].point2D_idx1, true_matches[i + 1].point2D_idx2});
  }
  ASSERT_GT(wrong.size(), 20u);
  graph.AddCorrespondences(1, 2, wrong);
  graph.Finalize();

  TrackedReconstruction tracked(graph, &scene.model);
  const TrackTriangulationOptions options = Enabled();
  CompleteAllTracks(options, &tracked);
  const size_t num_points = scene.model.NumPoints3D();
  ASSERT_GT(num_points, 100u);
  CompleteAndMergeAllPoints(options, &tracked);
  EXPECT_EQ(scene.model.NumPoints3D(), num_points);
  for (const auto& [point3D_id, point] : scene.model.Points3D()) {
    std::set<point3D_t> truths;
    for (const TrackElement& element : point.track.elements) {
      truths.insert(scene.TruePointOf(element));
    }
    EXPECT_EQ(truths.size(), 1u) << "point " << point3D_id << " mixes true points";
  }
}

TEST_F(PointCompletionTest, UnderReconstructedPairsAreRetriangulatedOnceWithTheRelaxedAngle) {
  TrackedReconstruction tracked(graph_, &scene_.model);
  // Too strict an angle leaves the pairs without points.
  TrackTriangulationOptions options = Enabled();
  options.min_angle_deg = 179;
  CompleteAllTracks(options, &tracked);
  const size_t num_before = scene_.model.NumObservations();
  ASSERT_EQ(num_before, 0u);
  options.retriangulate_min_angle_deg = 1.5;
  const size_t num_added = RetriangulateUnderReconstructedPairs(options, &tracked);
  EXPECT_GT(num_added, 0u);
  EXPECT_EQ(scene_.model.NumObservations(), num_before + num_added);
  ExpectEveryPointPure();
  // Each pair gets one chance.
  EXPECT_EQ(RetriangulateUnderReconstructedPairs(options, &tracked), 0u);
}

}  // namespace
}  // namespace parallax
