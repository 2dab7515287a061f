#pragma once

#include "parallax/geometry/sim3.h"
#include "parallax/scene/reconstruction.h"

namespace parallax {

// The rigid motion (scale 1) that lays a model's principal plane on z = 0, as COLMAP's
// `model_aligner --alignment_type plane` does for Gaussian splatting's convert.py: the
// points' centroid to the origin, their two directions of largest spread to x and y, and the
// normal to +z on the side where the cameras are (so that "up" is up for a scene photographed
// from above its ground). Identity for a model with fewer than three points.
Sim3d PrincipalPlaneAlignment(const Reconstruction& model);

}  // namespace parallax
