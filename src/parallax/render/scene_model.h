#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <vector>

namespace parallax {

// Surface kinds; each has its own procedural texture.
enum class Material : uint8_t { kGround, kStone, kColumn, kWall, kRoof };

struct SceneModelOptions {
  // What stands on the ground.
  enum class Kind {
    kTemples,  // a row of temples on a plaza (ring, hemisphere and sequence views)
    kTown,     // a street grid of houses, apartment blocks and fields (aerial surveys)
  };
  Kind kind = Kind::kTemples;
  // kTown: half the side in metres of the square of streets centred at the origin.
  double town_half_size = 150.0;
  // kTemples: number of temples, in a row along world +x (a long row for long sequences).
  int num_temples = 1;
  // Distance in metres between the centres of neighbouring temples.
  double temple_spacing = 18.0;
  // kTemples: rows of num_temples each, row r along +x at y = r * row_spacing (two rows face
  // each other across a street).
  int num_rows = 1;
  // Distance in metres between the centre lines of neighbouring rows.
  double row_spacing = 30.0;
  // kTemples: every temple a copy of the first (geometry, textures and blocks), textured in its
  // own frame, so that only the ground around each (textured in world coordinates) tells them
  // apart: repeated structure that can fold a reconstruction.
  bool identical_temples = false;
  // Seed of the textures and of the small blocks scattered around each temple.
  uint64_t seed = 0;

  void Check() const;
};

// A point on a surface and the surface's unit normal there (either side).
struct SurfacePoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
};

// A ray's nearest surface.
struct SurfaceHit {
  // Ray parameter: distance from the origin along the unit direction.
  double distance = 0.0;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  // Unit normal facing the ray's origin.
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  // Texture coordinates in metres on the surface.
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();
  Material material = Material::kGround;
  // Per-surface texture seed, so that no two surfaces look alike.
  uint32_t texture_seed = 0;
};

// A procedurally textured temple scene made of analytic primitives, in metres, world z up:
// a large ground plane (z = 0) and, per temple, a three-step base, a cella (a walled box), a
// peristyle of columns with plinths and capitals, an architrave slab and a gabled roof, plus
// a few stone blocks around it. Temple k is centred at (k * temple_spacing, 0, 0), about
// 12 m long (x), 8 m wide (y) and 7.4 m high; a second row, if any, stands row_spacing
// further along +y. Textures are deterministic functions of the
// surface point and the seed, rich from metres down to centimetres (fractal value noise,
// blocks, veins, speckles) so that SIFT finds stable keypoints on every surface; they fade
// detail finer than the pixel footprint (anti-aliasing and speed).
//
// The town (Kind::kTown) is a grid of 48 m blocks between 8 m streets. A block is a field
// (crop rows) or holds up to four buildings: houses with gabled roofs and flat-roofed blocks.
// Like real surveys it repeats itself: houses come in three sizes, roofs and fields in four
// textures each, laid out in the building's own coordinates, so that many roofs and fields
// look exactly alike and only their surroundings tell them apart.
class SceneModel {
 public:
  explicit SceneModel(const SceneModelOptions& options = {});

  // Nearest surface along origin + t * direction with 0 < t < max_distance (direction of
  // unit length). Returns false when the ray reaches the sky.
  bool Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                 double max_distance, SurfaceHit* hit) const;
  // True when anything blocks the segment (for shadow rays).
  bool Occluded(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                double max_distance) const;
  // Diffuse reflectance (RGB in [0, 1]) at a hit; `footprint` is the size in metres of one
  // pixel there, below which texture detail is averaged out.
  Eigen::Vector3f Albedo(const SurfaceHit& hit, double footprint) const;
  // Colour of the sky in a direction.
  static Eigen::Vector3f SkyColor(const Eigen::Vector3d& direction);

  // Points about `spacing` metres apart on every surface: a jittered grid on the ground
  // inside `ground_region` (x, y), and on each primitive's faces but the bottom ones. The
  // ground truth of which views see the same part of the scene. Deterministic for a seed.
  std::vector<SurfacePoint> SampleSurfacePoints(double spacing,
                                                const Eigen::AlignedBox2d& ground_region,
                                                uint64_t seed) const;

  const SceneModelOptions& Options() const { return options_; }
  // Number of temples in all rows.
  int NumTemples() const { return options_.num_temples * options_.num_rows; }
  // Centre of temple k at ground level: k % num_temples along its row, row k / num_temples.
  Eigen::Vector3d TempleCenter(int temple_idx) const;
  // Height of the ridge of the roof.
  static constexpr double kTempleHeight = 7.4;
  // Box of everything but the ground.
  const Eigen::AlignedBox3d& Bounds() const { return bounds_; }
  // Radius of the ground disc around the row of temples; beyond it is sky.
  double GroundRadius() const { return ground_radius_; }
  size_t NumPrimitives() const { return primitives_.size(); }

 private:
  enum class Shape : uint8_t { kBox, kCylinder, kTriangle };
  struct Primitive {
    Shape shape = Shape::kBox;
    Material material = Material::kStone;
    uint32_t texture_seed = 0;
    // Bounds (the box itself for kBox).
    Eigen::AlignedBox3d box;
    // kCylinder: vertical axis through (center.x, center.y) from box.min.z to box.max.z.
    Eigen::Vector2d center = Eigen::Vector2d::Zero();
    double radius = 0.0;
    // kBox and kTriangle: where texture coordinates are 0 (a copy of a box looks the same).
    Eigen::Vector3d uv_origin = Eigen::Vector3d::Zero();
    // kTriangle: vertex, edges, unit normal and texture axes (unit, in the plane).
    Eigen::Vector3d vertex = Eigen::Vector3d::Zero();
    Eigen::Vector3d edge1 = Eigen::Vector3d::Zero(), edge2 = Eigen::Vector3d::Zero();
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    Eigen::Vector3d axis_u = Eigen::Vector3d::Zero(), axis_v = Eigen::Vector3d::Zero();
  };
  // A bounding volume hierarchy node: an inner node has two children, a leaf a range.
  struct Node {
    Eigen::AlignedBox3d box;
    int left = -1, right = -1;
    int first = 0, count = 0;
  };

  void AddTemple(int temple_idx);
  void AddTown();
  // Whether town block (bx, by) is a field rather than built on.
  bool IsFieldBlock(int bx, int by) const;
  Eigen::Vector3f TownGroundAlbedo(const SurfaceHit& hit, float footprint) const;
  // Texture coordinates are those of the point less `uv_origin`.
  void AddBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max, Material material,
              const Eigen::Vector3d& uv_origin = Eigen::Vector3d::Zero());
  void AddCylinder(const Eigen::Vector2d& center, double radius, double z_min, double z_max,
                   Material material);
  // Texture u runs along `u_direction` projected into the triangle's plane, from
  // `uv_origin`. A fixed `texture_seed` (instead of a fresh one) repeats a texture.
  void AddTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                   const Eigen::Vector3d& u_direction, Material material,
                   const Eigen::Vector3d& uv_origin = Eigen::Vector3d::Zero(),
                   std::optional<uint32_t> texture_seed = std::nullopt);
  int BuildNode(int first, int count);
  // Distance to the primitive (or +inf); fills the hit when not null and nearer.
  bool IntersectPrimitive(const Primitive& primitive, const Eigen::Vector3d& origin,
                          const Eigen::Vector3d& direction, const Eigen::Vector3d& inv_direction,
                          double max_distance, SurfaceHit* hit) const;
  template <bool kAnyHit>
  bool Traverse(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                double max_distance, SurfaceHit* hit) const;

  SceneModelOptions options_;
  std::vector<Primitive> primitives_;
  std::vector<Node> nodes_;
  Eigen::AlignedBox3d bounds_;
  double ground_radius_ = 0.0;
  uint32_t next_texture_seed_ = 0;
  // next_texture_seed_ before the first temple: identical temples all start from it.
  uint32_t first_texture_seed_ = 0;
  // Fixed at construction (unlike next_texture_seed_): where the town's fields and houses are.
  uint32_t layout_seed_ = 0;
};

}  // namespace parallax
