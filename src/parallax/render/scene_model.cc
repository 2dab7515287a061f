#include "parallax/render/scene_model.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include "parallax/render/procedural_texture.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

constexpr double kEpsilon = 1e-7;
constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Temple dimensions in metres (centre at ground level). Three steps of the base: half sizes
// in x and y, top height.
constexpr std::array<std::array<double, 3>, 3> kSteps = {{{6.4, 4.4, 0.3}, {6.0, 4.0, 0.6}, {5.6, 3.6, 0.9}}};
constexpr double kFloor = 0.9;
constexpr double kColumnRadius = 0.33;
constexpr double kPlinthTop = 1.1;
constexpr double kCapitalBottom = 4.5;
constexpr double kArchitraveBottom = 4.8;
constexpr double kArchitraveTop = 5.6;
// Half extent of the paved plaza around a temple.
constexpr double kPlazaHalfX = 11.0;
constexpr double kPlazaHalfY = 8.5;

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
}

SceneModel::SceneModel(const SceneModelOptions& options) : options_(options) {
  options_.Check();
  next_texture_seed_ = static_cast<uint32_t>(options_.seed * 0x9E3779B97F4A7C15ull >> 32) ^
                       static_cast<uint32_t>(options_.seed);
  for (int k = 0; k < options_.num_temples; ++k) AddTemple(k);
  bounds_.setEmpty();
  for (const Primitive& primitive : primitives_) bounds_.extend(primitive.box);
  ground_radius_ = 0.5 * (options_.num_temples - 1) * options_.temple_spacing + 250.0;
  nodes_.reserve(2 * primitives_.size());
  BuildNode(0, static_cast<int>(primitives_.size()));
}

Eigen::Vector3d SceneModel::TempleCenter(int temple_idx) const {
  return Eigen::Vector3d(temple_idx * options_.temple_spacing, 0.0, 0.0);
}

void SceneModel::AddTemple(int temple_idx) {
  const Eigen::Vector3d c = TempleCenter(temple_idx);
  double z = 0.0;
  for (const auto& [half_x, half_y, top] : kSteps) {
    AddBox(c + Eigen::Vector3d(-half_x, -half_y, z), c + Eigen::Vector3d(half_x, half_y, top),
           Material::kStone);
    z = top;
  }
  // The cella: a walled room inside the peristyle.
  AddBox(c + Eigen::Vector3d(-3.2, -1.8, kFloor), c + Eigen::Vector3d(3.2, 1.8, kArchitraveBottom),
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
    AddBox(base + Eigen::Vector3d(-0.45, -0.45, kFloor), base + Eigen::Vector3d(0.45, 0.45, kPlinthTop),
           Material::kStone);
    AddCylinder(base.head<2>(), kColumnRadius, kPlinthTop, kCapitalBottom, Material::kColumn);
    AddBox(base + Eigen::Vector3d(-0.48, -0.48, kCapitalBottom),
           base + Eigen::Vector3d(0.48, 0.48, kArchitraveBottom), Material::kStone);
  }
  AddBox(c + Eigen::Vector3d(-5.5, -3.5, kArchitraveBottom), c + Eigen::Vector3d(5.5, 3.5, kArchitraveTop),
         Material::kStone);
  // Gabled roof: two slopes with a ridge along x, and a pediment at each end.
  const double ridge = kTempleHeight, eave_y = 3.7, eave_x = 5.7;
  for (const double side : {-1.0, 1.0}) {
    const Eigen::Vector3d a = c + Eigen::Vector3d(-eave_x, side * eave_y, kArchitraveTop);
    const Eigen::Vector3d b = c + Eigen::Vector3d(eave_x, side * eave_y, kArchitraveTop);
    const Eigen::Vector3d r1 = c + Eigen::Vector3d(-eave_x, 0.0, ridge);
    const Eigen::Vector3d r2 = c + Eigen::Vector3d(eave_x, 0.0, ridge);
    AddTriangle(a, b, r2, Eigen::Vector3d::UnitX(), Material::kRoof);
    AddTriangle(a, r2, r1, Eigen::Vector3d::UnitX(), Material::kRoof);
    const double x = side * 5.5;
    AddTriangle(c + Eigen::Vector3d(x, -3.5, kArchitraveTop), c + Eigen::Vector3d(x, 3.5, kArchitraveTop),
                c + Eigen::Vector3d(x, 0.0, ridge - 0.12), Eigen::Vector3d::UnitY(), Material::kStone);
  }
  // A few blocks (altars, pedestals, a stele) on the plaza, placed from the seed.
  uint32_t h = Mix32(next_texture_seed_ ^ (0x51ED27u * (temple_idx + 1)));
  for (int i = 0; i < 5; ++i) {
    const double angle = 2.0 * std::numbers::pi * (i + 0.6 * UnitFloat(h = Mix32(h))) / 5.0;
    const double distance = 8.0 + 2.0 * UnitFloat(h = Mix32(h));
    const Eigen::Vector3d center =
        c + Eigen::Vector3d(distance * std::cos(angle), 0.75 * distance * std::sin(angle), 0.0);
    const double half_x = 0.3 + 0.6 * UnitFloat(h = Mix32(h));
    const double half_y = 0.3 + 0.6 * UnitFloat(h = Mix32(h));
    const double height = 0.5 + 2.0 * UnitFloat(h = Mix32(h));
    AddBox(center + Eigen::Vector3d(-half_x, -half_y, 0.0), center + Eigen::Vector3d(half_x, half_y, height),
           i % 2 == 0 ? Material::kStone : Material::kWall);
  }
}

void SceneModel::AddBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max, Material material) {
  Primitive primitive;
  primitive.shape = Shape::kBox;
  primitive.material = material;
  primitive.texture_seed = Mix32(next_texture_seed_++);
  primitive.box = Eigen::AlignedBox3d(min, max);
  primitives_.push_back(primitive);
}

void SceneModel::AddCylinder(const Eigen::Vector2d& center, double radius, double z_min, double z_max,
                             Material material) {
  Primitive primitive;
  primitive.shape = Shape::kCylinder;
  primitive.material = material;
  primitive.texture_seed = Mix32(next_texture_seed_++);
  primitive.center = center;
  primitive.radius = radius;
  primitive.box = Eigen::AlignedBox3d(Eigen::Vector3d(center.x() - radius, center.y() - radius, z_min),
                                      Eigen::Vector3d(center.x() + radius, center.y() + radius, z_max));
  primitives_.push_back(primitive);
}

void SceneModel::AddTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                             const Eigen::Vector3d& u_direction, Material material) {
  Primitive primitive;
  primitive.shape = Shape::kTriangle;
  primitive.material = material;
  primitive.texture_seed = Mix32(next_texture_seed_++);
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
                   primitives_.begin() + first + count, [axis](const Primitive& a, const Primitive& b) {
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
      const Eigen::Vector3d point = origin + t * direction;
      uv = axis == 0 ? Eigen::Vector2d(point.y(), point.z())
                     : (axis == 1 ? Eigen::Vector2d(point.x(), point.z()) : Eigen::Vector2d(point.x(), point.y()));
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
      normal = primitive.normal.dot(direction) < 0 ? primitive.normal : Eigen::Vector3d(-primitive.normal);
      const Eigen::Vector3d point = origin + t * direction;
      uv = Eigen::Vector2d(point.dot(primitive.axis_u), point.dot(primitive.axis_v));
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
        point.head<2>() - 0.5 * (TempleCenter(0) + TempleCenter(options_.num_temples - 1)).head<2>();
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
      // Paved plaza around the nearest temple, earth and grass elsewhere.
      const int nearest = std::clamp(
          static_cast<int>(std::lround(hit.point.x() / options_.temple_spacing)), 0, options_.num_temples - 1);
      const Eigen::Vector3d local = hit.point - TempleCenter(nearest);
      const bool paved = std::abs(local.x()) < kPlazaHalfX && std::abs(local.y()) < kPlazaHalfY;
      return paved ? PavingAlbedo(p, hit.texture_seed, fp) : EarthAlbedo(p, hit.texture_seed, fp);
    }
    case Material::kStone: return MarbleAlbedo(p, hit.texture_seed, fp);
    case Material::kColumn: return ColumnAlbedo(p, hit.texture_seed, fp, static_cast<float>(kColumnRadius));
    case Material::kWall: return AshlarAlbedo(p, hit.texture_seed, fp);
    case Material::kRoof: return RoofTileAlbedo(p, hit.texture_seed, fp);
  }
  return Eigen::Vector3f::Constant(0.5f);
}

}  // namespace parallax
