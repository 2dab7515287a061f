#pragma once

#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "parallax/util/types.h"

namespace parallax {

// What happened to each image, for summary.json and the log.
struct MapperImageReport {
  int model_index = -1;  // Index into the returned models; -1 when not registered.
  std::string reason;    // Why it ended unregistered (empty when registered).
  int num_registration_trials = 0;
  size_t num_visible_points = 0;  // 2D-3D correspondences at the last attempt.
  size_t num_pnp_inliers = 0;
  // Mean reprojection error right after registration and triangulation (before any bundle
  // adjustment that includes the image) and in the final model.
  double error_before_ba_px = std::numeric_limits<double>::quiet_NaN();
  double error_after_ba_px = std::numeric_limits<double>::quiet_NaN();
};

// Wall time of the mapper's phases, each summed over the run. The rest of `seconds` is
// starting models, bookkeeping and the final reports.
struct MapperPhaseSeconds {
  double next_view = 0;        // Ranking the unregistered images by visibility.
  double registration = 0;     // 2D-3D correspondences, PnP RANSAC and pose refinement.
  double triangulation = 0;    // New points in each registered image.
  double local_ba = 0;         // Local bundle adjustments (the solver).
  double global_ba = 0;        // Global bundle adjustments (the solver).
  double filtering = 0;        // Observations and points that stopped fitting.
  double completion = 0;       // Tracks completed and points merged.
  double retriangulation = 0;  // Under-reconstructed pairs, before each global adjustment.

  // Each phase with its name (summary.json's key, and the log's), in the order above.
  std::vector<std::pair<const char*, double>> Named() const;
  double Total() const;
};

struct MapperSummary {
  std::map<image_t, MapperImageReport> images;
  size_t num_local_ba = 0;
  size_t num_global_ba = 0;
  MapperPhaseSeconds phase_seconds;
  // The bundle-adjustment solver's time, local and global.
  double BaSeconds() const { return phase_seconds.local_ba + phase_seconds.global_ba; }
  double seconds = 0;
  std::string failure;  // Set when no model could be started.
};

}  // namespace parallax
