#pragma once

#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "parallax/util/types.h"

namespace parallax {

// The thresholds an initial pair is held to at one step of the relaxation.
struct InitThresholds {
  int min_num_inliers = 0;     // Matches that must triangulate.
  double min_angle_deg = 0.0;  // Their median triangulation angle.
  int step = 0;                // 0: the thresholds as given; k: after k halvings.
};

// How a model started, for the log and summary.json.
struct ModelStartReport {
  bool from_input_model = false;  // Seeded by a given model rather than a pair.
  image_t image_id1 = kInvalidImageId;
  image_t image_id2 = kInvalidImageId;
  InitThresholds thresholds;  // Those the pair met.
  int num_triangulated = 0;
  double median_angle_deg = 0.0;
  int num_pairs_tried = 0;  // Pairs held to some thresholds before this one started.
};

// A model's verified pairs with another model's images.
struct ModelLink {
  int model_index = -1;  // The other model.
  size_t num_image_pairs = 0;
  size_t num_matches = 0;  // Inlier matches over those pairs.
};

// One returned model: how it started, and how it relates to the others.
struct MapperModelReport {
  ModelStartReport start;     // Of the largest model when several were joined into this one.
  int num_joined_models = 1;  // Models of the run joined into this one (JoinModels).
  size_t num_images = 0;
  size_t num_points = 0;
  std::vector<ModelLink> links;  // Most matches first; only models it has pairs with.
};

// What happened to each image, for summary.json and the log.
struct MapperImageReport {
  int model_index = -1;  // Index into the returned models; -1 when not registered.
  std::string reason;    // Why it ended unregistered (empty when registered).
  int num_registration_trials = 0;
  int num_relaxed_registration_trials = 0;  // Of those, in the last pass with lower bars.
  bool registered_relaxed = false;          // Registered in that pass.
  size_t num_visible_points = 0;            // 2D-3D correspondences at the last attempt.
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
  std::string failure;                    // Set when no model could be started.
  std::vector<MapperModelReport> models;  // One per returned model, in the same order.
  // Models that ended smaller than min_model_size; their images stayed free for later ones.
  int num_discarded_models = 0;
};

}  // namespace parallax
