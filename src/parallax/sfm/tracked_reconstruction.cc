#include "parallax/sfm/tracked_reconstruction.h"

#include <algorithm>

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
  if (track_id != kInvalidTrackId) track_point3D_[track_id] = point3D_id;
}

}  // namespace parallax
