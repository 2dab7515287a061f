#pragma once

#include <vector>

#include "parallax/sfm/track_triangulation.h"

namespace parallax {

// Grows a point along the correspondence graph: keypoints matched with its observations,
// directly or through up to options.complete_max_transitivity hops, that are free and in a
// registered image the point does not observe yet join it when they reproject within the
// threshold. Returns the number of observations added.
size_t CompletePoint(const TrackTriangulationOptions& options, point3D_t point3D_id,
                     TrackedReconstruction* model);

// Merges the point with the points that correspondences link to it, one after the other, as
// long as the merged point (refit on all their observations) reprojects within the threshold
// in every one of them; where both observe an image, the keypoint that fits better stays.
// Two points of one track whose elements were left apart, or of two tracks whose union was
// refused, become one. Returns the number of merges.
size_t MergePoint(const TrackTriangulationOptions& options, point3D_t point3D_id,
                  TrackedReconstruction* model);

// CompletePoint, then MergePoint, for each of the points that still exists. Returns the
// observations added plus the merges.
size_t CompleteAndMergePoints(const TrackTriangulationOptions& options,
                              const std::vector<point3D_t>& point3D_ids,
                              TrackedReconstruction* model);
size_t CompleteAndMergeAllPoints(const TrackTriangulationOptions& options,
                                 TrackedReconstruction* model);

}  // namespace parallax
