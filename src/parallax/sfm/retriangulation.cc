#include "parallax/sfm/retriangulation.h"

#include <set>

namespace parallax {

namespace {

// Share of the pair's matches whose two keypoints belong to one point.
double ReconstructedRatio(const Reconstruction& reconstruction, image_t image_id1,
                          image_t image_id2, const FeatureMatches& matches) {
  const Image& image1 = reconstruction.GetImage(image_id1);
  const Image& image2 = reconstruction.GetImage(image_id2);
  size_t num_reconstructed = 0;
  for (const FeatureMatch& match : matches) {
    const point3D_t point3D_id = image1.points2D[match.point2D_idx1].point3D_id;
    num_reconstructed += point3D_id != kInvalidPoint3DId &&
                         point3D_id == image2.points2D[match.point2D_idx2].point3D_id;
  }
  return matches.empty() ? 1.0 : static_cast<double>(num_reconstructed) / matches.size();
}

}  // namespace

size_t RetriangulateUnderReconstructedPairs(const TrackTriangulationOptions& options,
                                            TrackedReconstruction* model) {
  TrackTriangulationOptions relaxed = options;
  relaxed.min_angle_deg = options.retriangulate_min_angle_deg;
  relaxed.max_reprojection_error_px = options.retriangulate_max_reprojection_error_px;
  const Reconstruction& reconstruction = model->Model();
  const CorrespondenceGraph& graph = model->Graph();
  size_t num_added = 0;
  for (const auto& [pair_id, matches] : graph.PairMatches()) {
    const auto [image_id1, image_id2] = PairIdToImagePair(pair_id);
    if (!reconstruction.ExistsImage(image_id1) || !reconstruction.ExistsImage(image_id2) ||
        !reconstruction.IsImageRegistered(image_id1) ||
        !reconstruction.IsImageRegistered(image_id2) ||
        model->RetriangulatedPairs().count(pair_id)) {
      continue;
    }
    if (ReconstructedRatio(reconstruction, image_id1, image_id2, matches) >=
        options.retriangulate_min_ratio) {
      continue;
    }
    model->RetriangulatedPairs().insert(pair_id);
    std::set<track_t> tracks;
    for (const FeatureMatch& match : matches) {
      for (const TrackElement& element : {TrackElement{image_id1, match.point2D_idx1},
                                          TrackElement{image_id2, match.point2D_idx2}}) {
        if (!model->IsFree(element)) continue;
        const track_t track_id = graph.TrackOf(element.image_id, element.point2D_idx);
        if (track_id != kInvalidTrackId) {
          tracks.insert(track_id);
        } else if (ContinueKeypoint(relaxed, element, {}, model) != kInvalidPoint3DId) {
          ++num_added;
        }
      }
    }
    for (const track_t track_id : tracks) {
      num_added += ContinueOrTriangulateTrack(relaxed, track_id, model);
    }
  }
  return num_added;
}

}  // namespace parallax
