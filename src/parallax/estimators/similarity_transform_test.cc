#include "parallax/estimators/similarity_transform.h"

#include <gtest/gtest.h>

#include "parallax/util/eigen_matchers.h"

#include <limits>

#include "parallax/math/random.h"

namespace parallax {
namespace {

using test::EigenMatrixNear;

Sim3d RandomSim3d() {
  const Eigen::Vector3d axis(RandomUniformReal(-1, 1), RandomUniformReal(-1, 1),
                             RandomUniformReal(-1, 1));
  return Sim3d(RandomUniformReal(0.2, 5),
               Eigen::Quaterniond(Eigen::AngleAxisd(RandomUniformReal(-3, 3), axis.normalized())),
               Eigen::Vector3d(RandomUniformReal(-10, 10), RandomUniformReal(-10, 10),
                               RandomUniformReal(-10, 10)));
}

Eigen::Vector3d RandomPoint(double extent) {
  return Eigen::Vector3d(RandomUniformReal(-extent, extent), RandomUniformReal(-extent, extent),
                         RandomUniformReal(-extent, extent));
}

TEST(EstimateSim3dRansac, ExactCorrespondences) {
  const Sim3d truth = RandomSim3d();
  std::vector<Eigen::Vector3d> src, dst;
  for (int i = 0; i < 20; ++i) {
    src.push_back(RandomPoint(5));
    dst.push_back(truth * src.back());
  }
  const Sim3dRansacReport report = EstimateSim3dRansac(src, dst, Sim3dRansacOptions(0.01));
  ASSERT_TRUE(report.success);
  EXPECT_EQ(report.num_inliers, 20u);
  EXPECT_NEAR(report.dst_from_src.scale, truth.scale, 1e-8 * truth.scale);
  EXPECT_LT(report.dst_from_src.rotation.angularDistance(truth.rotation), 1e-8);
  EXPECT_THAT(report.dst_from_src.translation, EigenMatrixNear(truth.translation, 1e-8 * 10));
}

TEST(EstimateSim3dRansac, OneWildlyWrongCorrespondenceAmongTwenty) {
  for (int trial = 0; trial < 20; ++trial) {
    const Sim3d truth = RandomSim3d();
    std::vector<Eigen::Vector3d> src, dst;
    for (int i = 0; i < 20; ++i) {
      src.push_back(RandomPoint(5));
      dst.push_back(truth * src.back() + 1e-3 * RandomPoint(1));
    }
    const int bad = trial % 20;
    dst[bad] += Eigen::Vector3d(1000, -500, 300);  // A camera placed far off.
    const Sim3dRansacReport report = EstimateSim3dRansac(src, dst, Sim3dRansacOptions(0.05));
    ASSERT_TRUE(report.success);
    EXPECT_EQ(report.num_inliers, 19u);
    ASSERT_EQ(report.inlier_mask.size(), 20u);
    EXPECT_FALSE(report.inlier_mask[bad]);
    EXPECT_NEAR(report.dst_from_src.scale, truth.scale, 1e-3 * truth.scale);
    EXPECT_LT(report.dst_from_src.rotation.angularDistance(truth.rotation), 1e-3);
    EXPECT_THAT(report.dst_from_src.translation, EigenMatrixNear(truth.translation, 1e-2));
  }
}

TEST(EstimateSim3dRansac, FailsGracefullyOnDegenerateInput) {
  const Sim3d truth = RandomSim3d();
  std::vector<Eigen::Vector3d> src = {RandomPoint(1), RandomPoint(1)};
  std::vector<Eigen::Vector3d> dst = {truth * src[0], truth * src[1]};
  EXPECT_FALSE(EstimateSim3dRansac(src, dst, Sim3dRansacOptions(0.1)).success);
  EXPECT_FALSE(EstimateSim3dRansac({}, {}, Sim3dRansacOptions(0.1)).success);

  // Collinear points.
  src.clear();
  dst.clear();
  for (int i = 0; i < 10; ++i) {
    src.push_back(Eigen::Vector3d(i, 2 * i, -i));
    dst.push_back(truth * src.back());
  }
  EXPECT_FALSE(EstimateSim3dRansac(src, dst, Sim3dRansacOptions(0.1)).success);

  // NaN entries are outliers; the rest still determine the similarity.
  src.clear();
  dst.clear();
  for (int i = 0; i < 15; ++i) {
    src.push_back(RandomPoint(5));
    dst.push_back(truth * src.back());
  }
  src[2].x() = std::numeric_limits<double>::quiet_NaN();
  dst[5].z() = std::numeric_limits<double>::infinity();
  const Sim3dRansacReport report = EstimateSim3dRansac(src, dst, Sim3dRansacOptions(0.01));
  ASSERT_TRUE(report.success);
  EXPECT_EQ(report.num_inliers, 13u);
  EXPECT_NEAR(report.dst_from_src.scale, truth.scale, 1e-8 * truth.scale);
}

}  // namespace
}  // namespace parallax
