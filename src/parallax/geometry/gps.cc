#include "parallax/geometry/gps.h"

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

namespace parallax {
namespace {

constexpr double kSemiMajorAxis = 6378137.0;                          // WGS84 a, metres
constexpr double kFlattening = 1.0 / 298.257223563;                   // WGS84 f
constexpr double kEccentricity2 = kFlattening * (2.0 - kFlattening);  // e^2
constexpr double kRadians = std::numbers::pi / 180.0;

// Rows: east, north, up unit vectors at `origin`, in ECEF.
Eigen::Matrix3d EnuFromEcefRotation(const GeodeticPosition& origin) {
  const double lat = origin.latitude * kRadians, lon = origin.longitude * kRadians;
  Eigen::Matrix3d rotation;
  rotation << -std::sin(lon), std::cos(lon), 0.0,                                     //
      -std::sin(lat) * std::cos(lon), -std::sin(lat) * std::sin(lon), std::cos(lat),  //
      std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat);
  return rotation;
}

}  // namespace

Eigen::Vector3d EcefFromGeodetic(const GeodeticPosition& position) {
  const double lat = position.latitude * kRadians, lon = position.longitude * kRadians;
  const double sin_lat = std::sin(lat);
  // Radius of curvature in the prime vertical.
  const double normal_radius = kSemiMajorAxis / std::sqrt(1.0 - kEccentricity2 * sin_lat * sin_lat);
  const double horizontal = (normal_radius + position.altitude) * std::cos(lat);
  return Eigen::Vector3d(horizontal * std::cos(lon), horizontal * std::sin(lon),
                         (normal_radius * (1.0 - kEccentricity2) + position.altitude) * sin_lat);
}

GeodeticPosition GeodeticFromEcef(const Eigen::Vector3d& ecef) {
  const double horizontal = std::hypot(ecef.x(), ecef.y());
  GeodeticPosition position;
  position.longitude = std::atan2(ecef.y(), ecef.x()) / kRadians;
  // Fixed-point iteration on the latitude; five rounds converge to below 1e-12 rad.
  double lat = std::atan2(ecef.z(), horizontal * (1.0 - kEccentricity2));
  double normal_radius = kSemiMajorAxis;
  for (int iteration = 0; iteration < 5; ++iteration) {
    const double sin_lat = std::sin(lat);
    normal_radius = kSemiMajorAxis / std::sqrt(1.0 - kEccentricity2 * sin_lat * sin_lat);
    lat = std::atan2(ecef.z() + kEccentricity2 * normal_radius * sin_lat, horizontal);
  }
  position.latitude = lat / kRadians;
  // Away from the poles the horizontal form is the well-conditioned one.
  position.altitude =
      std::abs(std::cos(lat)) > 1e-6
          ? horizontal / std::cos(lat) - normal_radius
          : std::abs(ecef.z()) / std::abs(std::sin(lat)) - normal_radius * (1.0 - kEccentricity2);
  return position;
}

Eigen::Vector3d EnuFromGeodetic(const GeodeticPosition& position, const GeodeticPosition& origin) {
  return EnuFromEcefRotation(origin) * (EcefFromGeodetic(position) - EcefFromGeodetic(origin));
}

GeodeticPosition GeodeticFromEnu(const Eigen::Vector3d& enu, const GeodeticPosition& origin) {
  return GeodeticFromEcef(EcefFromGeodetic(origin) + EnuFromEcefRotation(origin).transpose() * enu);
}

}  // namespace parallax
