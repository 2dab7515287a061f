#include "parallax/render/covisibility.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <unordered_map>

#include "parallax/util/check.h"
#include "parallax/util/threading.h"

namespace parallax {
namespace {

// Points bucketed on a square grid in x, y, for the points a view's footprint covers.
class PointGrid {
 public:
  PointGrid(const std::vector<Eigen::Vector3d>& points, double cell_size) : cell_size_(cell_size) {
    for (size_t i = 0; i < points.size(); ++i)
      cells_[Key(Cell(points[i].x()), Cell(points[i].y()))].push_back(i);
  }
  template <typename Visit>
  void ForEachIn(const Eigen::AlignedBox2d& box, Visit&& visit) const {
    for (int64_t cx = Cell(box.min().x()); cx <= Cell(box.max().x()); ++cx) {
      for (int64_t cy = Cell(box.min().y()); cy <= Cell(box.max().y()); ++cy) {
        const auto it = cells_.find(Key(cx, cy));
        if (it == cells_.end()) continue;
        for (const size_t index : it->second) visit(index);
      }
    }
  }

 private:
  int64_t Cell(double coordinate) const {
    return static_cast<int64_t>(std::floor(coordinate / cell_size_));
  }
  static uint64_t Key(int64_t cx, int64_t cy) {
    return (static_cast<uint64_t>(cx) << 32) ^ static_cast<uint64_t>(cy & 0xFFFFFFFF);
  }
  double cell_size_;
  std::unordered_map<uint64_t, std::vector<size_t>> cells_;
};

// The part of the ground plane and of the scene up to `top` that a view can see, in x, y:
// its image corners cast onto z = 0 and z = top, or `max_distance` along rays that miss.
Eigen::AlignedBox2d ViewFootprint(const Camera& camera, const Rigid3d& cam_from_world, double top,
                                  double max_distance) {
  const Eigen::Vector3d center = ProjectionCenter(cam_from_world);
  const Eigen::Matrix3d world_from_cam = cam_from_world.rotation.toRotationMatrix().transpose();
  Eigen::AlignedBox2d box(center.head<2>(), center.head<2>());
  for (const double x : {0.0, static_cast<double>(camera.width)}) {
    for (const double y : {0.0, static_cast<double>(camera.height)}) {
      const Eigen::Vector3d ray =
          (world_from_cam * camera.CamFromImg(Eigen::Vector2d(x, y)).homogeneous()).normalized();
      for (const double z : {0.0, top}) {
        double t = max_distance;
        if (ray.z() * (z - center.z()) > 0.0) t = std::min(t, (z - center.z()) / ray.z());
        box.extend((center + t * ray).head<2>());
      }
    }
  }
  return box;
}

}  // namespace

void CovisibilityOptions::Check() const {
  PARALLAX_CHECK_GT(point_spacing, 0.0);
  PARALLAX_CHECK_GT(max_incidence_degrees, 0.0);
  PARALLAX_CHECK_LE(max_incidence_degrees, 90.0);
  PARALLAX_CHECK_GE(min_shared_points, 1);
  PARALLAX_CHECK_GT(max_distance, 0.0);
}

std::vector<CovisiblePair> ComputeCovisiblePairs(const SceneModel& scene,
                                                 const Reconstruction& views,
                                                 const CovisibilityOptions& options) {
  options.Check();
  const std::vector<image_t> image_ids = views.RegImageIds();
  const double top = std::max(scene.Bounds().isEmpty() ? 0.0 : scene.Bounds().max().z(), 1.0);
  std::vector<Eigen::AlignedBox2d> footprints(image_ids.size());
  Eigen::AlignedBox2d ground_region;
  ground_region.setEmpty();
  for (size_t i = 0; i < image_ids.size(); ++i) {
    const Image& image = views.GetImage(image_ids[i]);
    footprints[i] = ViewFootprint(views.GetCamera(image.camera_id), image.cam_from_world, top,
                                  options.max_distance);
    ground_region.extend(footprints[i]);
  }
  const std::vector<SurfacePoint> samples =
      scene.SampleSurfacePoints(options.point_spacing, ground_region, options.seed);
  std::vector<Eigen::Vector3d> points(samples.size());
  for (size_t i = 0; i < samples.size(); ++i) points[i] = samples[i].position;
  const PointGrid grid(points, 8.0);
  const double min_cosine = std::cos(options.max_incidence_degrees * std::numbers::pi / 180.0);

  // The points each view sees, in increasing index order.
  std::vector<std::vector<uint32_t>> seen(image_ids.size());
  ParallelFor(0, image_ids.size(), options.num_threads, [&](size_t i) {
    const Image& image = views.GetImage(image_ids[i]);
    const Camera& camera = views.GetCamera(image.camera_id);
    const Eigen::Vector3d center = ProjectionCenter(image.cam_from_world);
    grid.ForEachIn(footprints[i], [&](size_t index) {
      const Eigen::Vector3d& point = points[index];
      const Eigen::Vector3d point_in_cam = image.cam_from_world * point;
      if (point_in_cam.z() <= 0.0) return;
      const double distance = (point - center).norm();
      if (distance > options.max_distance) return;
      if (std::abs(samples[index].normal.dot(point - center)) < min_cosine * distance) return;
      const Eigen::Vector2d xy = camera.ImgFromCam(point_in_cam);
      if (xy.x() < 0.0 || xy.y() < 0.0 || xy.x() >= camera.width || xy.y() >= camera.height) return;
      // Stop a little short of the point: its own surface must not count as blocking it.
      if (scene.Occluded(center, (point - center) / distance, distance * (1.0 - 1e-6) - 0.01))
        return;
      seen[i].push_back(static_cast<uint32_t>(index));
    });
    std::sort(seen[i].begin(), seen[i].end());
  });

  std::vector<std::vector<uint32_t>> seen_by(points.size());
  for (size_t i = 0; i < image_ids.size(); ++i) {
    for (const uint32_t index : seen[i]) seen_by[index].push_back(static_cast<uint32_t>(i));
  }
  std::unordered_map<uint64_t, int> shared;
  for (const std::vector<uint32_t>& observers : seen_by) {
    for (size_t a = 0; a < observers.size(); ++a) {
      for (size_t b = a + 1; b < observers.size(); ++b) {
        ++shared[(static_cast<uint64_t>(observers[a]) << 32) | observers[b]];
      }
    }
  }
  std::vector<CovisiblePair> pairs;
  for (const auto& [key, count] : shared) {
    if (count < options.min_shared_points) continue;
    image_t id1 = image_ids[key >> 32], id2 = image_ids[key & 0xFFFFFFFF];
    if (id1 > id2) std::swap(id1, id2);
    pairs.push_back({id1, id2, count});
  }
  std::sort(pairs.begin(), pairs.end(), [](const CovisiblePair& a, const CovisiblePair& b) {
    return std::make_pair(a.image_id1, a.image_id2) < std::make_pair(b.image_id1, b.image_id2);
  });
  return pairs;
}

}  // namespace parallax
