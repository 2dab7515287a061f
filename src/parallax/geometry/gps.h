#pragma once

#include <Eigen/Core>

namespace parallax {

// A position on the WGS84 ellipsoid, as GPS receivers and EXIF give it.
struct GeodeticPosition {
  double latitude = 0.0;   // degrees, north positive
  double longitude = 0.0;  // degrees, east positive
  double altitude = 0.0;   // metres above the ellipsoid
};

// Earth-centred, earth-fixed metres of a geodetic position (WGS84).
Eigen::Vector3d EcefFromGeodetic(const GeodeticPosition& position);
// The inverse, to well under a millimetre anywhere near the Earth's surface.
GeodeticPosition GeodeticFromEcef(const Eigen::Vector3d& ecef);

// Local east, north, up metres of `position` in the tangent frame at `origin`: the frame in
// which GPS-tagged views are compared (distances in metres, up is up).
Eigen::Vector3d EnuFromGeodetic(const GeodeticPosition& position, const GeodeticPosition& origin);
// The inverse of EnuFromGeodetic.
GeodeticPosition GeodeticFromEnu(const Eigen::Vector3d& enu, const GeodeticPosition& origin);

}  // namespace parallax
