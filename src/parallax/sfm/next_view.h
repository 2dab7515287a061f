#pragma once

#include "parallax/sfm/tracked_reconstruction.h"

namespace parallax {

// How well an unregistered image would be constrained by the model: its keypoints whose
// track already has a 3D point, counted in a pyramid of grids (2x2, 4x4, 8x8) over the image
// so that well spread points score higher than a clump (COLMAP's visibility pyramid idea).
// Zero when the image sees no 3D point.
double VisibilityScore(image_t image_id, const TrackedReconstruction& model);

}  // namespace parallax
