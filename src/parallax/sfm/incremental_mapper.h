#pragma once

#include <vector>

#include "parallax/scene/reconstruction.h"
#include "parallax/sfm/incremental_mapper_options.h"
#include "parallax/sfm/mapper_input.h"
#include "parallax/sfm/mapper_summary.h"
#include "parallax/util/progress.h"

namespace parallax {

// The paper's Algorithm 1 (and COLMAP's incremental mapper): initialise from the best pair,
// then repeatedly register the image that sees the most (and best spread) triangulated
// points by PnP, triangulate the tracks it completes, adjust locally, and globally when the
// model has grown; filter and re-triangulate. When no image can be added, a new model is
// started from the remaining images. Models come back largest first.
class IncrementalMapper {
 public:
  IncrementalMapper(const IncrementalMapperOptions& options, const MapperInput& input);
  // Maps from scratch.
  std::vector<Reconstruction> Reconstruct(MapperSummary* summary);
  // Maps starting from the registered images of `seed` (ids of this input; poses and
  // intrinsics as given, points triangulated anew from the tracks), as the last stage of
  // partitioned mapping does with its merged clusters: the first model grows from the seed,
  // further models start from what is left as usual.
  std::vector<Reconstruction> Extend(const Reconstruction& seed, MapperSummary* summary);
  // Counts registrations on `progress` (shared by mappers running side by side) instead of
  // a "mapping" line of the mapper's own.
  void SetProgress(ProgressReporter* progress) { progress_ = progress; }

 private:
  std::vector<Reconstruction> Run(const Reconstruction* seed, MapperSummary* summary);
  const IncrementalMapperOptions options_;
  const MapperInput& input_;
  ProgressReporter* progress_ = nullptr;
};

// A copy holding only the registered images, the cameras they use, and the points.
Reconstruction ExtractRegisteredModel(const Reconstruction& reconstruction);

}  // namespace parallax
