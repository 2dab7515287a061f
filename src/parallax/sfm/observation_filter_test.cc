#include "parallax/sfm/observation_filter.h"

#include <gtest/gtest.h>

#include "parallax/scene/synthetic_dataset.h"

namespace parallax {
namespace {

Reconstruction ExactRing() {
  SyntheticDatasetOptions options;
  options.num_images = 8;
  options.num_points3D = 200;
  options.min_track_length = 3;
  options.seed = 5;
  Reconstruction truth;
  SynthesizeDataset(options, &truth);
  return truth;
}

TEST(ObservationFilter, ExactModelLosesNothing) {
  Reconstruction model = ExactRing();
  const size_t num_observations = model.NumObservations();
  EXPECT_EQ(FilterAllPoints(ObservationFilterOptions(), &model), 0u);
  EXPECT_EQ(model.NumObservations(), num_observations);
}

TEST(ObservationFilter, OneBadObservationGoesAndItsPointStays) {
  Reconstruction model = ExactRing();
  const auto& [point3D_id, point] = *model.Points3D().begin();
  const point3D_t id = point3D_id;
  ASSERT_GE(point.track.Length(), 3u);
  const TrackElement bad = point.track.elements.front();
  model.GetImage(bad.image_id).points2D[bad.point2D_idx].xy += Eigen::Vector2d(10, 0);
  const size_t length = point.track.Length();
  EXPECT_EQ(FilterPoints(ObservationFilterOptions(), {id}, &model), 1u);
  ASSERT_TRUE(model.ExistsPoint3D(id));
  EXPECT_EQ(model.GetPoint3D(id).track.Length(), length - 1);
  EXPECT_FALSE(model.GetImage(bad.image_id).points2D[bad.point2D_idx].HasPoint3D());
}

TEST(ObservationFilter, PointsLeftWithOneGoodViewOrBehindACameraGo) {
  Reconstruction model = ExactRing();
  // A point moved far off: every view disagrees.
  const point3D_t moved = model.Points3D().begin()->first;
  const size_t moved_length = model.GetPoint3D(moved).track.Length();
  model.GetPoint3D(moved).xyz += Eigen::Vector3d(0.5, 0.5, 0.5);
  EXPECT_EQ(FilterPoints(ObservationFilterOptions(), {moved}, &model), moved_length);
  EXPECT_FALSE(model.ExistsPoint3D(moved));

  // A point behind its cameras reprojects nowhere (+inf), never within the threshold.
  const point3D_t behind = model.Points3D().begin()->first;
  const Image& image = model.GetImage(model.GetPoint3D(behind).track.elements.front().image_id);
  const Eigen::Vector3d center = image.ProjectionCenter();
  model.GetPoint3D(behind).xyz = center - 3.0 * image.ViewingDirection();
  FilterPoints(ObservationFilterOptions(), {behind}, &model);
  EXPECT_FALSE(model.ExistsPoint3D(behind));
}

TEST(ObservationFilter, PointsSeenUnderTooSmallAnAngleGo) {
  Reconstruction model = ExactRing();
  ObservationFilterOptions options;
  options.min_triangulation_angle_deg = 179;  // No point of the ring spans that.
  const size_t num_observations = model.NumObservations();
  EXPECT_EQ(FilterAllPoints(options, &model), num_observations);
  EXPECT_EQ(model.NumPoints3D(), 0u);
}

}  // namespace
}  // namespace parallax
