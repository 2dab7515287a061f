#include "parallax/render/scene_model.h"

#include <gtest/gtest.h>

#include <cmath>

#include "parallax/render/procedural_texture.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

TEST(SceneModel, RaysHitTheKnownSurfaces) {
  const SceneModel scene;
  SurfaceHit hit;
  // Straight down onto the ridge of the roof.
  ASSERT_TRUE(scene.Intersect(Eigen::Vector3d(0, 0, 20), -Eigen::Vector3d::UnitZ(), 1e9, &hit));
  EXPECT_NEAR(hit.distance, 20 - SceneModel::kTempleHeight, 1e-9);
  EXPECT_EQ(hit.material, Material::kRoof);
  // Onto a roof slope: the ridge (y = 0, z = 7.4) falls to the eaves (y = -3.7, z = 5.6).
  ASSERT_TRUE(
      scene.Intersect(Eigen::Vector3d(1.0, -1.85, 20), -Eigen::Vector3d::UnitZ(), 1e9, &hit));
  EXPECT_NEAR(hit.point.z(), 6.5, 1e-9);
  EXPECT_NEAR(hit.normal.normalized().dot(Eigen::Vector3d(0, -1.8, 3.7).normalized()), 1.0, 1e-9);
  // Horizontally along the axis, between the columns of the short side, onto the cella wall.
  ASSERT_TRUE(scene.Intersect(Eigen::Vector3d(-30, 0, 3.5), Eigen::Vector3d::UnitX(), 1e9, &hit));
  EXPECT_NEAR(hit.point.x(), -3.2, 1e-9);
  EXPECT_EQ(hit.material, Material::kWall);
  EXPECT_NEAR(hit.normal.x(), -1.0, 1e-12);
  // A column of the long side: axis at (-4.75, -3.0), radius 0.33.
  ASSERT_TRUE(
      scene.Intersect(Eigen::Vector3d(-4.75, -30, 3.0), Eigen::Vector3d::UnitY(), 1e9, &hit));
  EXPECT_EQ(hit.material, Material::kColumn);
  EXPECT_NEAR(hit.point.y(), -3.33, 1e-9);
  // The ground away from the temple, and the sky.
  ASSERT_TRUE(scene.Intersect(Eigen::Vector3d(40, 40, 10), -Eigen::Vector3d::UnitZ(), 1e9, &hit));
  EXPECT_NEAR(hit.distance, 10, 1e-9);
  EXPECT_EQ(hit.material, Material::kGround);
  EXPECT_FALSE(scene.Intersect(Eigen::Vector3d(0, 0, 20), Eigen::Vector3d::UnitZ(), 1e9, &hit));
  EXPECT_FALSE(scene.Intersect(Eigen::Vector3d(0, 0, 20), -Eigen::Vector3d::UnitZ(), 5, &hit));
  // Beyond the ground disc there is only sky.
  EXPECT_FALSE(scene.Intersect(Eigen::Vector3d(1000, 0, 10), -Eigen::Vector3d::UnitZ(), 1e9, &hit));
}

TEST(SceneModel, ShadowRays) {
  const SceneModel scene;
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  // Under the roof, between a column and the cella: the roof blocks the sky straight up.
  EXPECT_TRUE(scene.Occluded(Eigen::Vector3d(0, -2.5, 1.0), up, 1e9));
  EXPECT_FALSE(scene.Occluded(Eigen::Vector3d(0, -2.5, 1.0), up, 2.0));
  EXPECT_FALSE(scene.Occluded(Eigen::Vector3d(40, 40, 0.01), up, 1e9));
}

TEST(SceneModel, RowOfTemples) {
  SceneModelOptions options;
  options.num_temples = 4;
  const SceneModel row(options);
  EXPECT_EQ(row.NumPrimitives(), 4 * SceneModel().NumPrimitives());
  EXPECT_NEAR(row.Bounds().max().z(), SceneModel::kTempleHeight, 1e-5);
  EXPECT_GT(row.Bounds().sizes().x(), 3 * options.temple_spacing + 12);
  SurfaceHit hit;
  for (int k = 0; k < options.num_temples; ++k) {
    ASSERT_TRUE(row.Intersect(row.TempleCenter(k) + Eigen::Vector3d(0, 0, 20),
                              -Eigen::Vector3d::UnitZ(), 1e9, &hit));
    EXPECT_EQ(hit.material, Material::kRoof);
  }
  options.num_temples = 0;
  EXPECT_THROW(SceneModel{options}, CheckError);
}

TEST(SceneModel, TwoRowsFaceEachOtherAcrossAStreet) {
  SceneModelOptions options;
  options.num_temples = 3;
  options.num_rows = 2;
  options.row_spacing = 24.0;
  const SceneModel street(options);
  EXPECT_EQ(street.NumTemples(), 6);
  EXPECT_EQ(street.NumPrimitives(), 6 * SceneModel().NumPrimitives());
  EXPECT_EQ(street.TempleCenter(2), Eigen::Vector3d(2 * options.temple_spacing, 0, 0));
  EXPECT_EQ(street.TempleCenter(4), Eigen::Vector3d(options.temple_spacing, 24.0, 0));
  SurfaceHit hit;
  for (int k = 0; k < street.NumTemples(); ++k) {
    ASSERT_TRUE(street.Intersect(street.TempleCenter(k) + Eigen::Vector3d(0, 0, 20),
                                 -Eigen::Vector3d::UnitZ(), 1e9, &hit));
    EXPECT_EQ(hit.material, Material::kRoof);
  }
  // Down the middle of the street the way is clear, between the rows' facades.
  EXPECT_FALSE(
      street.Intersect(Eigen::Vector3d(-10, 12, 1.6), Eigen::Vector3d::UnitX(), 1e9, &hit));
  // Looking across, a temple of each row (or a block on its plaza).
  ASSERT_TRUE(street.Intersect(Eigen::Vector3d(1, 12, 3.0), -Eigen::Vector3d::UnitY(), 1e9, &hit));
  EXPECT_GT(hit.point.y(), 1.7);
  EXPECT_LT(hit.point.y(), 9.0);
  ASSERT_TRUE(street.Intersect(Eigen::Vector3d(1, 12, 3.0), Eigen::Vector3d::UnitY(), 1e9, &hit));
  EXPECT_GT(hit.point.y(), 24.0 - 9.0);
  EXPECT_LT(hit.point.y(), 24.0 - 1.7);
  options.row_spacing = 5.0;
  EXPECT_THROW(SceneModel{options}, CheckError);
}

// Surfaces seen straight down over the temples' plazas, at the same offsets from temple 0
// and temple 1: how many are the same surface (material and height) with the same albedo, on
// the ground and off it.
struct CopyComparison {
  int num_buildings = 0, num_buildings_same = 0;
  int num_ground = 0, num_ground_same = 0;
  int num_shapes_differ = 0;
};

CopyComparison CompareTemples(const SceneModel& scene) {
  CopyComparison comparison;
  const Eigen::Vector3d offset = scene.TempleCenter(1) - scene.TempleCenter(0);
  SurfaceHit hit0, hit1;
  for (double x = -10.9; x < 11; x += 0.37) {
    for (double y = -8.4; y < 8.5; y += 0.41) {
      const Eigen::Vector3d origin(x, y, 20);
      if (!scene.Intersect(origin, -Eigen::Vector3d::UnitZ(), 1e9, &hit0) ||
          !scene.Intersect(origin + offset, -Eigen::Vector3d::UnitZ(), 1e9, &hit1)) {
        ADD_FAILURE() << "no hit at " << x << ", " << y;
        continue;
      }
      if (hit0.material != hit1.material || std::abs(hit0.distance - hit1.distance) > 1e-9) {
        ++comparison.num_shapes_differ;
        continue;
      }
      const bool same = (scene.Albedo(hit0, 0.005) - scene.Albedo(hit1, 0.005)).norm() < 1e-4;
      if (hit0.material == Material::kGround) {
        ++comparison.num_ground;
        comparison.num_ground_same += same;
      } else {
        ++comparison.num_buildings;
        comparison.num_buildings_same += same;
      }
    }
  }
  return comparison;
}

TEST(SceneModel, IdenticalTemplesDifferOnlyInTheirGround) {
  SceneModelOptions options;
  options.num_temples = 2;
  options.temple_spacing = 36.0;
  options.identical_temples = true;
  options.seed = 3;
  const CopyComparison twins = CompareTemples(SceneModel(options));
  // Temples, steps and blocks: the same shapes in the same places, textured alike.
  EXPECT_EQ(twins.num_shapes_differ, 0);
  EXPECT_GT(twins.num_buildings, 500);
  EXPECT_EQ(twins.num_buildings_same, twins.num_buildings);
  // The plaza and the earth around them are not copies.
  EXPECT_GT(twins.num_ground, 300);
  EXPECT_LT(twins.num_ground_same, twins.num_ground / 20);
  // From the side too: the colonnade and the cella behind it.
  const SceneModel scene(options);
  SurfaceHit hit0, hit1;
  for (int i = 0; i < 60; ++i) {
    const Eigen::Vector3d origin(-3.0 + 0.1 * i, -15.0, 1.0 + 0.06 * i);
    ASSERT_TRUE(scene.Intersect(origin, Eigen::Vector3d::UnitY(), 1e9, &hit0));
    ASSERT_TRUE(scene.Intersect(origin + Eigen::Vector3d(36.0, 0, 0), Eigen::Vector3d::UnitY(), 1e9,
                                &hit1));
    EXPECT_EQ(hit0.material, hit1.material);
    EXPECT_LT((scene.Albedo(hit0, 0.005) - scene.Albedo(hit1, 0.005)).norm(), 1e-4) << i;
  }

  // Without the option the second temple is its own (and the blocks stand elsewhere).
  options.identical_temples = false;
  const CopyComparison row = CompareTemples(SceneModel(options));
  EXPECT_GT(row.num_shapes_differ, 0);
  // (Mortar joints are one colour on every surface: those few points match anyway.)
  EXPECT_LT(row.num_buildings_same, row.num_buildings / 3);
}

// Standard deviation of the luminance difference between points `step` metres apart.
double TextureContrast(const SceneModel& scene, Material material, double step, double footprint) {
  SurfaceHit hit;
  hit.material = material;
  hit.texture_seed = 12345;
  double sum = 0, sum_squares = 0;
  int count = 0;
  for (int i = 0; i < 400; ++i) {
    const Eigen::Vector2d uv(0.37 * i + 3.1, 0.21 * (i % 17) - 1.3);
    hit.uv = uv;
    hit.point = Eigen::Vector3d(uv.x(), uv.y(), 0);
    const float a = scene.Albedo(hit, footprint).mean();
    hit.uv = uv + Eigen::Vector2d(step, 0);
    hit.point = Eigen::Vector3d(hit.uv.x(), hit.uv.y(), 0);
    const float b = scene.Albedo(hit, footprint).mean();
    sum += a - b;
    sum_squares += (a - b) * (a - b);
    ++count;
  }
  const double mean = sum / count;
  return std::sqrt(sum_squares / count - mean * mean);
}

TEST(SceneModel, TexturesAreRichAtSeveralScales) {
  const SceneModel scene;
  for (const Material material :
       {Material::kGround, Material::kStone, Material::kColumn, Material::kWall, Material::kRoof}) {
    // Seen from close by (2 mm per pixel), detail at 1 cm, 10 cm and 1 m.
    for (const double step : {0.01, 0.1, 1.0}) {
      EXPECT_GT(TextureContrast(scene, material, step, 0.002), 0.03)
          << "material " << static_cast<int>(material) << " step " << step;
    }
    // From far away (1 m per pixel) the centimetre detail is averaged out.
    EXPECT_LT(TextureContrast(scene, material, 0.01, 1.0), 0.01) << static_cast<int>(material);
  }
}

TEST(SceneModel, TexturesAreDeterministicAndSeeded) {
  SceneModelOptions options;
  options.seed = 5;
  const SceneModel a(options), b(options);
  options.seed = 6;
  const SceneModel c(options);
  SurfaceHit hit_a, hit_b, hit_c;
  int num_different = 0;
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector3d origin(-30, -0.5 + 0.02 * i, 1.0 + 0.05 * i);
    ASSERT_TRUE(a.Intersect(origin, Eigen::Vector3d::UnitX(), 1e9, &hit_a));
    ASSERT_TRUE(b.Intersect(origin, Eigen::Vector3d::UnitX(), 1e9, &hit_b));
    ASSERT_TRUE(c.Intersect(origin, Eigen::Vector3d::UnitX(), 1e9, &hit_c));
    EXPECT_EQ(a.Albedo(hit_a, 0.01), b.Albedo(hit_b, 0.01));
    if ((a.Albedo(hit_a, 0.01) - c.Albedo(hit_c, 0.01)).norm() > 1e-3) ++num_different;
  }
  EXPECT_GT(num_different, 40);
}

TEST(ProceduralTexture, NoiseIsBoundedAndCentred) {
  double sum = 0;
  for (int i = 0; i < 10000; ++i) {
    const Eigen::Vector2f p(0.731f * i, 0.377f * (i % 101));
    const float value = ValueNoise(p.x(), p.y(), 7);
    ASSERT_GE(value, 0.0f);
    ASSERT_LE(value, 1.0f);
    const float fbm = Fbm(p, 3, 1.0f, 6, 0.001f);
    ASSERT_GE(fbm, 0.0f);
    ASSERT_LE(fbm, 1.0f);
    sum += fbm;
  }
  EXPECT_NEAR(sum / 10000, 0.5, 0.02);
  // Below the footprint every octave has faded: a constant.
  EXPECT_EQ(Fbm(Eigen::Vector2f(1.3f, 2.7f), 3, 1.0f, 6, 10.0f), 0.5f);
}

}  // namespace
}  // namespace parallax
