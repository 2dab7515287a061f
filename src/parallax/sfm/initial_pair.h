#pragma once

#include <map>
#include <set>
#include <vector>

#include "parallax/geometry/rigid3.h"
#include "parallax/scene/reconstruction.h"
#include "parallax/scene/two_view_geometry.h"
#include "parallax/sfm/incremental_mapper_options.h"
#include "parallax/sfm/mapper_summary.h"

namespace parallax {

// The thresholds in the order they are tried: as given, then halving the angle and the
// inlier count in turns (the angle first: a forward walk fails on angle, and a pair with
// many inliers at a smaller angle is the safer start), each stopping at its floor, until
// both are at their floors. COLMAP halves the same two in turns, the inliers first.
std::vector<InitThresholds> InitThresholdSchedule(const IncrementalMapperOptions& options);

// How one candidate pair triangulates under its relative pose, whatever the thresholds.
struct InitialPairEvaluation {
  bool has_pose = false;  // False when no relative pose could be had (then nothing else is set).
  Rigid3d cam2_from_cam1;
  int num_triangulated = 0;  // Inlier matches in front of both cameras and within the error.
  double median_angle_deg = 0.0;
};

// Triangulates the pair's inlier matches under the pose verification stored (from E when the
// database holds none, as COLMAP's before 3.7) and measures their angles. `max_error_px`:
// the largest reprojection error in either image.
InitialPairEvaluation EvaluateInitialPair(const Reconstruction& reconstruction,
                                          image_pair_t pair_id, const TwoViewGeometry& geometry,
                                          double max_error_px);

// What the initialiser keeps across the models of one run: each pair's evaluation (a pair is
// triangulated once however many thresholds it is held to), the pairs a model already
// started from, which are not tried again, and the images of starts that ended too small:
// a pair of two of them is not tried either (another pair of a small island would end the
// same way), though later models may still register them.
struct InitialPairLedger {
  std::map<image_pair_t, InitialPairEvaluation> evaluations;
  std::set<image_pair_t> started;
  std::set<image_t> failed_start_images;
};

}  // namespace parallax
