#include "parallax/geometry/similarity.h"

#include <gtest/gtest.h>

#include "parallax/util/eigen_matchers.h"

#include <limits>

#include "parallax/math/random.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

using test::Sim3dNear;

Sim3d RandomSim3d() {
  const Eigen::Vector3d axis(RandomUniformReal(-1, 1), RandomUniformReal(-1, 1),
                             RandomUniformReal(-1, 1));
  return Sim3d(RandomUniformReal(0.1, 10),
               Eigen::Quaterniond(Eigen::AngleAxisd(RandomUniformReal(-3, 3), axis.normalized())),
               Eigen::Vector3d(RandomUniformReal(-100, 100), RandomUniformReal(-100, 100),
                               RandomUniformReal(-100, 100)));
}

std::vector<Eigen::Vector3d> RandomPoints(size_t num_points) {
  std::vector<Eigen::Vector3d> points(num_points);
  for (auto& point : points) {
    point = Eigen::Vector3d(RandomUniformReal(-5, 5), RandomUniformReal(-5, 5),
                            RandomUniformReal(-5, 5));
  }
  return points;
}

TEST(EstimateSim3d, RecoversExactSimilarity) {
  for (int trial = 0; trial < 50; ++trial) {
    const Sim3d truth = RandomSim3d();
    const size_t num_points = 3 + trial % 10;
    const std::vector<Eigen::Vector3d> src = RandomPoints(num_points);
    std::vector<Eigen::Vector3d> dst;
    for (const auto& point : src) dst.push_back(truth * point);
    const std::optional<Sim3d> estimate = EstimateSim3d(src, dst);
    ASSERT_TRUE(estimate.has_value());
    EXPECT_THAT(*estimate, Sim3dNear(truth, 1e-8));
  }
}

TEST(EstimateSim3d, RecoversExactSimilarityOfPlanarPoints) {
  const Sim3d truth = RandomSim3d();
  std::vector<Eigen::Vector3d> src = RandomPoints(10);
  for (auto& point : src) point.z() = 2.0;  // Coplanar is fine, collinear is not.
  std::vector<Eigen::Vector3d> dst;
  for (const auto& point : src) dst.push_back(truth * point);
  const std::optional<Sim3d> estimate = EstimateSim3d(src, dst);
  ASSERT_TRUE(estimate.has_value());
  EXPECT_THAT(*estimate, Sim3dNear(truth, 1e-8));
}

TEST(EstimateSim3d, NoisyPointsGiveCloseSimilarity) {
  const Sim3d truth = RandomSim3d();
  const std::vector<Eigen::Vector3d> src = RandomPoints(200);
  std::vector<Eigen::Vector3d> dst;
  for (const auto& point : src) {
    dst.push_back(truth * point + Eigen::Vector3d(RandomGaussian(0, 0.01), RandomGaussian(0, 0.01),
                                                  RandomGaussian(0, 0.01)));
  }
  const std::optional<Sim3d> estimate = EstimateSim3d(src, dst);
  ASSERT_TRUE(estimate.has_value());
  EXPECT_NEAR(estimate->scale, truth.scale, 1e-2 * truth.scale);
  EXPECT_LT(estimate->rotation.angularDistance(truth.rotation), 1e-2);
  double squared_error = 0;
  for (size_t i = 0; i < src.size(); ++i)
    squared_error += (*estimate * src[i] - dst[i]).squaredNorm();
  // Least squares: never worse than the truth on its own data.
  double truth_squared_error = 0;
  for (size_t i = 0; i < src.size(); ++i)
    truth_squared_error += (truth * src[i] - dst[i]).squaredNorm();
  EXPECT_LE(squared_error, truth_squared_error);
}

TEST(EstimateSim3d, RefusesDegenerateInput) {
  const Sim3d truth = RandomSim3d();
  // Too few points.
  std::vector<Eigen::Vector3d> src = RandomPoints(2);
  std::vector<Eigen::Vector3d> dst = {truth * src[0], truth * src[1]};
  EXPECT_FALSE(EstimateSim3d(src, dst).has_value());
  EXPECT_FALSE(EstimateSim3d({}, {}).has_value());

  // Collinear points.
  src.clear();
  dst.clear();
  for (int i = 0; i < 10; ++i) {
    src.push_back(Eigen::Vector3d(1, 2, 3) + i * Eigen::Vector3d(0.3, -0.2, 0.5));
    dst.push_back(truth * src.back());
  }
  EXPECT_FALSE(EstimateSim3d(src, dst).has_value());

  // All destination points equal: zero scale.
  src = RandomPoints(10);
  dst.assign(10, Eigen::Vector3d(1, 2, 3));
  EXPECT_FALSE(EstimateSim3d(src, dst).has_value());

  // Non-finite coordinates.
  src = RandomPoints(10);
  dst.clear();
  for (const auto& point : src) dst.push_back(truth * point);
  dst[3].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(EstimateSim3d(src, dst).has_value());
  dst[3].y() = 0;
  src[7].x() = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(EstimateSim3d(src, dst).has_value());

  // Mismatched sizes are a programming error.
  src = RandomPoints(5);
  dst = RandomPoints(4);
  EXPECT_THROW(EstimateSim3d(src, dst), CheckError);
}

}  // namespace
}  // namespace parallax
