#include "parallax/sfm/incremental_mapper_options.h"

#include "parallax/util/check.h"

namespace parallax {

void IncrementalMapperOptions::Check() const {
  PARALLAX_CHECK_GE(init_min_num_inliers, 1);
  PARALLAX_CHECK_GE(init_min_triangulation_angle_deg, 0.0);
  PARALLAX_CHECK_GE(init_min_num_inliers_floor, 1);
  PARALLAX_CHECK_GE(init_min_triangulation_angle_floor_deg, 0.0);
  PARALLAX_CHECK_GE(init_max_trials, 1);
  absolute_pose.Check();
  absolute_pose_refinement.Check();
  PARALLAX_CHECK_GE(absolute_pose_min_num_inliers, 3);
  PARALLAX_CHECK(absolute_pose_min_inlier_ratio >= 0 && absolute_pose_min_inlier_ratio <= 1);
  PARALLAX_CHECK_GE(max_registration_trials, 1);
  PARALLAX_CHECK_GE(relaxed_absolute_pose_min_num_inliers, 3);
  PARALLAX_CHECK(relaxed_absolute_pose_min_inlier_ratio >= 0 &&
                 relaxed_absolute_pose_min_inlier_ratio <= 1);
  triangulation.Check();
  filter.Check();
  local_ba.Check();
  global_ba.Check();
  final_ba.Check();
  PARALLAX_CHECK_GE(local_ba_num_images, 2);
  PARALLAX_CHECK_GE(global_ba_images_ratio, 1.0);
  PARALLAX_CHECK_GE(global_ba_points_ratio, 1.0);
  PARALLAX_CHECK_GE(global_ba_max_refinements, 1);
  PARALLAX_CHECK_GE(min_model_size, 2);
  PARALLAX_CHECK_GE(max_num_models, 1);
  join.Check();
}

}  // namespace parallax
