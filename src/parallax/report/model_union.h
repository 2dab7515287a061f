#pragma once

#include "parallax/report/evaluation.h"

namespace parallax {

struct ModelUnionReport {
  size_t num_shared_images = 0;  // Registered in both (by name); the base's poses are kept.
  size_t num_alignment_inliers = 0;
  size_t num_images_added = 0;  // Registered in `model` only.
  size_t num_points_added = 0;
  double scale = 1;  // Of the similarity base_from_model.
};

// `parallax model merge`: `model` moved into the frame of `base` by the similarity of the
// camera centres of their shared images (matched by name, RANSAC; AlignToReference), and
// added to it. Shared images (registered in both) keep `base`'s pose and observations; the
// images only `model` registered come with their poses (and their cameras, under new ids,
// unless `base` knows the image); its points come with their observations in those images,
// and those left with fewer than two are dropped. Throws InputError when
// the two share too little to be aligned; `base_source` names `base` in its message.
Reconstruction UniteModels(const Reconstruction& base, const std::string& base_source,
                           const Reconstruction& model, ModelUnionReport* report = nullptr);

}  // namespace parallax
