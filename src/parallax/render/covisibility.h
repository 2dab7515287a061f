#pragma once

#include <vector>

#include "parallax/render/scene_model.h"
#include "parallax/scene/reconstruction.h"

namespace parallax {

struct CovisibilityOptions {
  // Spacing in metres of the scene points sampled on every surface.
  double point_spacing = 1.0;
  // Pairs that share fewer visible points are left out.
  int min_shared_points = 30;
  // Points farther than this from a camera do not count as seen (a horizon for oblique views).
  double max_distance = 400.0;
  // Nor do points whose surface the ray meets more obliquely than this (degrees from the
  // normal): a wall seen edge-on from above shows no texture to match, though it is in view.
  double max_incidence_degrees = 75.0;
  // Seed of the jittered sample positions.
  uint64_t seed = 0;
  // Worker threads (<= 0: all cores).
  int num_threads = -1;
  void Check() const;
};

// Two views and the number of scene points both see.
struct CovisiblePair {
  image_t image_id1 = kInvalidImageId;  // The smaller id.
  image_t image_id2 = kInvalidImageId;
  int num_shared_points = 0;
};

// Which registered views of `views` see the same part of `scene`: points are sampled on its
// surfaces (SceneModel::SampleSurfacePoints, the ground inside what the views see), a point
// is seen by a view when it projects inside the image, lies in front of the camera, faces it
// within max_incidence_degrees and nothing blocks the ray between them. Pairs sorted by ids. The
// ground truth that pair selection (retrieval, GPS neighbours) is measured against.
std::vector<CovisiblePair> ComputeCovisiblePairs(const SceneModel& scene,
                                                 const Reconstruction& views,
                                                 const CovisibilityOptions& options);

}  // namespace parallax
