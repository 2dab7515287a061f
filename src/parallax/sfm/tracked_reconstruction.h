#pragma once

#include <set>
#include <unordered_map>
#include <vector>

#include "parallax/scene/correspondence_graph.h"
#include "parallax/scene/reconstruction.h"

namespace parallax {

// A model under construction together with the feature tracks and correspondences it grows
// from. Tracks seed points; a track may hold more than one point (when its elements form
// groups that disagree), and points grow beyond their track along the correspondences and
// merge (track_triangulation.h, point_completion.h). Edits that add observations go through
// here so that each track remembers a point of its own.
class TrackedReconstruction {
 public:
  TrackedReconstruction(const CorrespondenceGraph& graph, Reconstruction* reconstruction);

  const CorrespondenceGraph& Graph() const { return graph_; }
  Reconstruction& Model() { return *reconstruction_; }
  const Reconstruction& Model() const { return *reconstruction_; }

  // A live point of the track in O(1): the last one that took one of its elements (points
  // deleted by filtering or merged away read as none until another takes one). For ranking
  // candidate images, where a walk over every track would cost too much.
  point3D_t PointOfTrack(track_t track_id) const;
  // Tracks whose PointOfTrack may have changed since the last call, some more than once or
  // unchanged: for state that follows the points of tracks (the next-view scores). The first
  // call returns every track and starts noting changes.
  std::vector<track_t> TakeChangedTracks();
  // Every live point holding one of the track's elements (a walk over its elements).
  std::vector<point3D_t> PointsOfTrack(track_t track_id) const;
  // Live points holding a keypoint matched with this one.
  std::vector<point3D_t> PointsOfCorrespondences(const TrackElement& element) const;

  // The keypoint is in a registered image and belongs to no point yet.
  bool IsFree(const TrackElement& element) const;
  // The model's image with this id, or nullptr. Cached: the triangulator asks for images
  // millions of times, and the model's images never move (std::map nodes) nor go away.
  const Image* FindImage(image_t image_id) const;

  point3D_t AddPoint3D(const Eigen::Vector3d& xyz, Track track);
  void AddObservation(point3D_t point3D_id, const TrackElement& element);
  // Reconstruction::MergePoints3D, the merged point noted for its elements' tracks.
  point3D_t MergePoints3D(point3D_t point3D_id1, point3D_t point3D_id2);

  // Image pairs already re-triangulated (each is, at most once).
  std::set<image_pair_t>& RetriangulatedPairs() { return retriangulated_pairs_; }

 private:
  // Appends the point of a keypoint in a registered image, if it has one and is not listed.
  void AddPointOf(const TrackElement& element, std::vector<point3D_t>* point3D_ids) const;
  void NotePoint(const TrackElement& element, point3D_t point3D_id);
  // Files the model's removed observations under the tracks they change.
  void NoteRemovedObservations(std::vector<track_t>* changed);

  const CorrespondenceGraph& graph_;
  Reconstruction* reconstruction_;
  std::vector<point3D_t> track_point3D_;
  bool noting_changes_ = false;
  std::vector<track_t> changed_tracks_;  // Since TakeChangedTracks last ran.
  // Tracks whose element left their (live) point: the point is still theirs, and they change
  // when it goes, though its track no longer leads to them.
  std::unordered_map<point3D_t, std::vector<track_t>> tracks_left_by_point_;
  std::set<image_pair_t> retriangulated_pairs_;
  mutable std::vector<const Image*> image_cache_;  // By image id; nullptr: not looked up yet.
};

}  // namespace parallax
