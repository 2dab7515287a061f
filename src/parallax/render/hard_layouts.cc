#include "parallax/render/hard_layouts.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "parallax/geometry/look_at.h"
#include "parallax/render/synthetic_scene.h"

namespace parallax {
namespace {

constexpr double kDegrees = std::numbers::pi / 180.0;
// Orbits as the ring's: radius at the default focal length, height as a share of it, and the
// height looked at.
constexpr double kOrbitRadius = 21.0;
constexpr double kOrbitElevation = 0.45;
constexpr double kTargetHeight = 3.0;
// kWeak: the arcs stop this far (degrees of azimuth) from the far side of their temple.
constexpr double kWeakArcHalfSpan = 120.0;

double Zoom(const SyntheticSceneOptions& options) {
  return options.EffectiveFocalLength() / (0.9 * options.width);
}

// A camera looking from `center` at `target`, jittered as the ring's views are.
Rigid3d JitteredLookAt(Eigen::Vector3d center, Eigen::Vector3d target, double zoom,
                       std::mt19937_64* engine) {
  const auto jitter = [engine](double stddev) {
    return std::normal_distribution<double>(0.0, stddev)(*engine);
  };
  center += Eigen::Vector3d(jitter(0.3), jitter(0.3), jitter(0.2)) * zoom;
  target += Eigen::Vector3d(jitter(0.3), jitter(0.3), jitter(0.2));
  return LookAt(center, target);
}

// A view on the orbit around `temple` at `azimuth` (radians).
Rigid3d OrbitView(const Eigen::Vector3d& temple, double azimuth, double zoom,
                  std::mt19937_64* engine) {
  const double radius = kOrbitRadius * zoom;
  const Eigen::Vector3d center =
      temple + Eigen::Vector3d(radius * std::cos(azimuth), radius * std::sin(azimuth),
                               kOrbitElevation * radius);
  return JitteredLookAt(center, temple + Eigen::Vector3d(0, 0, kTargetHeight), zoom, engine);
}

}  // namespace

SceneModelOptions StreetSceneOptions(const SyntheticSceneOptions& options) {
  SceneModelOptions scene_options;
  scene_options.seed = options.seed;
  scene_options.num_rows = 2;
  scene_options.row_spacing = kStreetRowSpacing;
  const double street_end = kStreetStart + (options.num_views - 1) * kStreetStep + kStreetLookahead;
  scene_options.num_temples =
      1 + static_cast<int>(std::ceil(street_end / scene_options.temple_spacing));
  return scene_options;
}

SceneModelOptions TwinSceneOptions(const SyntheticSceneOptions& options) {
  SceneModelOptions scene_options;
  scene_options.seed = options.seed;
  scene_options.num_temples = 2;
  scene_options.temple_spacing = kTwinSpacing;
  scene_options.identical_temples = true;
  return scene_options;
}

SceneModelOptions WeakSceneOptions(const SyntheticSceneOptions& options) {
  SceneModelOptions scene_options;
  scene_options.seed = options.seed;
  scene_options.num_temples = 2;
  scene_options.temple_spacing = kWeakSpacing;
  return scene_options;
}

int WeakBridgeViewCount(int num_views) {
  return std::clamp(static_cast<int>(std::lround(num_views / 10.0)), 2, 4);
}

std::vector<Rigid3d> StreetWalkPoses(const SyntheticSceneOptions& options,
                                     std::mt19937_64* engine) {
  const auto jitter = [engine](double stddev) {
    return std::normal_distribution<double>(0.0, stddev)(*engine);
  };
  const double phase = std::uniform_real_distribution<double>(0.0, 2.0 * std::numbers::pi)(*engine);
  std::vector<Rigid3d> poses;
  for (int i = 0; i < options.num_views; ++i) {
    // The body sways sideways with each step (a period of two steps) and the gaze wanders.
    const double sway = 0.12 * std::sin(std::numbers::pi * i + phase);
    const Eigen::Vector3d center(kStreetStart + i * kStreetStep + jitter(0.08),
                                 0.5 * kStreetRowSpacing + sway + jitter(0.05),
                                 kStreetEyeHeight + jitter(0.04));
    const double yaw =
        (3.0 * std::sin(phase + 2.0 * std::numbers::pi * i / 11.0) + jitter(1.0)) * kDegrees;
    const double pitch = (-6.0 + jitter(1.0)) * kDegrees;
    const double roll = jitter(1.0) * kDegrees;
    const Eigen::Vector3d forward(std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw),
                                  std::sin(pitch));
    const Rigid3d roll_in_cam(Eigen::Quaterniond(Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ())),
                              Eigen::Vector3d::Zero());
    poses.push_back(roll_in_cam * LookAt(center, center + forward));
  }
  return poses;
}

std::vector<Rigid3d> TwinOrbitPoses(const SyntheticSceneOptions& options, std::mt19937_64* engine) {
  const double zoom = Zoom(options);
  const double radius = kOrbitRadius * zoom, spacing = kTwinSpacing;
  const double perimeter = 2.0 * spacing + 2.0 * std::numbers::pi * radius;
  const double phase = std::uniform_real_distribution<double>(0.0, perimeter)(*engine);
  std::vector<Rigid3d> poses;
  for (int i = 0; i < options.num_views; ++i) {
    // Arc length from (0, -radius): the straight side to temple 1, its half circle, the other
    // straight side back, temple 0's half circle.
    double s = std::fmod(phase + perimeter * i / options.num_views, perimeter);
    Eigen::Vector2d xy;
    const double half_circle = std::numbers::pi * radius;
    if (s < spacing) {
      xy = Eigen::Vector2d(s, -radius);
    } else if ((s -= spacing) < half_circle) {
      const double angle = -0.5 * std::numbers::pi + s / radius;
      xy = Eigen::Vector2d(spacing + radius * std::cos(angle), radius * std::sin(angle));
    } else if ((s -= half_circle) < spacing) {
      xy = Eigen::Vector2d(spacing - s, radius);
    } else {
      s -= spacing;
      const double angle = 0.5 * std::numbers::pi + s / radius;
      xy = Eigen::Vector2d(radius * std::cos(angle), radius * std::sin(angle));
    }
    const Eigen::Vector3d center(xy.x(), xy.y(), kOrbitElevation * radius);
    const Eigen::Vector3d target(std::clamp(xy.x(), 0.0, spacing), 0.0, kTargetHeight);
    poses.push_back(JitteredLookAt(center, target, zoom, engine));
  }
  return poses;
}

std::vector<Rigid3d> WeakLinkPoses(const SyntheticSceneOptions& options, std::mt19937_64* engine) {
  const double zoom = Zoom(options);
  const int num_bridge = WeakBridgeViewCount(options.num_views);
  const int num_arc0 = (options.num_views - num_bridge + 1) / 2;
  const int num_arc1 = options.num_views - num_bridge - num_arc0;
  const Eigen::Vector3d temple0 = Eigen::Vector3d::Zero(), temple1(kWeakSpacing, 0.0, 0.0);
  const double span = 2.0 * kWeakArcHalfSpan * kDegrees;
  std::vector<Rigid3d> poses;
  // Temple 0 from azimuth +120 degrees through 0 (facing temple 1) to -120 degrees.
  for (int i = 0; i < num_arc0; ++i) {
    const double azimuth = kWeakArcHalfSpan * kDegrees - span * i / std::max(1, num_arc0 - 1);
    poses.push_back(OrbitView(temple0, azimuth, zoom, engine));
  }
  // From the side (y < 0), far enough that both temples are in view; a few metres apart.
  const double middle = 0.5 * kWeakSpacing;
  for (int j = 0; j < num_bridge; ++j) {
    const double offset = 5.0 * (j - 0.5 * (num_bridge - 1));
    const Eigen::Vector3d center(middle + offset, -kWeakBridgeDistance * zoom,
                                 kOrbitElevation * kOrbitRadius * zoom + 2.0);
    poses.push_back(
        JitteredLookAt(center, Eigen::Vector3d(middle + 0.4 * offset, 0.0, 2.0), zoom, engine));
  }
  // Temple 1 from azimuth -60 degrees through 180 (facing temple 0) to +60 degrees.
  for (int i = 0; i < num_arc1; ++i) {
    const double azimuth =
        (180.0 + kWeakArcHalfSpan) * kDegrees - span * i / std::max(1, num_arc1 - 1);
    poses.push_back(OrbitView(temple1, azimuth, zoom, engine));
  }
  return poses;
}

}  // namespace parallax
