#pragma once

#include <vector>

#include "parallax/estimators/similarity_transform.h"
#include "parallax/geometry/sim3.h"
#include "parallax/scene/correspondence_graph.h"
#include "parallax/scene/reconstruction.h"

namespace parallax {

struct ModelJoinerOptions {
  // Tracks with a point in both models that must agree with the similarity.
  int min_inlier_points = 15;
  // Inlier distance of the similarity RANSAC, as a share of the spread of the joined points
  // (their median distance from their median): independent of each model's arbitrary scale.
  double max_error_fraction = 0.03;
  RansacOptions ransac = Sim3dRansacOptions(1.0);  // Its max_error and seed are set per join.
  uint64_t seed = 0;
  void Check() const;
};

// How one model joined the others.
struct ModelJoinReport {
  bool joined = false;           // The frame (the largest model) counts as joined.
  size_t num_shared_tracks = 0;  // Tracks with a point in this model and in the joined ones.
  size_t num_inliers = 0;        // Of those, agreeing with the similarity.
  Sim3d joined_from_model;
};

// Joins the models of one incremental run, whose image sets are disjoint, into one frame: a
// feature track that has a point in two models says where that point lies in both, so the
// tracks the models share give the similarity between them (LO-RANSAC, Umeyama). The
// largest model is the frame; then, repeatedly, the model sharing the most tracks with what
// is joined so far comes in, when enough of them agree. Models whose matches to the others
// never triangulated in both, or disagree, are left out.
//
// The result holds the cameras (the first joined model's intrinsics win) and the joined
// images with their poses, no points: the caller triangulates all tracks anew and adjusts
// the whole. `reports` gets one entry per input model.
Reconstruction JoinModels(const ModelJoinerOptions& options,
                          const std::vector<Reconstruction>& models,
                          const CorrespondenceGraph& correspondence_graph,
                          std::vector<ModelJoinReport>* reports);

}  // namespace parallax
