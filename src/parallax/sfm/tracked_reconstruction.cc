#include "parallax/sfm/tracked_reconstruction.h"

#include <algorithm>
#include <numeric>

namespace parallax {

TrackedReconstruction::TrackedReconstruction(const CorrespondenceGraph& graph,
                                             Reconstruction* reconstruction)
    : graph_(graph),
      reconstruction_(reconstruction),
      track_point3D_(graph.NumTracks(), kInvalidPoint3DId) {}

point3D_t TrackedReconstruction::PointOfTrack(track_t track_id) const {
  const point3D_t point3D_id = track_point3D_[track_id];
  if (point3D_id == kInvalidPoint3DId || !reconstruction_->ExistsPoint3D(point3D_id)) {
    return kInvalidPoint3DId;
  }
  return point3D_id;
}

const Image* TrackedReconstruction::FindImage(image_t image_id) const {
  if (image_id < image_cache_.size() && image_cache_[image_id] != nullptr) {
    return image_cache_[image_id];
  }
  if (!reconstruction_->ExistsImage(image_id)) return nullptr;
  const Image* image = &reconstruction_->GetImage(image_id);
  constexpr image_t kMaxCachedImageId = 1 << 22;  // Ids beyond are looked up every time.
  if (image_id < kMaxCachedImageId) {
    if (image_id >= image_cache_.size()) image_cache_.resize(image_id + 1, nullptr);
    image_cache_[image_id] = image;
  }
  return image;
}

void TrackedReconstruction::AddPointOf(const TrackElement& element,
                                       std::vector<point3D_t>* point3D_ids) const {
  const Image* image = FindImage(element.image_id);
  if (image == nullptr || !image->registered) return;
  const point3D_t point3D_id = image->points2D[element.point2D_idx].point3D_id;
  if (point3D_id == kInvalidPoint3DId) return;
  if (std::find(point3D_ids->begin(), point3D_ids->end(), point3D_id) == point3D_ids->end()) {
    point3D_ids->push_back(point3D_id);
  }
}

std::vector<point3D_t> TrackedReconstruction::PointsOfTrack(track_t track_id) const {
  std::vector<point3D_t> point3D_ids;
  for (const TrackElement& element : graph_.TrackElements(track_id)) {
    AddPointOf(element, &point3D_ids);
  }
  return point3D_ids;
}

std::vector<point3D_t> TrackedReconstruction::PointsOfCorrespondences(
    const TrackElement& element) const {
  std::vector<point3D_t> point3D_ids;
  for (const TrackElement& other :
       graph_.CorrespondencesOf(element.image_id, element.point2D_idx)) {
    AddPointOf(other, &point3D_ids);
  }
  return point3D_ids;
}

bool TrackedReconstruction::IsFree(const TrackElement& element) const {
  const Image* image = FindImage(element.image_id);
  return image != nullptr && image->registered &&
         !image->points2D[element.point2D_idx].HasPoint3D();
}

point3D_t TrackedReconstruction::AddPoint3D(const Eigen::Vector3d& xyz, Track track) {
  const point3D_t point3D_id = reconstruction_->AddPoint3D(xyz, track);
  for (const TrackElement& element : track.elements) NotePoint(element, point3D_id);
  return point3D_id;
}

void TrackedReconstruction::AddObservation(point3D_t point3D_id, const TrackElement& element) {
  reconstruction_->AddObservation(point3D_id, element);
  NotePoint(element, point3D_id);
}

point3D_t TrackedReconstruction::MergePoints3D(point3D_t point3D_id1, point3D_t point3D_id2) {
  const point3D_t merged = reconstruction_->MergePoints3D(point3D_id1, point3D_id2);
  for (const TrackElement& element : reconstruction_->GetPoint3D(merged).track.elements) {
    NotePoint(element, merged);
  }
  return merged;
}

void TrackedReconstruction::NotePoint(const TrackElement& element, point3D_t point3D_id) {
  const track_t track_id = graph_.TrackOf(element.image_id, element.point2D_idx);
  if (track_id == kInvalidTrackId) return;
  track_point3D_[track_id] = point3D_id;
  if (noting_changes_) changed_tracks_.push_back(track_id);
}

std::vector<track_t> TrackedReconstruction::TakeChangedTracks() {
  if (!noting_changes_) {
    noting_changes_ = true;
    reconstruction_->KeepRemovedObservations();
    std::vector<track_t> all(graph_.NumTracks());
    std::iota(all.begin(), all.end(), track_t{0});
    // Tracks whose point lost their elements before noting began must be filed as well.
    for (const track_t track_id : all) {
      const point3D_t point3D_id = PointOfTrack(track_id);
      if (point3D_id == kInvalidPoint3DId) continue;
      const std::vector<TrackElement>& elements =
          reconstruction_->GetPoint3D(point3D_id).track.elements;
      if (std::none_of(elements.begin(), elements.end(), [&](const TrackElement& element) {
            return graph_.TrackOf(element.image_id, element.point2D_idx) == track_id;
          })) {
        tracks_left_by_point_[point3D_id].push_back(track_id);
      }
    }
    return all;
  }
  std::vector<track_t> changed;
  changed.swap(changed_tracks_);
  NoteRemovedObservations(&changed);
  return changed;
}

void TrackedReconstruction::NoteRemovedObservations(std::vector<track_t>* changed) {
  // A track's point changes only when the track is noted with another point (NotePoint) or
  // its point is deleted. The deleted point's remaining elements lead to most such tracks;
  // the rest lost the element that linked them earlier, and were filed here then.
  for (const Reconstruction::RemovedObservation& removed :
       reconstruction_->TakeRemovedObservations()) {
    const track_t track_id = graph_.TrackOf(removed.element.image_id, removed.element.point2D_idx);
    if (track_id != kInvalidTrackId) changed->push_back(track_id);
    if (reconstruction_->ExistsPoint3D(removed.point3D_id)) {
      if (track_id != kInvalidTrackId && track_point3D_[track_id] == removed.point3D_id) {
        tracks_left_by_point_[removed.point3D_id].push_back(track_id);
      }
      continue;
    }
    const auto left = tracks_left_by_point_.find(removed.point3D_id);
    if (left == tracks_left_by_point_.end()) continue;
    changed->insert(changed->end(), left->second.begin(), left->second.end());
    tracks_left_by_point_.erase(left);
  }
}

}  // namespace parallax
