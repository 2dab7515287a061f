#pragma once

#include "parallax/sfm/track_triangulation.h"

namespace parallax {

// Re-triangulates, once each, the pairs of registered images whose verified matches are
// under-reconstructed (fewer than options.retriangulate_min_ratio of them join the two
// keypoints in one point), with the relaxed angle and reprojection thresholds: points that
// were too flat or too far off when first tried, before the poses had been adjusted
// (COLMAP's Retriangulate after global bundle adjustment). Returns the observations added.
size_t RetriangulateUnderReconstructedPairs(const TrackTriangulationOptions& options,
                                            TrackedReconstruction* model);

}  // namespace parallax
