#pragma once

#include <cstdint>
#include <map>
#include <span>
#include <unordered_map>
#include <vector>

#include "parallax/feature/types.h"
#include "parallax/scene/track.h"
#include "parallax/util/types.h"

namespace parallax {

using track_t = uint32_t;
inline constexpr track_t kInvalidTrackId = UINT32_MAX;

// Verified matches of all image pairs, joined into feature tracks by union-find.
//
// Tracks are built greedily from the strongest pairs down (most inliers first). A union that
// would put two keypoints of one image into one track is refused, so every track is
// consistent; the refusals split what would have been an inconsistent component instead of
// dropping it, and are counted in TrackStats.
class CorrespondenceGraph {
 public:
  struct TrackStats {
    size_t num_tracks = 0;            // Tracks with at least two elements.
    size_t num_observations = 0;      // Keypoints in a track.
    size_t num_refused_unions = 0;    // Matches that would have made a track inconsistent.
    size_t num_split_components = 0;  // Components that would have been inconsistent.
    double mean_track_length = 0;
  };

  void AddImage(image_t image_id, size_t num_points2D);
  // Matches of a verified pair (point2D_idx1 in image_id1). Out-of-range indices throw.
  void AddCorrespondences(image_t image_id1, image_t image_id2, const FeatureMatches& matches);
  // Builds the tracks. Call once, after every AddImage / AddCorrespondences.
  void Finalize();

  bool ExistsImage(image_t image_id) const { return images_.count(image_id) > 0; }
  std::vector<image_t> ImageIds() const;
  size_t NumPoints2D(image_t image_id) const { return images_.at(image_id).num_points2D; }
  // Keypoints of the image that belong to a track.
  size_t NumObservationsForImage(image_t image_id) const;

  size_t NumTracks() const { return tracks_.size(); }
  const std::vector<TrackElement>& TrackElements(track_t track_id) const {
    return tracks_[track_id];
  }
  track_t TrackOf(image_t image_id, point2D_t point2D_idx) const;
  // A track of two keypoints matched with each other and nothing else: a feature that only
  // two images saw, which can never be held by more than two.
  bool IsTwoViewTrack(track_t track_id) const;
  // The tracks of all the image's keypoints in order (kInvalidTrackId where none),
  // NumPoints2D(image_id) of them: one lookup for loops over an image's keypoints.
  const track_t* TracksOfImage(image_t image_id) const;
  const TrackStats& Stats() const { return stats_; }

  // Every keypoint matched with keypoint `point2D_idx` of `image_id` in a verified pair, the
  // refused unions included: what points grow and merge along, where tracks only seed them.
  std::span<const TrackElement> CorrespondencesOf(image_t image_id, point2D_t point2D_idx) const;

  // Verified matches of a pair as added (oriented so point2D_idx1 is in the smaller id).
  const std::map<image_pair_t, FeatureMatches>& PairMatches() const { return pair_matches_; }
  size_t NumMatchesBetween(image_t image_id1, image_t image_id2) const;
  // Images that share verified matches with `image_id`, with the match counts.
  const std::map<image_t, size_t>& NeighborsOf(image_t image_id) const;

 private:
  struct ImageEntry {
    size_t num_points2D = 0;
    size_t node_offset = 0;  // First node of the image in the union-find arrays.
    std::map<image_t, size_t> neighbors;
  };

  void BuildCorrespondenceLists(size_t num_nodes);

  std::map<image_t, ImageEntry> images_;
  std::map<image_pair_t, FeatureMatches> pair_matches_;
  std::vector<std::vector<TrackElement>> tracks_;
  std::vector<track_t> node_track_;  // Track of every keypoint node (or kInvalidTrackId).
  // Correspondences of node n: correspondences_[correspondence_offsets_[n] ..
  // correspondence_offsets_[n + 1]), 8 bytes per keypoint and 16 per verified match.
  std::vector<size_t> correspondence_offsets_;
  static constexpr size_t kNoImage = SIZE_MAX;
  // By image id: the image's first node and its number of keypoints.
  std::vector<std::pair<size_t, size_t>> image_nodes_;
  std::vector<TrackElement> correspondences_;
  TrackStats stats_;
  bool finalized_ = false;
};

}  // namespace parallax
