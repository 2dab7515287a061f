#include "parallax/sfm/tracked_reconstruction.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "parallax/sfm/testing/synthetic_mapper_input.h"

namespace parallax {
namespace {

bool Contains(const std::vector<track_t>& tracks, track_t track_id) {
  return std::find(tracks.begin(), tracks.end(), track_id) != tracks.end();
}

// Two tracks with elements in registered images 1..3 (the first two of `a`, one of `b`).
class ChangedTracksTest : public ::testing::Test {
 protected:
  void SetUp() override {
    scene_.Register(1, 8);
    const CorrespondenceGraph& graph = scene_.input.correspondence_graph;
    for (track_t track_id = 0; track_id < graph.NumTracks(); ++track_id) {
      std::vector<TrackElement> in_first_three;
      for (const TrackElement& element : graph.TrackElements(track_id)) {
        if (element.image_id <= 3) in_first_three.push_back(element);
      }
      if (in_first_three.size() < 3) continue;
      if (track_a_ == kInvalidTrackId) {
        track_a_ = track_id;
        a_ = in_first_three;
      } else {
        track_b_ = track_id;
        b_ = in_first_three;
        break;
      }
    }
    ASSERT_NE(track_b_, kInvalidTrackId);
  }

  PosedSyntheticScene scene_;
  track_t track_a_ = kInvalidTrackId;
  track_t track_b_ = kInvalidTrackId;
  std::vector<TrackElement> a_, b_;
};

TEST_F(ChangedTracksTest, FirstCallGivesEveryTrackThenOnlyTheChangedOnes) {
  TrackedReconstruction tracked(scene_.input.correspondence_graph, &scene_.model);
  EXPECT_EQ(tracked.TakeChangedTracks().size(), scene_.input.correspondence_graph.NumTracks());
  EXPECT_TRUE(tracked.TakeChangedTracks().empty());
  Track track;
  track.AddElement(a_[0].image_id, a_[0].point2D_idx);
  track.AddElement(a_[1].image_id, a_[1].point2D_idx);
  const point3D_t point3D_id = tracked.AddPoint3D(Eigen::Vector3d(0, 0, 5), track);
  std::vector<track_t> changed = tracked.TakeChangedTracks();
  EXPECT_TRUE(Contains(changed, track_a_));
  EXPECT_FALSE(Contains(changed, track_b_));
  scene_.model.DeletePoint3D(point3D_id);  // Behind TrackedReconstruction's back.
  changed = tracked.TakeChangedTracks();
  EXPECT_TRUE(Contains(changed, track_a_));
  EXPECT_EQ(tracked.PointOfTrack(track_a_), kInvalidPoint3DId);
}

// The point holds one element of track a and two of track b. Filtering takes a's element
// away while the point lives on, so a still reads the point; when the point goes, its
// remaining elements lead only to b, and a must change all the same.
TEST_F(ChangedTracksTest, ATrackWhoseElementLeftItsPointChangesWhenThePointGoes) {
  TrackedReconstruction tracked(scene_.input.correspondence_graph, &scene_.model);
  tracked.TakeChangedTracks();
  Track track;
  track.AddElement(a_[0].image_id, a_[0].point2D_idx);
  for (int i = 0; i < 2; ++i) track.AddElement(b_[i].image_id, b_[i].point2D_idx);
  const point3D_t point3D_id = tracked.AddPoint3D(Eigen::Vector3d(0, 0, 5), track);
  tracked.TakeChangedTracks();
  scene_.model.DeleteObservation(a_[0].image_id, a_[0].point2D_idx);
  ASSERT_TRUE(scene_.model.ExistsPoint3D(point3D_id));
  EXPECT_EQ(tracked.PointOfTrack(track_a_), point3D_id);
  tracked.TakeChangedTracks();
  scene_.model.DeletePoint3D(point3D_id);
  const std::vector<track_t> changed = tracked.TakeChangedTracks();
  EXPECT_TRUE(Contains(changed, track_a_));
  EXPECT_TRUE(Contains(changed, track_b_));
  EXPECT_EQ(tracked.PointOfTrack(track_a_), kInvalidPoint3DId);
}

// The same when the element left before noting began.
TEST_F(ChangedTracksTest, TracksLeftBeforeTheFirstCallAreFollowedToo) {
  TrackedReconstruction tracked(scene_.input.correspondence_graph, &scene_.model);
  Track track;
  track.AddElement(a_[0].image_id, a_[0].point2D_idx);
  for (int i = 0; i < 2; ++i) track.AddElement(b_[i].image_id, b_[i].point2D_idx);
  const point3D_t point3D_id = tracked.AddPoint3D(Eigen::Vector3d(0, 0, 5), track);
  scene_.model.DeleteObservation(a_[0].image_id, a_[0].point2D_idx);
  tracked.TakeChangedTracks();
  scene_.model.DeletePoint3D(point3D_id);
  EXPECT_TRUE(Contains(tracked.TakeChangedTracks(), track_a_));
}

}  // namespace
}  // namespace parallax
