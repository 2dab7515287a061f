#include "parallax/geometry/essential_matrix.h"

#include <Eigen/Dense>
#include <array>
#include <limits>

#include "parallax/geometry/triangulation.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

Eigen::Matrix3d CrossProductMatrix(const Eigen::Vector3d& v) {
  Eigen::Matrix3d matrix;
  matrix << 0, -v(2), v(1), v(2), 0, -v(0), -v(1), v(0), 0;
  return matrix;
}

// Points farther than this many baselines are too close to infinity to vote for a pose: their
// depth sign flips with noise.
constexpr double kMaxDepthInBaselines = 1000.0;

}  // namespace

Eigen::Matrix3d EssentialFromFundamental(const Eigen::Matrix3d& F, const Eigen::Matrix3d& K1,
                                         const Eigen::Matrix3d& K2) {
  return K2.transpose() * F * K1;
}

Eigen::Matrix3d FundamentalFromEssential(const Eigen::Matrix3d& E, const Eigen::Matrix3d& K1,
                                         const Eigen::Matrix3d& K2) {
  return K2.transpose().inverse() * E * K1.inverse();
}

Eigen::Matrix3d EssentialFromPose(const Rigid3d& cam2_from_cam1) {
  return CrossProductMatrix(cam2_from_cam1.translation) *
         cam2_from_cam1.rotation.toRotationMatrix();
}

void DecomposeEssentialMatrix(const Eigen::Matrix3d& E, Eigen::Matrix3d* R1, Eigen::Matrix3d* R2,
                              Eigen::Vector3d* t) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(E, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d U = svd.matrixU();
  Eigen::Matrix3d V = svd.matrixV();
  // E is defined up to sign, so U and V may be flipped freely to make both proper rotations.
  if (U.determinant() < 0) U = -U;
  if (V.determinant() < 0) V = -V;
  Eigen::Matrix3d W;
  W << 0, 1, 0, -1, 0, 0, 0, 0, 1;
  *R1 = U * W * V.transpose();
  *R2 = U * W.transpose() * V.transpose();
  *t = U.col(2).normalized();
}

int ChoosePoseByCheirality(const std::vector<Eigen::Matrix3d>& rotations,
                           const std::vector<Eigen::Vector3d>& translations,
                           const std::vector<Eigen::Vector2d>& points1,
                           const std::vector<Eigen::Vector2d>& points2,
                           std::vector<Eigen::Vector3d>* points3D) {
  PARALLAX_CHECK_EQ(rotations.size(), translations.size());
  PARALLAX_CHECK_EQ(points1.size(), points2.size());
  if (points3D != nullptr) points3D->clear();
  // The point triangulated with (R, -t) is -X when (R, t) gives X (the t column of the linear
  // system flips sign), so one triangulation per rotation serves both signs of t.
  const Matrix3x4d cam1_from_cam1 = Matrix3x4d::Identity();
  const auto in_front = [](double depth1, double depth2) {
    return depth1 > std::numeric_limits<double>::epsilon() && depth1 < kMaxDepthInBaselines &&
           depth2 > std::numeric_limits<double>::epsilon() && depth2 < kMaxDepthInBaselines;
  };
  std::vector<std::vector<Eigen::Vector3d>> candidate_points(2 * rotations.size());
  for (size_t c = 0; c < rotations.size(); ++c) {
    if (!rotations[c].allFinite() || !translations[c].allFinite()) continue;
    Matrix3x4d cam2_from_cam1_matrix;
    cam2_from_cam1_matrix << rotations[c], translations[c];
    for (size_t i = 0; i < points1.size(); ++i) {
      const std::optional<Eigen::Vector3d> point3D =
          TriangulatePoint(cam1_from_cam1, cam2_from_cam1_matrix, points1[i], points2[i]);
      if (!point3D) continue;
      const double depth1 = (*point3D)(2);
      const double depth2 = cam2_from_cam1_matrix.row(2).dot(point3D->homogeneous());
      if (in_front(depth1, depth2)) {
        candidate_points[2 * c].push_back(*point3D);
      } else if (in_front(-depth1, -depth2)) {
        candidate_points[2 * c + 1].push_back(-*point3D);
      }
    }
  }
  int best = -1;
  for (size_t candidate = 0; candidate < candidate_points.size(); ++candidate) {
    if (candidate_points[candidate].empty()) continue;
    if (best < 0 || candidate_points[candidate].size() > candidate_points[best].size()) {
      best = static_cast<int>(candidate);
    }
  }
  if (best >= 0 && points3D != nullptr) points3D->swap(candidate_points[best]);
  return best;
}

bool PoseFromEssentialMatrix(const Eigen::Matrix3d& E, const std::vector<Eigen::Vector2d>& points1,
                             const std::vector<Eigen::Vector2d>& points2, Rigid3d* cam2_from_cam1,
                             std::vector<Eigen::Vector3d>* points3D) {
  if (points3D != nullptr) points3D->clear();
  if (points1.size() != points2.size() || points1.empty() || !E.allFinite()) return false;
  Eigen::Matrix3d R1, R2;
  Eigen::Vector3d t;
  DecomposeEssentialMatrix(E, &R1, &R2, &t);
  if (!R1.allFinite() || !R2.allFinite() || !t.allFinite()) return false;
  const std::vector<Eigen::Matrix3d> rotations = {R1, R2};
  const int best = ChoosePoseByCheirality(rotations, {t, t}, points1, points2, points3D);
  if (best < 0) return false;
  *cam2_from_cam1 = Rigid3d(Eigen::Quaterniond(rotations[best / 2]).normalized(),
                            best % 2 == 0 ? t : Eigen::Vector3d(-t));
  return true;
}

}  // namespace parallax
