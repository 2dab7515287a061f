#include "parallax/scene/correspondence_graph.h"

#include <gtest/gtest.h>

#include <set>

#include "parallax/util/check.h"

namespace parallax {
namespace {

TEST(CorrespondenceGraph, ChainsMatchesIntoTracks) {
  CorrespondenceGraph graph;
  for (image_t id = 1; id <= 3; ++id) graph.AddImage(id, 5);
  graph.AddCorrespondences(1, 2, {{0, 1}, {2, 2}});
  graph.AddCorrespondences(3, 2, {{4, 1}});  // Reversed order: idx1 belongs to image 3.
  graph.Finalize();
  ASSERT_EQ(graph.NumTracks(), 2u);
  const track_t track = graph.TrackOf(1, 0);
  ASSERT_NE(track, kInvalidTrackId);
  EXPECT_EQ(graph.TrackOf(2, 1), track);
  EXPECT_EQ(graph.TrackOf(3, 4), track);
  EXPECT_EQ(graph.TrackElements(track).size(), 3u);
  EXPECT_EQ(graph.TrackOf(1, 1), kInvalidTrackId);
  EXPECT_EQ(graph.NumObservationsForImage(2), 2u);
  EXPECT_EQ(graph.NumMatchesBetween(2, 3), 1u);
  EXPECT_EQ(graph.NeighborsOf(2).at(1), 2u);
  EXPECT_EQ(graph.PairMatches().at(ImagePairToPairId(2, 3)).front().point2D_idx1, 1u);
  for (image_t id = 1; id <= 3; ++id) {
    const track_t* tracks = graph.TracksOfImage(id);
    for (point2D_t idx = 0; idx < 5; ++idx) EXPECT_EQ(tracks[idx], graph.TrackOf(id, idx));
  }
}

TEST(CorrespondenceGraph, SplitsInconsistentComponentInsteadOfDropping) {
  // Image 1 keypoints 0 and 1 both chain to image 2 keypoint 0 (through image 3): the weaker
  // pair's link is refused, both halves survive as consistent tracks.
  CorrespondenceGraph graph;
  for (image_t id = 1; id <= 3; ++id) graph.AddImage(id, 10);
  graph.AddCorrespondences(1, 2, {{0, 0}, {5, 5}, {6, 6}});  // Strongest pair.
  graph.AddCorrespondences(2, 3, {{0, 0}, {5, 5}});
  graph.AddCorrespondences(1, 3, {{1, 0}});  // Weakest: would join keypoints 0 and 1 of image 1.
  graph.Finalize();
  EXPECT_EQ(graph.Stats().num_refused_unions, 1u);
  EXPECT_EQ(graph.Stats().num_split_components, 1u);
  for (track_t t = 0; t < graph.NumTracks(); ++t) {
    std::set<image_t> images;
    for (const auto& element : graph.TrackElements(t)) {
      EXPECT_TRUE(images.insert(element.image_id).second) << "inconsistent track " << t;
    }
  }
  EXPECT_EQ(graph.TrackOf(1, 0), graph.TrackOf(3, 0));
  EXPECT_EQ(graph.TrackElements(graph.TrackOf(1, 0)).size(), 3u);
  EXPECT_EQ(graph.TrackOf(1, 1), kInvalidTrackId);  // Its only link was refused.
  // The refused match is still a correspondence, in both directions.
  const auto refused = graph.CorrespondencesOf(1, 1);
  ASSERT_EQ(refused.size(), 1u);
  EXPECT_EQ(refused[0], (TrackElement{3, 0}));
  const auto back = graph.CorrespondencesOf(3, 0);
  ASSERT_EQ(back.size(), 2u);
  using Keypoint = std::pair<image_t, point2D_t>;
  const std::set<Keypoint> expected = {{1, 1}, {2, 0}};
  const std::set<Keypoint> found = {{back[0].image_id, back[0].point2D_idx},
                                    {back[1].image_id, back[1].point2D_idx}};
  EXPECT_EQ(found, expected);
  EXPECT_TRUE(graph.CorrespondencesOf(1, 9).empty());
  EXPECT_THROW(graph.CorrespondencesOf(1, 10), CheckError);
  EXPECT_THROW(graph.CorrespondencesOf(4, 0), std::out_of_range);
  EXPECT_FALSE(graph.IsTwoViewTrack(graph.TrackOf(1, 5)));  // Seen by images 1, 2 and 3.
}

TEST(CorrespondenceGraph, RejectsOutOfRangeMatches) {
  CorrespondenceGraph graph;
  graph.AddImage(1, 2);
  graph.AddImage(2, 2);
  EXPECT_THROW(graph.AddCorrespondences(1, 2, {{0, 7}}), CheckError);
}

}  // namespace
}  // namespace parallax
