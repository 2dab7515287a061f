#pragma once

#include <vector>

#include "parallax/scene/correspondence_graph.h"
#include "parallax/scene/reconstruction.h"

namespace parallax {

// A model under construction together with its link to the feature tracks: each track has
// at most one 3D point, and a point's observations are a subset of its track.
class TrackedReconstruction {
 public:
  TrackedReconstruction(const CorrespondenceGraph& graph, Reconstruction* reconstruction)
      : graph_(graph),
        reconstruction_(reconstruction),
        track_point3D_(graph.NumTracks(), kInvalidPoint3DId) {}

  const CorrespondenceGraph& Graph() const { return graph_; }
  Reconstruction& Model() { return *reconstruction_; }
  const Reconstruction& Model() const { return *reconstruction_; }

  // The live 3D point of a track (points deleted by filtering read as none).
  point3D_t PointOfTrack(track_t track_id) const {
    const point3D_t point3D_id = track_point3D_[track_id];
    if (point3D_id == kInvalidPoint3DId || !reconstruction_->ExistsPoint3D(point3D_id)) {
      return kInvalidPoint3DId;
    }
    return point3D_id;
  }
  void SetPointOfTrack(track_t track_id, point3D_t point3D_id) {
    track_point3D_[track_id] = point3D_id;
  }

 private:
  const CorrespondenceGraph& graph_;
  Reconstruction* reconstruction_;
  std::vector<point3D_t> track_point3D_;
};

}  // namespace parallax
