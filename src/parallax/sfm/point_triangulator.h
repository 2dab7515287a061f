#pragma once

#include "parallax/scene/reconstruction.h"
#include "parallax/sfm/incremental_mapper_options.h"
#include "parallax/sfm/mapper_input.h"
#include "parallax/sfm/mapper_summary.h"

namespace parallax {

// COLMAP's point_triangulator: the points of a model whose poses are known (from another tool,
// a rig, a survey), triangulated from the input's tracks. The poses and intrinsics of `posed`
// stay exactly as given; every track its registered images see is triangulated anew, points
// are completed and merged, filtered, adjusted with the poses held and filtered again; no
// other image is registered. `posed` is in the input's image ids (ModelInInputIds). Throws
// InputError when fewer than two of its images are in the input.
Reconstruction TriangulateIntoPoses(const IncrementalMapperOptions& options,
                                    const MapperInput& input, const Reconstruction& posed,
                                    MapperSummary* summary);

}  // namespace parallax
