#include "parallax/render/scene_model.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "parallax/render/procedural_texture.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

constexpr double kEpsilon = 1e-7;
constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Temple dimensions in metres (centre at ground level). Three steps of the base: half sizes
// in x and y, top height.
constexpr std::array<std::array<double, 3>, 3> kSteps = {
    {{6.4, 4.4, 0.3}, {6.0, 4.0, 0.6}, {5.6, 3.6, 0.9}}};
constexpr double kFloor = 0.9;
constexpr double kColumnRadius = 0.33;
constexpr double kPlinthTop = 1.1;
constexpr double kCapitalBottom = 4.5;
constexpr double kArchitraveBottom = 4.8;
constexpr double kArchitraveTop = 5.6;
// Half extent of the paved plaza around a temple.
constexpr double kPlazaHalfX = 11.0;
constexpr double kPlazaHalfY = 8.5;
// Town blocks: pitch (street centre to street centre) and street width, in metres.
constexpr double kBlockPitch = 48.0;
constexpr double kStreetWidth = 8.0;
// Roofs and fields come in this many textures each.
constexpr uint32_t kNumRepeatedTextures = 4;

// Entry and exit distances of a ray through a box (inv_direction = 1 / direction).
inline bool SlabTest(const Eigen::AlignedBox3d& box, const Eigen::Vector3d& origin,
                     const Eigen::Vector3d& inv_direction, double max_distance, double* t_near) {
  const Eigen::Vector3d t1 = (box.min() - origin).cwiseProduct(inv_direction);
  const Eigen::Vector3d t2 = (box.max() - origin).cwiseProduct(inv_direction);
  const double t_enter = t1.cwiseMin(t2).maxCoeff();
  const double t_exit = t1.cwiseMax(t2).minCoeff();
  *t_near = t_enter;
  return t_enter <= t_exit && t_exit > 0.0 && t_enter < max_distance;
}

}  // namespace

void SceneModelOptions::Check() const {
  PARALLAX_CHECK_GE(num_temples, 1);
  PARALLAX_CHECK_GT(temple_spacing, 2 * kPlazaHalfX * 0.7);
  PARALLAX_CHECK_GE(num_rows, 1);
  PARALLAX_CHECK_GT(row_spacing, 2 * kSteps[0][1]);  // Rows may share a plaza, not overlap.
  PARALLAX_CHECK_GT(town_half_size, 0.0);
}

SceneModel::SceneModel(const SceneModelOptions& options) : options_(options) {
  options_.Check();
  next_texture_seed_ = static_cast<uint32_t>(options_.seed * 0x9E3779B97F4A7C15ull >> 32) ^
                       static_cast<uint32_t>(options_.seed);
  layout_seed_ = Mix32(next_texture_seed_ ^ 0x7A3B9C1Du);
  first_texture_seed_ = next_texture_seed_;
  if (options_.kind == SceneModelOptions::Kind::kTown) {
    options_.num_temples = 1;  // The ground disc is centred on temple 0's place, the origin.
    options_.num_rows = 1;
    AddTown();
    ground_radius_ = std::sqrt(2.0) * options_.town_half_size + 300.0;
  } else {
    for (int k = 0; k < NumTemples(); ++k) AddTemple(k);
    ground_radius_ = 0.5 * (options_.num_temples - 1) * options_.temple_spacing + 250.0;
  }
  bounds_.setEmpty();
  for (const Primitive& primitive : primitives_) bounds_.extend(primitive.box);
  nodes_.reserve(2 * primitives_.size());
  BuildNode(0, static_cast<int>(primitives_.size()));
}

std::vector<SurfacePoint> SceneModel::SampleSurfacePoints(double spacing,
                                                          const Eigen::AlignedBox2d& ground_region,
                                                          uint64_t seed) const {
  PARALLAX_CHECK_GT(spacing, 0.0);
  std::mt19937_64 engine(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<SurfacePoint> points;
  // A jittered grid on a parallelogram `origin + s * edge1 + t * edge2`, s, t in [0, 1];
  // `triangle` keeps the half with s + t <= 1.
  const auto sample_patch = [&](const Eigen::Vector3d& origin, const Eigen::Vector3d& edge1,
                                const Eigen::Vector3d& edge2, bool triangle) {
    const Eigen::Vector3d normal = edge1.cross(edge2).normalized();
    const int n1 = std::max(1, static_cast<int>(std::ceil(edge1.norm() / spacing)));
    const int n2 = std::max(1, static_cast<int>(std::ceil(edge2.norm() / spacing)));
    for (int i = 0; i < n1; ++i) {
      for (int j = 0; j < n2; ++j) {
        const double s = (i + unit(engine)) / n1, t = (j + unit(engine)) / n2;
        if (triangle && s + t > 1.0) continue;
        points.push_back({origin + s * edge1 + t * edge2, normal});
      }
    }
  };
  if (!ground_region.isEmpty()) {
    const Eigen::Vector2d size = ground_region.sizes();
    sample_patch(Eigen::Vector3d(ground_region.min().x(), ground_region.min().y(), 0.0),
                 Eigen::Vector3d(size.x(), 0.0, 0.0), Eigen::Vector3d(0.0, size.y(), 0.0), false);
  }
  for (const Primitive& primitive : primitives_) {
    switch (primitive.shape) {
      case Shape::kBox: {
        const Eigen::Vector3d& lo = primitive.box.min();
        const Eigen::Vector3d size = primitive.box.sizes();
        const Eigen::Vector3d x(size.x(), 0, 0), y(0, size.y(), 0), z(0, 0, size.z());
        sample_patch(lo + z, x, y, false);  // Top.
        sample_patch(lo, x, z, false);
        sample_patch(lo + y, x, z, false);
        sample_patch(lo, y, z, false);
        sample_patch(lo + x, y, z, false);
        break;
      }
      case Shape::kCylinder: {
        const double height = primitive.box.sizes().z();
        const int n = std::max(
            3, static_cast<int>(std::ceil(2 * std::numbers::pi * primitive.radius / spacing)));
        const int m = std::max(1, static_cast<int>(std::ceil(height / spacing)));
        for (int i = 0; i < n; ++i) {
          for (int j = 0; j < m; ++j) {
            const double angle = 2 * std::numbers::pi * (i + unit(engine)) / n;
            const Eigen::Vector3d normal(std::cos(angle), std::sin(angle), 0.0);
            const Eigen::Vector3d position =
                Eigen::Vector3d(primitive.center.x(), primitive.center.y(),
                                primitive.box.min().z() + height * (j + unit(engine)) / m) +
                primitive.radius * normal;
            points.push_back({position, normal});
          }
        }
        break;
      }
      case Shape::kTriangle:
        sample_patch(primitive.vertex, primitive.edge1, primitive.edge2, true);
        break;
    }
  }
  return points;
}

Eigen::Vector3d SceneModel::TempleCenter(int temple_idx) const {
  const int row = temple_idx / options_.num_temples;
  return Eigen::Vector3d((temple_idx % options_.num_temples) * options_.temple_spacing,
                         row * options_.row_spacing, 0.0);
}

void SceneModel::AddTemple(int temple_idx) {
  const Eigen::Vector3d c = TempleCenter(temple_idx);
  // A copy of temple 0: the same seeds, in the same order, textured from its own centre.
  const bool copy = options_.identical_temples;
  if (copy) next_texture_seed_ = first_texture_seed_;
  const Eigen::Vector3d uv_origin = copy ? c : Eigen::Vector3d::Zero();
  const auto add_box = [&](const Eigen::Vector3d& min, const Eigen::Vector3d& max,
                           Material material) { AddBox(min, max, material, uv_origin); };
  double z = 0.0;
  for (const auto& [half_x, half_y, top] : kSteps) {
    add_box(c + Eigen::Vector3d(-half_x, -half_y, z), c + Eigen::Vector3d(half_x, half_y, top),
            Material::kStone);
    z = top;
  }
  // The cella: a walled room inside the peristyle.
  add_box(c + Eigen::Vector3d(-3.2, -1.8, kFloor), c + Eigen::Vector3d(3.2, 1.8, kArchitraveBottom),
          Material::kWall);
  // Peristyle: 6 columns on each long side, 2 more on each short side.
  std::vector<Eigen::Vector2d> columns;
  for (int i = 0; i < 6; ++i) {
    columns.emplace_back(-4.75 + 1.9 * i, -3.0);
    columns.emplace_back(-4.75 + 1.9 * i, 3.0);
  }
  for (const double x : {-4.75, 4.75}) {
    columns.emplace_back(x, -1.0);
    columns.emplace_back(x, 1.0);
  }
  for (const Eigen::Vector2d& xy : columns) {
    const Eigen::Vector3d base = c + Eigen::Vector3d(xy.x(), xy.y(), 0.0);
    add_box(base + Eigen::Vector3d(-0.45, -0.45, kFloor),
            base + Eigen::Vector3d(0.45, 0.45, kPlinthTop), Material::kStone);
    // Column textures run around the axis and up: the same on every copy.
    AddCylinder(base.head<2>(), kColumnRadius, kPlinthTop, kCapitalBottom, Material::kColumn);
    add_box(base + Eigen::Vector3d(-0.48, -0.48, kCapitalBottom),
            base + Eigen::Vector3d(0.48, 0.48, kArchitraveBottom), Material::kStone);
  }
  add_box(c + Eigen::Vector3d(-5.5, -3.5, kArchitraveBottom),
          c + Eigen::Vector3d(5.5, 3.5, kArchitraveTop), Material::kStone);
  // Gabled roof: two slopes with a ridge along x, and a pediment at each end.
  const double ridge = kTempleHeight, eave_y = 3.7, eave_x = 5.7;
  for (const double side : {-1.0, 1.0}) {
    const Eigen::Vector3d a = c + Eigen::Vector3d(-eave_x, side * eave_y, kArchitraveTop);
    const Eigen::Vector3d b = c + Eigen::Vector3d(eave_x, side * eave_y, kArchitraveTop);
    const Eigen::Vector3d r1 = c + Eigen::Vector3d(-eave_x, 0.0, ridge);
    const Eigen::Vector3d r2 = c + Eigen::Vector3d(eave_x, 0.0, ridge);
    AddTriangle(a, b, r2, Eigen::Vector3d::UnitX(), Material::kRoof, uv_origin);
    AddTriangle(a, r2, r1, Eigen::Vector3d::UnitX(), Material::kRoof, uv_origin);
    const double x = side * 5.5;
    AddTriangle(c + Eigen::Vector3d(x, -3.5, kArchitraveTop),
                c + Eigen::Vector3d(x, 3.5, kArchitraveTop),
                c + Eigen::Vector3d(x, 0.0, ridge - 0.12), Eigen::Vector3d::UnitY(),
                Material::kStone, uv_origin);
  }
  // A few blocks (altars, pedestals, a stele) on the plaza, placed from the seed.
  uint32_t h = Mix32(next_texture_seed_ ^ (0x51ED27u * ((copy ? 0 : temple_idx) + 1)));
  for (int i = 0; i < 5; ++i) {
    const double angle = 2.0 * std::numbers::pi * (i + 0.6 * UnitFloat(h = Mix32(h))) / 5.0;
    const double distance = 8.0 + 2.0 * UnitFloat(h = Mix32(h));
    const Eigen::Vector3d center =
        c + Eigen::Vector3d(distance * std::cos(angle), 0.75 * distance * std::sin(angle), 0.0);
    const double half_x = 0.3 + 0.6 * UnitFloat(h = Mix32(h));
    const double half_y = 0.3 + 0.6 * UnitFloat(h = Mix32(h));
    const double height = 0.5 + 2.0 * UnitFloat(h = Mix32(h));
    add_box(center + Eigen::Vector3d(-half_x, -half_y, 0.0),
            center + Eigen::Vector3d(half_x, half_y, height),
            i % 2 == 0 ? Material::kStone : Material::kWall);
  }
}

bool SceneModel::IsFieldBlock(int bx, int by) const {
  return UnitFloat(HashCell(bx, by, layout_seed_ ^ 0xF1E1D5u)) < 0.3f;
}

void SceneModel::AddTown() {
  const int num_blocks = static_cast<int>(std::ceil(options_.town_half_size / kBlockPitch));
  // Repeated textures are drawn from the seed once, so every copy is the same.
  const uint32_t roof_seed = Mix32(layout_seed_ ^ 0x0F00Fu);
  for (int by = -num_blocks; by < num_blocks; ++by) {
    for (int bx = -num_blocks; bx < num_blocks; ++bx) {
      if (IsFieldBlock(bx, by)) continue;
      const Eigen::Vector2d block_min(bx * kBlockPitch + kStreetWidth,
                                      by * kBlockPitch + kStreetWidth);
      const double lot_size = 0.5 * (kBlockPitch - kStreetWidth);
      for (int lot = 0; lot < 4; ++lot) {
        uint32_t h = HashCell(2 * bx + lot % 2, 2 * by + lot / 2, layout_seed_ ^ 0xB0115u);
        if (UnitFloat(h) < 0.15f) continue;  // An empty lot.
        const int type = static_cast<int>((h = Mix32(h)) % 3);
        // Houses of three sizes (x by y by wall height); type 2 is a flat-roofed block.
        const double sizes[3][3] = {{10.0, 8.0, 4.0}, {13.0, 9.0, 5.5}, {15.0, 12.0, 11.0}};
        const bool rotated = (Mix32(h + 1) & 1) != 0;
        const double size_x = sizes[type][rotated ? 1 : 0], size_y = sizes[type][rotated ? 0 : 1];
        const double wall_height = sizes[type][2];
        const Eigen::Vector2d lot_min = block_min + lot_size * Eigen::Vector2d(lot % 2, lot / 2);
        const Eigen::Vector2d slack(lot_size - 2.0 - size_x, lot_size - 2.0 - size_y);
        const Eigen::Vector2d min =
            lot_min + Eigen::Vector2d(1.0 + slack.x() * UnitFloat(Mix32(h + 2)),
                                      1.0 + slack.y() * UnitFloat(Mix32(h + 3)));
        const Eigen::Vector3d low(min.x(), min.y(), 0.0);
        const Eigen::Vector3d high(min.x() + size_x, min.y() + size_y, wall_height);
        AddBox(low, high, Material::kWall);
        if (type == 2) continue;
        // A gabled roof, ridge along the longer side, textured in the roof's own frame: the
        // tiles of every roof line up the same way, their weathering is the house's own.
        const uint32_t texture = Mix32(roof_seed + Mix32(h + 4));
        const double ridge_height = wall_height + 0.35 * std::min(size_x, size_y);
        const Eigen::Vector3d along =
            size_x >= size_y ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
        const Eigen::Vector3d across =
            size_x >= size_y ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitX();
        const double length = size_x >= size_y ? size_x : size_y,
                     width = size_x >= size_y ? size_y : size_x;
        const Eigen::Vector3d eave0(low.x(), low.y(), wall_height);
        const Eigen::Vector3d ridge0 =
            eave0 + 0.5 * width * across + (ridge_height - wall_height) * Eigen::Vector3d::UnitZ();
        for (const double side : {0.0, 1.0}) {
          const Eigen::Vector3d a = eave0 + side * width * across;
          const Eigen::Vector3d b = a + length * along;
          AddTriangle(a, b, ridge0 + length * along, along, Material::kRoof, a, texture);
          AddTriangle(a, ridge0 + length * along, ridge0, along, Material::kRoof, a, texture);
          // The gable ends.
          const Eigen::Vector3d end = eave0 + side * length * along;
          AddTriangle(end, end + width * across, ridge0 + side * length * along, across,
                      Material::kWall);
        }
      }
    }
  }
}

Eigen::Vector3f SceneModel::TownGroundAlbedo(const SurfaceHit& hit, float footprint) const {
  const double x = hit.point.x(), y = hit.point.y();
  const int bx = static_cast<int>(std::floor(x / kBlockPitch)),
            by = static_cast<int>(std::floor(y / kBlockPitch));
  const Eigen::Vector2f local(static_cast<float>(x - bx * kBlockPitch),
                              static_cast<float>(y - by * kBlockPitch));
  if (local.x() < kStreetWidth || local.y() < kStreetWidth) {
    // Streets along x where local y is small, along y otherwise; v is across the street.
    const float half = 0.5f * static_cast<float>(kStreetWidth);
    const bool along_x =
        local.y() < kStreetWidth && (local.x() >= kStreetWidth || local.y() < local.x());
    // Texture in world coordinates: no two streets alike but for their markings.
    return along_x ? AsphaltAlbedo(hit.uv.cast<float>(), static_cast<float>(x), local.y() - half,
                                   hit.texture_seed, footprint)
                   : AsphaltAlbedo(hit.uv.cast<float>(), static_cast<float>(y), local.x() - half,
                                   hit.texture_seed, footprint);
  }
  const uint32_t block = HashCell(bx, by, hit.texture_seed);
  if (IsFieldBlock(bx, by)) {
    // One of four crops (row spacing and colour) in the block's own frame (rows along x or
    // y); the soil's detail is the block's own, as no two real fields are pixel copies.
    const uint32_t crop = Mix32(hit.texture_seed + block % kNumRepeatedTextures);
    const Eigen::Vector2f uv = (crop & 1) ? local : Eigen::Vector2f(local.y(), local.x());
    const float tone =
        0.9f + 0.2f * Fbm(hit.uv.cast<float>(), hit.texture_seed + 5, 90.0f, 2, footprint);
    return tone * FieldAlbedo(uv, crop, Mix32(block), footprint);
  }
  return EarthAlbedo(hit.uv.cast<float>(), hit.texture_seed, footprint);
}

void SceneModel::AddBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max, Material material,
                        const Eigen::Vector3d& uv_origin) {
  Primitive primitive;
  primitive.shape = Shape::kBox;
  primitive.material = material;
  primitive.texture_seed = Mix32(next_texture_seed_++);
  primitive.box = Eigen::AlignedBox3d(min, max);
  primitive.uv_origin = uv_origin;
  primitives_.push_back(primitive);
}

void SceneModel::AddCylinder(const Eigen::Vector2d& center, double radius, double z_min,
                             double z_max, Material material) {
  Primitive primitive;
  primitive.shape = Shape::kCylinder;
  primitive.material = material;
  primitive.texture_seed = Mix32(next_texture_seed_++);
  primitive.center = center;
  primitive.radius = radius;
  primitive.box =
      Eigen::AlignedBox3d(Eigen::Vector3d(center.x() - radius, center.y() - radius, z_min),
                          Eigen::Vector3d(center.x() + radius, center.y() + radius, z_max));
  primitives_.push_back(primitive);
}

void SceneModel::AddTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& c, const Eigen::Vector3d& u_direction,
                             Material material, const Eigen::Vector3d& uv_origin,
                             std::optional<uint32_t> texture_seed) {
  Primitive primitive;
  primitive.shape = Shape::kTriangle;
  primitive.material = material;
  primitive.texture_seed = texture_seed ? *texture_seed : Mix32(next_texture_seed_++);
  primitive.uv_origin = uv_origin;
  primitive.vertex = a;
  primitive.edge1 = b - a;
  primitive.edge2 = c - a;
  primitive.normal = primitive.edge1.cross(primitive.edge2).normalized();
  primitive.axis_u =
      (u_direction - u_direction.dot(primitive.normal) * primitive.normal).normalized();
  primitive.axis_v = primitive.normal.cross(primitive.axis_u);
  primitive.box = Eigen::AlignedBox3d(a, a);
  primitive.box.extend(b);
  primitive.box.extend(c);
  // Thin boxes still need a positive extent for the slab test to be robust.
  primitive.box.min().array() -= 1e-6;
  primitive.box.max().array() += 1e-6;
  primitives_.push_back(primitive);
}

int SceneModel::BuildNode(int first, int count) {
  const int index = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  Eigen::AlignedBox3d box;
  box.setEmpty();
  Eigen::AlignedBox3d centers;
  centers.setEmpty();
  for (int i = first; i < first + count; ++i) {
    box.extend(primitives_[i].box);
    centers.extend(primitives_[i].box.center());
  }
  nodes_[index].box = box;
  if (count <= 2) {
    nodes_[index].first = first;
    nodes_[index].count = count;
    return index;
  }
  // Median split along the longest axis of the centres.
  int axis;
  centers.sizes().maxCoeff(&axis);
  const int half = count / 2;
  std::nth_element(primitives_.begin() + first, primitives_.begin() + first + half,
                   primitives_.begin() + first + count,
                   [axis](const Primitive& a, const Primitive& b) {
                     return a.box.center()[axis] < b.box.center()[axis];
                   });
  const int left = BuildNode(first, half);
  const int right = BuildNode(first + half, count - half);
  nodes_[index].left = left;
  nodes_[index].right = right;
  return index;
}

bool SceneModel::IntersectPrimitive(const Primitive& primitive, const Eigen::Vector3d& origin,
                                    const Eigen::Vector3d& direction,
                                    const Eigen::Vector3d& inv_direction, double max_distance,
                                    SurfaceHit* hit) const {
  double t = kInfinity;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();
  uint32_t texture_seed = primitive.texture_seed;
  switch (primitive.shape) {
    case Shape::kBox: {
      const Eigen::Vector3d t1 = (primitive.box.min() - origin).cwiseProduct(inv_direction);
      const Eigen::Vector3d t2 = (primitive.box.max() - origin).cwiseProduct(inv_direction);
      const Eigen::Vector3d t_min = t1.cwiseMin(t2);
      int axis;
      const double t_enter = t_min.maxCoeff(&axis);
      const double t_exit = t1.cwiseMax(t2).minCoeff();
      // Rays starting inside a box (never the case for cameras) pass through it.
      if (t_enter > t_exit || t_enter <= kEpsilon || t_enter >= max_distance) return false;
      t = t_enter;
      if (hit == nullptr) return true;
      normal = Eigen::Vector3d::Zero();
      normal[axis] = direction[axis] > 0 ? -1.0 : 1.0;
      const Eigen::Vector3d point = (origin + t * direction) - primitive.uv_origin;
      uv = axis == 0 ? Eigen::Vector2d(point.y(), point.z())
                     : (axis == 1 ? Eigen::Vector2d(point.x(), point.z())
                                  : Eigen::Vector2d(point.x(), point.y()));
      texture_seed = Mix32(texture_seed + 2 * axis + (normal[axis] > 0 ? 1 : 0));
      break;
    }
    case Shape::kCylinder: {
      const double dx = origin.x() - primitive.center.x(), dy = origin.y() - primitive.center.y();
      const double a = direction.x() * direction.x() + direction.y() * direction.y();
      if (a < 1e-14) return false;
      const double b = dx * direction.x() + dy * direction.y();
      const double c = dx * dx + dy * dy - primitive.radius * primitive.radius;
      const double discriminant = b * b - a * c;
      if (discriminant < 0.0) return false;
      t = (-b - std::sqrt(discriminant)) / a;
      if (t <= kEpsilon || t >= max_distance) return false;
      const double z = origin.z() + t * direction.z();
      if (z < primitive.box.min().z() || z > primitive.box.max().z()) return false;
      if (hit == nullptr) return true;
      normal = Eigen::Vector3d((dx + t * direction.x()) / primitive.radius,
                               (dy + t * direction.y()) / primitive.radius, 0.0);
      uv = Eigen::Vector2d(std::atan2(normal.y(), normal.x()) * primitive.radius, z);
      break;
    }
    case Shape::kTriangle: {
      // Moeller-Trumbore, two-sided.
      const Eigen::Vector3d p = direction.cross(primitive.edge2);
      const double determinant = primitive.edge1.dot(p);
      if (std::abs(determinant) < 1e-14) return false;
      const double inv_determinant = 1.0 / determinant;
      const Eigen::Vector3d s = origin - primitive.vertex;
      const double u = s.dot(p) * inv_determinant;
      if (u < 0.0 || u > 1.0) return false;
      const Eigen::Vector3d q = s.cross(primitive.edge1);
      const double v = direction.dot(q) * inv_determinant;
      if (v < 0.0 || u + v > 1.0) return false;
      t = primitive.edge2.dot(q) * inv_determinant;
      if (t <= kEpsilon || t >= max_distance) return false;
      if (hit == nullptr) return true;
      normal = primitive.normal.dot(direction) < 0 ? primitive.normal
                                                   : Eigen::Vector3d(-primitive.normal);
      const Eigen::Vector3d point = origin + t * direction;
      const Eigen::Vector3d from_origin = point - primitive.uv_origin;
      uv = Eigen::Vector2d(from_origin.dot(primitive.axis_u), from_origin.dot(primitive.axis_v));
      break;
    }
  }
  hit->distance = t;
  hit->point = origin + t * direction;
  hit->normal = normal;
  hit->uv = uv;
  hit->material = primitive.material;
  hit->texture_seed = texture_seed;
  return true;
}

template <bool kAnyHit>
bool SceneModel::Traverse(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                          double max_distance, SurfaceHit* hit) const {
  const Eigen::Vector3d inv_direction = direction.cwiseInverse();
  double best = max_distance;
  bool found = false;
  std::array<int, 64> stack;
  int stack_size = 0;
  double t_near;
  if (!SlabTest(nodes_[0].box, origin, inv_direction, best, &t_near)) return false;
  stack[stack_size++] = 0;
  while (stack_size > 0) {
    const Node& node = nodes_[stack[--stack_size]];
    if (node.left < 0) {
      for (int i = node.first; i < node.first + node.count; ++i) {
        if (IntersectPrimitive(primitives_[i], origin, direction, inv_direction, best,
                               kAnyHit ? nullptr : hit)) {
          if (kAnyHit) return true;
          found = true;
          best = hit->distance;
        }
      }
      continue;
    }
    double t_left, t_right;
    const bool hit_left = SlabTest(nodes_[node.left].box, origin, inv_direction, best, &t_left);
    const bool hit_right = SlabTest(nodes_[node.right].box, origin, inv_direction, best, &t_right);
    // Push the farther child first so that the nearer one is visited first.
    if (hit_left && hit_right) {
      if (t_left < t_right) {
        stack[stack_size++] = node.right;
        stack[stack_size++] = node.left;
      } else {
        stack[stack_size++] = node.left;
        stack[stack_size++] = node.right;
      }
    } else if (hit_left) {
      stack[stack_size++] = node.left;
    } else if (hit_right) {
      stack[stack_size++] = node.right;
    }
  }
  return found;
}

bool SceneModel::Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                           double max_distance, SurfaceHit* hit) const {
  double best = max_distance;
  bool found = false;
  // The ground plane z = 0, a disc around the middle of the row.
  if (direction.z() < -1e-12 && origin.z() > 0.0) {
    const double t = -origin.z() / direction.z();
    const Eigen::Vector3d point = origin + t * direction;
    const Eigen::Vector2d from_middle =
        point.head<2>() - 0.5 * (TempleCenter(0) + TempleCenter(NumTemples() - 1)).head<2>();
    if (t < best && from_middle.norm() < ground_radius_) {
      best = t;
      found = true;
      hit->distance = t;
      hit->point = point;
      hit->point.z() = 0.0;
      hit->normal = Eigen::Vector3d::UnitZ();
      hit->uv = point.head<2>();
      hit->material = Material::kGround;
      hit->texture_seed = Mix32(next_texture_seed_ ^ 0x6A09E667u);
    }
  }
  if (Traverse<false>(origin, direction, best, hit)) found = true;
  return found;
}

bool SceneModel::Occluded(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                          double max_distance) const {
  return Traverse<true>(origin, direction, max_distance, nullptr);
}

Eigen::Vector3f SceneModel::SkyColor(const Eigen::Vector3d& direction) {
  const float elevation = static_cast<float>(std::clamp(direction.z(), 0.0, 1.0));
  const Eigen::Vector3f horizon(0.86f, 0.89f, 0.93f), zenith(0.42f, 0.60f, 0.86f);
  return horizon + (zenith - horizon) * std::sqrt(elevation);
}

Eigen::Vector3f SceneModel::Albedo(const SurfaceHit& hit, double footprint) const {
  const Eigen::Vector2f p = hit.uv.cast<float>();
  const float fp = static_cast<float>(std::max(footprint, 1e-5));
  switch (hit.material) {
    case Material::kGround: {
      if (options_.kind == SceneModelOptions::Kind::kTown) return TownGroundAlbedo(hit, fp);
      // Paved plaza around the nearest temple, earth and grass elsewhere.
      const int nearest =
          std::clamp(static_cast<int>(std::lround(hit.point.x() / options_.temple_spacing)), 0,
                     options_.num_temples - 1);
      const int row =
          std::clamp(static_cast<int>(std::lround(hit.point.y() / options_.row_spacing)), 0,
                     options_.num_rows - 1);
      const Eigen::Vector3d local = hit.point - TempleCenter(row * options_.num_temples + nearest);
      const bool paved = std::abs(local.x()) < kPlazaHalfX && std::abs(local.y()) < kPlazaHalfY;
      return paved ? PavingAlbedo(p, hit.texture_seed, fp) : EarthAlbedo(p, hit.texture_seed, fp);
    }
    case Material::kStone:
      return MarbleAlbedo(p, hit.texture_seed, fp);
    case Material::kColumn:
      return ColumnAlbedo(p, hit.texture_seed, fp, static_cast<float>(kColumnRadius));
    case Material::kWall:
      return AshlarAlbedo(p, hit.texture_seed, fp);
    case Material::kRoof:
      return RoofTileAlbedo(p, hit.texture_seed, fp);
  }
  return Eigen::Vector3f::Constant(0.5f);
}

}  // namespace parallax
