#include "parallax/render/covisibility.h"

#include <gtest/gtest.h>

#include <map>

#include "parallax/render/synthetic_scene.h"

namespace parallax {
namespace {

// Views of the aerial town: nadir at `centers`, 60 m up.
Reconstruction NadirViews(const std::vector<Eigen::Vector2d>& centers) {
  Reconstruction views;
  views.AddCamera(Camera::Create(1, CameraModelId::kPinhole, 576, 640, 480));
  for (size_t i = 0; i < centers.size(); ++i) {
    Image image;
    image.image_id = static_cast<image_t>(i + 1);
    image.camera_id = 1;
    image.name = "view" + std::to_string(i);
    Eigen::Matrix3d rotation;
    rotation << 1, 0, 0, 0, -1, 0, 0, 0, -1;  // Looking down, image up is north.
    const Eigen::Vector3d center(centers[i].x(), centers[i].y(), 60.0);
    image.cam_from_world = Rigid3d(rotation, -rotation * center);
    views.AddImage(std::move(image));
    views.RegisterImage(static_cast<image_t>(i + 1));
  }
  return views;
}

TEST(Covisibility, SharedPointsFallWithDistance) {
  SceneModelOptions scene_options;
  scene_options.kind = SceneModelOptions::Kind::kTown;
  scene_options.town_half_size = 200;
  const SceneModel scene(scene_options);
  // Footprint 66.7 x 50 m: views 10 m apart overlap much, 40 m little, 300 m not at all.
  const Reconstruction views = NadirViews({{0, 0}, {0, 10}, {0, 40}, {300, 0}});
  CovisibilityOptions options;
  options.num_threads = 2;
  const std::vector<CovisiblePair> pairs = ComputeCovisiblePairs(scene, views, options);
  std::map<std::pair<image_t, image_t>, int> shared;
  for (const CovisiblePair& pair : pairs) {
    EXPECT_LT(pair.image_id1, pair.image_id2);
    EXPECT_GE(pair.num_shared_points, options.min_shared_points);
    shared[{pair.image_id1, pair.image_id2}] = pair.num_shared_points;
  }
  ASSERT_TRUE(shared.count({1, 2}) && shared.count({1, 3}));
  // About one point per square metre: 10 m apart share about 0.8 of a 3300 m^2 footprint.
  const int near = shared[{1, 2}], far = shared[{1, 3}];
  EXPECT_GT(near, 2000);
  EXPECT_GT(near, 2 * far);
  EXPECT_EQ(shared.count({1, 4}), 0u);
  EXPECT_EQ(shared.count({3, 4}), 0u);

  // Counting the walls seen edge-on too adds points, never removes any.
  options.max_incidence_degrees = 90.0;
  for (const CovisiblePair& pair : ComputeCovisiblePairs(scene, views, options)) {
    const auto it = shared.find({pair.image_id1, pair.image_id2});
    EXPECT_GE(pair.num_shared_points, it == shared.end() ? 0 : it->second);
  }
}

TEST(Covisibility, SurfacePointsLieOnTheScene) {
  SceneModelOptions scene_options;
  scene_options.kind = SceneModelOptions::Kind::kTown;
  scene_options.town_half_size = 100;
  const SceneModel scene(scene_options);
  const std::vector<SurfacePoint> samples = scene.SampleSurfacePoints(
      2.0, Eigen::AlignedBox2d(Eigen::Vector2d(-20, -20), Eigen::Vector2d(20, 20)), 7);
  ASSERT_GT(samples.size(), 400u);  // The 40 x 40 m ground alone gives 400.
  // Every point is on the ground or in a building's box; a ray cast straight down onto a
  // ground point meets nothing below a building's top.
  int checked = 0;
  for (const auto& [point, normal] : samples) {
    EXPECT_NEAR(normal.norm(), 1.0, 1e-9);
    EXPECT_TRUE(point.z() == 0.0 || scene.Bounds().exteriorDistance(point) < 1e-6);
    if (point.z() != 0.0) continue;
    const Eigen::Vector3d origin = point + Eigen::Vector3d(0.0, 0.0, 50.0);
    SurfaceHit hit;
    if (!scene.Intersect(origin, Eigen::Vector3d(0, 0, -1), 1e9, &hit)) continue;
    // The nearest surface straight above the point is at or above it.
    EXPECT_GE(hit.point.z(), point.z() - 1e-6);
    ++checked;
  }
  EXPECT_GT(checked, 300);
}

}  // namespace
}  // namespace parallax
