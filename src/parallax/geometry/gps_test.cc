#include "parallax/geometry/gps.h"

#include <gtest/gtest.h>

#include "parallax/util/eigen_matchers.h"

namespace parallax {
namespace {

using test::EigenMatrixNear;

TEST(Gps, EcefOfKnownPoints) {
  // On the equator at the prime meridian the ECEF x is the semi-major axis.
  const Eigen::Vector3d equator = EcefFromGeodetic({0.0, 0.0, 0.0});
  EXPECT_NEAR(equator.x(), 6378137.0, 1e-6);
  EXPECT_NEAR(equator.y(), 0.0, 1e-6);
  EXPECT_NEAR(equator.z(), 0.0, 1e-6);
  // At the north pole z is the semi-minor axis b = a (1 - f).
  const Eigen::Vector3d pole = EcefFromGeodetic({90.0, 0.0, 100.0});
  EXPECT_NEAR(pole.z(), 6356752.314245 + 100.0, 1e-4);
  EXPECT_NEAR(std::hypot(pole.x(), pole.y()), 0.0, 1e-6);
}

TEST(Gps, GeodeticRoundTripEverywhere) {
  for (const double latitude : {-89.9, -45.0, -0.5, 0.0, 12.3, 46.52, 89.99}) {
    for (const double longitude : {-179.0, -70.1, 0.0, 6.57, 151.2}) {
      for (const double altitude : {-400.0, 0.0, 612.25, 12000.0}) {
        const GeodeticPosition position{latitude, longitude, altitude};
        const GeodeticPosition back = GeodeticFromEcef(EcefFromGeodetic(position));
        EXPECT_NEAR(back.latitude, latitude, 1e-10);
        EXPECT_NEAR(back.longitude, longitude, 1e-10);
        EXPECT_NEAR(back.altitude, altitude, 1e-5);
      }
    }
  }
}

TEST(Gps, EnuIsMetresEastNorthUp) {
  const GeodeticPosition origin{46.5, 6.6, 400.0};
  // One arc second of latitude is about 30.9 m at 46.5 degrees (meridian radius of curvature).
  const Eigen::Vector3d north = EnuFromGeodetic({46.5 + 1.0 / 3600.0, 6.6, 400.0}, origin);
  EXPECT_NEAR(north.x(), 0.0, 1e-6);
  EXPECT_NEAR(north.y(), 30.88, 0.02);
  EXPECT_NEAR(north.z(), 0.0, 1e-3);  // The Earth's curvature over 31 m: 0.07 mm.
  const Eigen::Vector3d east = EnuFromGeodetic({46.5, 6.6 + 1.0 / 3600.0, 400.0}, origin);
  EXPECT_GT(east.x(), 21.2);  // cos(46.5) * 30.92 m
  EXPECT_LT(east.x(), 21.4);
  EXPECT_NEAR(EnuFromGeodetic({46.5, 6.6, 450.0}, origin).z(), 50.0, 1e-6);
  const Eigen::Vector3d enu(123.4, -567.8, 42.0);
  EXPECT_THAT(EnuFromGeodetic(GeodeticFromEnu(enu, origin), origin), EigenMatrixNear(enu, 1e-6));
}

}  // namespace
}  // namespace parallax
