#pragma once

#include <vector>

#include "parallax/estimators/similarity_transform.h"
#include "parallax/geometry/sim3.h"
#include "parallax/scene/reconstruction.h"

namespace parallax {

struct ModelMergerOptions {
  // Registered images two models must share to be merged.
  int min_shared_images = 3;
  // 3D points seen in the shared images of both models that must agree with the similarity.
  int min_inlier_points = 30;
  // Inlier distance of the similarity RANSAC, as a share of the spread of the shared points
  // (their median distance from their median): independent of each model's arbitrary scale.
  double max_error_fraction = 0.01;
  // The similarity's RANSAC (its max_error is set from the fraction above, its seed from
  // `seed`).
  RansacOptions ransac = Sim3dRansacOptions(1.0);
  uint64_t seed = 0;  // Of the similarity RANSAC of every merge.
  void Check() const;
};

// How one model joined the merged one.
struct ModelMergeReport {
  bool success = false;
  size_t num_shared_images = 0;
  size_t num_correspondences = 0;  // Shared observations with a 3D point in both models.
  size_t num_inliers = 0;
  Sim3d merged_from_model;
};

// Brings models of overlapping image sets (the clusters of a partitioned run, mapped apart)
// into one frame. The largest model is the frame; then, repeatedly, the model sharing the
// most registered images with what is merged so far joins by the similarity that maps its 3D
// points onto the merged ones, matched through the keypoints of the shared images (LO-RANSAC,
// Umeyama). Images already merged keep their pose; new ones take the transformed pose.
//
// The result holds the cameras (the first model's intrinsics win) and the registered images
// with their poses; no points, which the caller triangulates anew from all the tracks.
// `reports` gets one entry per input model (the first is the frame, with success set);
// models that never share enough with the rest are left out, their report unsuccessful.
Reconstruction MergeModels(const ModelMergerOptions& options,
                           const std::vector<Reconstruction>& models,
                           std::vector<ModelMergeReport>* reports = nullptr);

// Adds `model`'s image `image_id` to `into` (which must hold its camera), registered, with its
// pose moved by `into_from_model` and no keypoints (the caller triangulates anew): how merged
// and joined models take their images.
void AddPoseOnlyImage(const Reconstruction& model, image_t image_id, const Sim3d& into_from_model,
                      Reconstruction* into);

// The median distance of the points from their per-axis median: a model's spread, for
// thresholds that hold whatever its arbitrary scale.
double MedianDistanceFromMedian(const std::vector<Eigen::Vector3d>& points);

}  // namespace parallax
